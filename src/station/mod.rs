//! The operator's station: driving and tuning the robot from Foxglove (issue 29). The
//! live view's WebSocket server (`live::server`) carries it when `[foxglove] operate`
//! is on: services for the socket's methods that change state, a teleop channel in the
//! shape Foxglove's Teleop panel publishes, with a dead-man, and who may do either.
//! Everything an operator asks goes through the control socket's own methods
//! ([`Operator`], implemented by `socket::RunningServer::operator`), so it meets the
//! same checks, the same loop queue and the same errors as `snakectl`.
//!
//! - [`access`]: which Foxglove clients may operate (the token).
//! - [`teleop`]: a twist to the gait's speed and steering, and the dead-man (pure).
//! - [`services`]: the services and what they answer.
//! - [`actions`]: operator actions as events on the `/operator` channel (file and live).

pub mod access;
pub mod actions;
pub mod drive;
pub mod parameters;
pub mod services;
pub mod teleop;

use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, OnceLock};

use serde_json::Value;

pub use access::Access;
pub use teleop::{Steer, Teleop, TeleopConfig, Twist};

/// An error an operator's call answers with: the control socket's code and message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CallError {
    pub code: i64,
    pub message: String,
}

impl std::fmt::Display for CallError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "error {}: {}", self.code, self.message)
    }
}

/// What a call answers, once it has been carried out.
pub type CallFuture = Pin<Box<dyn Future<Output = Result<Value, CallError>> + Send>>;

/// Carries out a control-socket method (`method`, its `params` object) as an
/// authorised client's request, the client named `who` (the drive lease and the logs
/// name it so: one operator drives at a time, `socket::driver`).
pub trait Operator: Send + Sync {
    fn call(&self, who: &str, method: &str, params: Value) -> CallFuture;
    /// `who` is about to drive: it holds the drive or takes a free one; refused while
    /// another operator drives.
    fn claim_drive(&self, who: &str) -> Result<(), CallError>;
}

/// What the station needs, given to the live view: its settings and the operator,
/// which the daemon binds once the control socket runs (calls before that are
/// refused as "not ready").
#[derive(Clone)]
pub struct Station {
    pub config: StationConfig,
    operator: Arc<OnceLock<Arc<dyn Operator>>>,
}

impl std::fmt::Debug for Station {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Station")
            .field("config", &self.config)
            .field("bound", &self.operator.get().is_some())
            .finish()
    }
}

impl PartialEq for Station {
    fn eq(&self, other: &Self) -> bool {
        self.config == other.config && Arc::ptr_eq(&self.operator, &other.operator)
    }
}

/// The station's settings (`[foxglove]` in the daemon's configuration).
#[derive(Debug, Clone, PartialEq)]
pub struct StationConfig {
    /// The token a client must give (`auth` service) before operating; `None`: every
    /// client may (only allowed on a loopback address, checked by the daemon).
    pub token: Option<String>,
    pub teleop: TeleopConfig,
}

/// The code of a call refused for want of privilege (the socket's -32005).
pub const UNAUTHORIZED: i64 = -32005;
/// The code of a call made before the control socket runs (the socket's "refused").
pub const NOT_READY: i64 = -32002;
/// The socket's codes for a request that is not JSON, and for bad params.
pub const PARSE_ERROR: i64 = -32700;
pub const INVALID_PARAMS: i64 = -32602;

fn not_ready() -> CallError {
    CallError {
        code: NOT_READY,
        message: "not ready: the control socket is not running yet".into(),
    }
}

impl Station {
    pub fn new(config: StationConfig) -> Self {
        Self {
            config,
            operator: Arc::default(),
        }
    }

    /// Binds the operator (the control socket); later binds are ignored.
    pub fn bind(&self, operator: Arc<dyn Operator>) {
        let _ = self.operator.set(operator);
    }

    /// Carries `method` out through the bound operator, as `who`.
    pub fn call(&self, who: &str, method: &str, params: Value) -> CallFuture {
        match self.operator.get() {
            Some(op) => op.call(who, method, params),
            None => Box::pin(async { Err(not_ready()) }),
        }
    }

    /// Whether `who` may drive now (see [`Operator::claim_drive`]).
    pub fn claim_drive(&self, who: &str) -> Result<(), CallError> {
        match self.operator.get() {
            Some(op) => op.claim_drive(who),
            None => Err(not_ready()),
        }
    }
}
