//! The control socket: newline-delimited JSON over a Unix socket (and optionally
//! TCP on 127.0.0.1), served by tokio, feeding the loop through a bounded channel.
//!
//! The protocol is documented in `docs/control-socket.md`. In short: one request
//! per line, `{"id": 1, "method": "status", "params": {...}}`, one answer per
//! request, `{"id": 1, "result": ...}` or `{"id": 1, "error": {"code", "message"}}`,
//! and stream messages without an id. Everything a request carries is validated
//! here, on the async side, before anything reaches the loop; requests that act
//! on the loop are sent with `try_send` (a full channel is an immediate "busy")
//! and answered when the loop acks them.
//!
//! - [`api`]: wire format, params, error codes.
//! - `server`: binding, the runtime thread, accept loops, the client limit.
//! - `shared`: what every connection shares; `session`: one connection's state
//!   (its telemetry stream).
//! - `clients`: the client table (the limit, eviction of the idlest, stops over the
//!   limit); `conn`: one connection: reading lines, answering in order, the writer.
//! - `methods`: each method: a read, or an act carried out by the operator API
//!   (`crate::operator`); `wire`: acts' params read into the API's typed requests and
//!   their answers written; `views`: JSON views of a snapshot;
//!   `controller_views`: JSON views of controllers (`controller.list/get`, any gait's
//!   controller in `status` and telemetry).
//! - [`client`]: a small blocking client (used by `snakectl` and the tests).

pub mod api;
pub mod client;
mod clients;
mod conn;
pub(crate) mod controller_views;
mod lines;
mod methods;
pub mod paths;
mod pose_method;
mod server;
mod session;
mod shared;
mod views;
mod wire;

use std::path::PathBuf;
use std::time::Duration;

pub use crate::operator::handle::{BusKind, DaemonInfo, LoopHandle, Pacing, RecordView};

pub use methods::{DEFAULT_RATE_HZ, METHODS, RATE_RANGE_HZ, call_json};
pub use server::{RunningServer, ServerError, start};
pub use wire::{act_params, answer_json, controller_set_params};

/// The system service's socket (see [`paths`] for how "auto" resolves).
pub const DEFAULT_SOCKET_PATH: &str = paths::SYSTEM_SOCKET;

/// How the server listens and what it tolerates.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// Unix stream socket path (the parent directory is created if missing).
    pub unix_path: Option<PathBuf>,
    /// TCP port on 127.0.0.1 only (0 picks a free port; see `RunningServer::tcp_addr`).
    pub tcp_port: Option<u16>,
    /// Longest request line accepted, bytes (without the newline).
    pub max_line_bytes: usize,
    /// Connections served at once; one more is told -32004 and closed.
    pub max_clients: usize,
    /// How long a request waits for the loop's ack before -32001.
    pub ack_timeout: Duration,
    /// Mode of the socket file (e.g. 0o660: owner and group may control the robot).
    pub socket_mode: u32,
    /// A connection with no request and no telemetry stream for this long is closed
    /// (`None`: never).
    pub idle_timeout: Option<Duration>,
    /// The token a TCP client must send with `auth` before any other method; required
    /// when `tcp_port` is set.
    pub tcp_token: Option<String>,
    /// A driver that sends no driving request for this long no longer holds the drive
    /// (`operator::driver`).
    pub driver_timeout: Duration,
    /// The recorder's state, `record` in `status` and `stats` (`None`: no recorder,
    /// `{"state": "off"}`).
    pub record: Option<RecordView>,
    /// Where `pose.external` fixes go (`None`: refused, no pose input).
    pub pose: Option<crate::estimation::external_pose::PoseInput>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            unix_path: Some(PathBuf::from(DEFAULT_SOCKET_PATH)),
            tcp_port: None,
            max_line_bytes: 65536,
            max_clients: 64,
            ack_timeout: Duration::from_secs(1),
            socket_mode: 0o660,
            idle_timeout: Some(Duration::from_secs(300)),
            tcp_token: None,
            driver_timeout: crate::operator::driver::DEFAULT_DRIVER_TIMEOUT,
            record: None,
            pose: None,
        }
    }
}
