//! Operator actions from Foxglove as events: one JSON message per action on the
//! `/operator` channel of the recorder's context, so the recording (file) and every
//! live viewer get it, naming the client, what it asked and what it was answered.

use std::sync::Arc;

use foxglove::{Context, RawChannel};

use crate::foxglove_json::json_channel;
use serde_json::{Value, json};

/// The channel's topic.
pub const TOPIC: &str = "/operator";

/// Writes operator actions.
#[derive(Clone)]
pub struct Actions {
    channel: Option<Arc<RawChannel>>,
}

impl Actions {
    /// On `ctx` (no channel, and nothing logged, if it cannot be made).
    pub fn new(ctx: &Arc<Context>) -> Self {
        let schema = br#"{"type":"object","properties":{"client":{"type":"string"},"action":{"type":"string"},"params":{},"ok":{"type":"boolean"},"answer":{}}}"#;
        Self {
            channel: json_channel(ctx, TOPIC, "snaked.OperatorAction", schema),
        }
    }

    /// Writes nothing (no recording).
    pub fn off() -> Self {
        Self { channel: None }
    }

    /// `client` (its name and id) did `action` with `params` and was answered `answer`.
    pub fn log(&self, client: &str, action: &str, params: &Value, answer: &Result<Value, String>) {
        let Some(ch) = &self.channel else {
            return;
        };
        let (ok, answer) = match answer {
            Ok(v) => (true, v.clone()),
            Err(e) => (false, Value::String(e.clone())),
        };
        let msg = json!({
            "client": client,
            "action": action,
            "params": params,
            "ok": ok,
            "answer": answer,
        });
        ch.log(msg.to_string().as_bytes());
    }
}
