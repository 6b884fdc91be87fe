//! The methods for an operator that is not a socket connection (the Foxglove station,
//! `station::Operator`): each call runs on the socket's runtime exactly as an
//! authorised connection's request would (the same checks, the navigator stopping
//! before a driving request, the loop's queue and ack).

use std::sync::Arc;

use serde_json::Value;
use tokio::sync::{mpsc, watch};

use super::api::Params;
use super::methods;
use super::session::Session;
use super::shared::Shared;
use crate::station::{CallError, CallFuture, NOT_READY, Operator};

/// Methods an operator from elsewhere may not call: they belong to a connection.
const CONNECTION_ONLY: [&str; 3] = ["auth", "telemetry.subscribe", "telemetry.unsubscribe"];

pub(crate) struct SocketOperator {
    shared: Arc<Shared>,
    runtime: tokio::runtime::Handle,
}

impl SocketOperator {
    pub(crate) fn new(shared: Arc<Shared>, runtime: tokio::runtime::Handle) -> Self {
        Self { shared, runtime }
    }
}

impl Operator for SocketOperator {
    fn call(&self, who: &str, method: &str, params: Value) -> CallFuture {
        let shared = self.shared.clone();
        let method = method.to_owned();
        let who = who.to_owned();
        let task = self.runtime.spawn(async move {
            if CONNECTION_ONLY.contains(&method.as_str()) {
                return Err(super::api::RpcError::new(
                    super::api::code::METHOD_NOT_FOUND,
                    format!("`{method}` belongs to a socket connection"),
                ));
            }
            let p = Params::from_value(&params)?;
            // A session of its own: authorised (the station checked), no stream, never
            // told of closing (the runtime's shutdown ends the call).
            let (out, _lines) = mpsc::channel(1);
            let (_closing_tx, closing) = watch::channel(false);
            let mut session = Session::new(out, closing, who);
            session.set_authorized(true);
            methods::dispatch(&shared, &mut session, &method, p).await
        });
        Box::pin(async move {
            match task.await {
                Ok(answer) => answer.map_err(|e| CallError {
                    code: e.code,
                    message: e.message,
                }),
                Err(_) => Err(CallError {
                    code: NOT_READY,
                    message: "the control socket stopped".into(),
                }),
            }
        })
    }

    fn claim_drive(&self, who: &str) -> Result<(), CallError> {
        self.shared
            .driver
            .claim(who, std::time::Instant::now())
            .map_err(|e| CallError {
                code: e.code,
                message: e.message,
            })
    }
}
