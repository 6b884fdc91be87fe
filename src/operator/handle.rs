//! What the operator API is given: the loop's ends of its channels and static facts
//! about the daemon, and a window on the recorder's state.

use serde::Serialize;

use crate::controller_interface::catalog::Catalog;
use crate::gait::BodyLayout;
use crate::rt::controller_slots::Installed;
use crate::rt::messages::{Ack, Envelope};
use crate::rt::telemetry::TelemetryReader;

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
    /// HEBI modules through libhebi (`[bus] kind = "hebi"`).
    Hebi,
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
