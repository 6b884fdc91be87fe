//! The live view: the Foxglove WebSocket server that serves the recorder's channels as
//! they are written (`record` starts it on its context, on its writer thread), latches
//! what is published once for late subscribers, reports slow viewers, and carries the
//! operator's station (`station`) when `[foxglove] operate` is on.
//!
//! - [`server`]: the server, its listener and the station's hook-up ([`Live`]).
//! - [`latch`]: latched messages and the count of connected clients ([`Latch`]).
//! - [`viewers`]: slow viewers made visible (`/live/viewers`, a warning status).

pub mod latch;
pub mod server;
pub mod viewers;

use std::net::{Ipv4Addr, SocketAddr};

pub use latch::Latch;
pub use server::Live;

/// Port the Foxglove app connects to by default.
pub const DEFAULT_LIVE_PORT: u16 = 8765;

/// Where the live view listens.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveOptions {
    /// Default `127.0.0.1:8765` (loopback: watching needs no authentication). Port 0
    /// picks a free port (`record::Recorder::live_addr` tells which).
    pub addr: SocketAddr,
    /// Operating from Foxglove (services, teleop; `[foxglove] operate`): `None`, the
    /// view is for watching only.
    pub station: Option<crate::station::Station>,
    /// Connections the server holds at once, counted from accept (one still in its
    /// handshake counts); one more is closed at once, with a warning. `None`: no cap.
    pub max_connections: Option<usize>,
    /// ...of which from one IP address.
    pub max_connections_per_address: Option<usize>,
    /// A connection that has not completed its WebSocket handshake and taken the server's
    /// first message within this long is closed. `None`: no timeout.
    pub handshake_timeout: Option<std::time::Duration>,
}

impl Default for LiveOptions {
    fn default() -> Self {
        Self {
            addr: SocketAddr::from((Ipv4Addr::LOCALHOST, DEFAULT_LIVE_PORT)),
            station: None,
            max_connections: None,
            max_connections_per_address: None,
            handshake_timeout: None,
        }
    }
}

/// An asset the server hands out when a client fetches its URI: the robot's model (the
/// recorder's URDF) for the 3-D panel's URDF layer.
#[derive(Debug, Clone)]
pub struct Asset {
    pub uri: &'static str,
    pub body: String,
}

/// Why the live view could not start (`record::RecordError::Live` and `::Runtime` when
/// the recorder starts it).
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error("cannot start the live view on {addr}: {reason}")]
    Bind {
        addr: SocketAddr,
        reason: foxglove::FoxgloveError,
    },
    #[error("cannot start the live view's runtime: {0}")]
    Runtime(std::io::Error),
}
