//! The operator's station: driving and tuning the robot from Foxglove (issue 29). The
//! live view's WebSocket server (`live::server`) carries it when `[foxglove] operate`
//! is on: services for the socket's methods that change state, a teleop channel in the
//! shape Foxglove's Teleop panel publishes, with a dead-man, and who may do either.
//! It is a thin adapter over the operator API (`crate::operator`): teleop and the
//! Parameters panel hand it typed acts and read the loop's snapshot; the services take
//! the socket's methods with their JSON params through the socket's own mapping. So an
//! operator here meets the same checks, the same loop queue and the same errors as
//! `snakectl`.
//!
//! - [`access`]: which Foxglove clients may operate (the token).
//! - [`teleop`]: a twist to the gait's speed and steering, and the dead-man (pure).
//! - [`services`]: the services and what they answer.
//! - [`parameters`]: the Parameters panel.
//! - [`drive`]: the teleop channel's worker.
//! - [`actions`]: operator actions as events on the `/operator` channel (file and live).

pub mod access;
pub mod actions;
pub mod drive;
pub mod parameters;
pub mod services;
pub mod teleop;

use std::sync::{Arc, OnceLock};

use serde_json::Value;

pub use access::Access;
pub use teleop::{Steer, Teleop, TeleopConfig, Twist};

use crate::operator::{Act, Done, Operator, OperatorError, code};
use crate::rt::telemetry::Snapshot;

/// What the station needs, given to the live view: its settings and the operator API,
/// which the daemon binds once the control socket runs (calls before that are refused
/// as not ready).
#[derive(Clone)]
pub struct Station {
    pub config: StationConfig,
    operator: Arc<OnceLock<Operator>>,
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

fn not_ready() -> OperatorError {
    OperatorError::new(
        code::NOT_READY,
        "not ready: the control socket is not running yet",
    )
}

impl Station {
    pub fn new(config: StationConfig) -> Self {
        Self {
            config,
            operator: Arc::default(),
        }
    }

    /// Binds the operator API; later binds are ignored.
    pub fn bind(&self, operator: Operator) {
        let _ = self.operator.set(operator);
    }

    /// The operator API, once bound.
    pub fn operator(&self) -> Result<&Operator, OperatorError> {
        self.operator.get().ok_or_else(not_ready)
    }

    /// Carries `act` out as the client `who`.
    pub async fn act(&self, who: &str, act: Act) -> Result<Done, OperatorError> {
        self.operator()?.act(who, act).await
    }

    /// A control-socket method with its JSON params, as `who`: the services' edge
    /// (the socket's own mapping, so both answer alike).
    pub async fn call_json(
        &self,
        who: &str,
        method: &str,
        params: &Value,
    ) -> Result<Value, OperatorError> {
        crate::socket::call_json(self.operator()?, who, method, params).await
    }

    /// Whether `who` may drive now (`operator::driver`).
    pub fn claim_drive(&self, who: &str) -> Result<(), OperatorError> {
        self.operator()?.claim_drive(who)
    }

    /// The loop's latest snapshot, once bound.
    pub fn snapshot(&self) -> Option<Snapshot> {
        self.operator.get().map(Operator::snapshot)
    }
}
