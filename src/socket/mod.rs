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
//! - `methods`: each method's params read into the operator API's typed requests
//!   (`crate::operator`), and its answer written; `views`: JSON views of a snapshot;
//!   `controller_views`: JSON views of controllers (`controller.list/get`, any gait's
//!   controller in `status` and telemetry).
//! - [`client`]: a small blocking client (used by `snakectl` and the tests).

pub mod api;
pub mod client;
mod clients;
mod conn;
mod controller_views;
mod lines;
mod methods;
pub mod paths;
mod server;
mod session;
mod shared;
mod views;

use std::path::PathBuf;
use std::time::Duration;

use serde::Serialize;

use crate::controller_interface::catalog::Catalog;
use crate::gait::BodyLayout;
use crate::rt::controller_slots::Installed;
use crate::rt::messages::{Ack, Envelope};
use crate::rt::telemetry::TelemetryReader;

pub use methods::{
    DEFAULT_RATE_HZ, METHODS, RATE_RANGE_HZ, act_params, answer_json, call_json,
    controller_set_params,
};
pub use server::{RunningServer, ServerError, start};

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
        }
    }
}

/// Reads the recorder's state as JSON when `status` or `stats` asks: the daemon's
/// wiring hands it in (the socket knows nothing of the recorder).
#[derive(Clone)]
pub struct RecordView(std::sync::Arc<dyn Fn() -> serde_json::Value + Send + Sync>);

impl RecordView {
    pub fn new(read: impl Fn() -> serde_json::Value + Send + Sync + 'static) -> Self {
        Self(std::sync::Arc::new(read))
    }

    /// What `view` reads, `{"state": "off"}` without one.
    pub fn read(view: Option<&Self>) -> serde_json::Value {
        view.map_or_else(|| serde_json::json!({ "state": "off" }), |v| (v.0)())
    }
}

impl std::fmt::Debug for RecordView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("RecordView")
    }
}

impl PartialEq for RecordView {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The server's ends of the loop's channels.
pub struct LoopHandle {
    /// Bounded: the server only ever `try_send`s.
    pub requests: crossbeam_channel::Sender<Envelope>,
    /// The loop's answers, matched to requests by ticket.
    pub acks: crossbeam_channel::Receiver<Ack>,
    pub telemetry: TelemetryReader,
    pub info: DaemonInfo,
    /// The loop's body: controllers are built for it here, off the loop.
    pub layout: BodyLayout,
    /// Controllers the loop replaced; the server frees them.
    pub retired: crossbeam_channel::Receiver<Installed>,
    /// Where the installed controllers' names and configurations are (the daemon
    /// put the initial ones there).
    pub catalog: Catalog,
}

/// How the daemon talks to its modules.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BusKind {
    /// Real (or `snake-emu`) modules over UDP.
    #[default]
    Udp,
    /// The in-process emulator (`snaked --emulated`).
    Emulated,
}

/// How the loop is paced.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Pacing {
    /// Absolute deadlines on the wall clock.
    #[default]
    Realtime,
    /// Advance when the emulator's feedback for the next step has arrived.
    Lockstep,
}

/// Static facts about the daemon, reported by `status`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct DaemonInfo {
    /// The daemon's version (`CARGO_PKG_VERSION`).
    pub version: String,
    pub module_count: usize,
    /// Module names, head first.
    pub module_names: Vec<String>,
    pub loop_rate_hz: f64,
    pub bus: BusKind,
    pub pacing: Pacing,
}
