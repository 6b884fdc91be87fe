//! Telemetry leaves the loop through a wait-free latest-value buffer (a triple
//! buffer): the loop overwrites its back buffer in place and publishes, never
//! blocking and never allocating; readers on the async side take the newest.
use std::sync::{Arc, Mutex};

use serde::Serialize;

use crate::bus::BusCounters;
use crate::gait::{GaitKind, GaitTable};
use crate::rt::controller_slots::ControllerTelemetry;
use crate::rt::setpoint_guard::GuardCounters;
use crate::rt::stats::LoopStats;
use crate::safety::failsafe::{Mode, Reason};

/// One joint as the loop last saw and commanded it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct JointTelemetry {
    /// Position set-point sent (NaN when limp).
    pub setpoint_rad: f64,
    pub position_rad: f64,
    pub velocity_rad_s: f64,
    pub torque_nm: f64,
    /// Age of this module's newest feedback, s (infinite before the first).
    pub feedback_age_s: f64,
}

/// The loop's state, published every cycle.
#[derive(Clone)]
pub struct Snapshot {
    pub cycle: u64,
    /// Loop time, s since the loop started (simulated time in lockstep).
    pub t_s: f64,
    pub mode: Mode,
    pub reason: Reason,
    /// The gait the loop is running or blending into.
    pub gait: GaitKind,
    /// 0..1 while blending into `gait`, 1 when done.
    pub blend_progress: f64,
    pub blend_time_s: f64,
    pub params: GaitTable,
    pub joints: Vec<JointTelemetry>,
    pub stats: LoopStats,
    pub bus: BusCounters,
    /// Requests the loop has applied or refused.
    pub requests_applied: u64,
    pub requests_refused: u64,
    /// Every gait's controller and, while the active one drives, its report.
    pub controller: ControllerTelemetry,
    /// What the set-point guard changed or refused.
    pub guard: GuardCounters,
    /// Recorder items dropped because its ring was full (0 without a recorder).
    pub record_dropped: u64,
    /// The estimators' body estimate (pose, heading) this cycle.
    pub body: crate::controller_interface::BodyEstimate,
    /// Whether the running gait makes way (the stuck detector, issue 28).
    pub progress: crate::navigation::progress::ProgressReport,
    /// What the navigator does (issue 28).
    pub navigator: crate::navigation::state::NavigatorState,
    /// Whether the gait moves or a controlled stop holds it (`rt::gait_clock`), and the
    /// gait clock's rate, 0..1.
    pub motion: crate::rt::gait_clock::Motion,
    pub gait_rate: f64,
}

impl Snapshot {
    pub fn new(n: usize, gait: GaitKind, params: GaitTable, blend_time_s: f64) -> Self {
        Snapshot {
            cycle: 0,
            t_s: 0.0,
            mode: Mode::Limp,
            reason: Reason::Startup,
            gait,
            blend_progress: 0.0,
            blend_time_s,
            params,
            joints: vec![JointTelemetry::default(); n],
            stats: LoopStats::default(),
            bus: BusCounters::default(),
            requests_applied: 0,
            requests_refused: 0,
            controller: ControllerTelemetry::default(),
            guard: GuardCounters::default(),
            record_dropped: 0,
            body: crate::controller_interface::BodyEstimate::default(),
            progress: crate::navigation::progress::ProgressReport::default(),
            navigator: crate::navigation::state::NavigatorState::OFF,
            motion: crate::rt::gait_clock::Motion::Running,
            gait_rate: 1.0,
        }
    }
}

/// The loop's end: `write` fills the back buffer in place.
pub struct TelemetryWriter {
    input: triple_buffer::Input<Snapshot>,
}

/// The readers' end, cheap to clone. Reading takes a short lock that only
/// readers contend for; the loop never touches it.
#[derive(Clone)]
pub struct TelemetryReader {
    output: Arc<Mutex<triple_buffer::Output<Snapshot>>>,
}

pub fn channel(initial: Snapshot) -> (TelemetryWriter, TelemetryReader) {
    let (input, output) = triple_buffer::triple_buffer(&initial);
    (
        TelemetryWriter { input },
        TelemetryReader {
            output: Arc::new(Mutex::new(output)),
        },
    )
}

impl TelemetryWriter {
    /// Update the back buffer in place with `fill`, then publish it. The back
    /// buffer holds an older snapshot: `fill` must overwrite every field it uses.
    pub fn write(&mut self, fill: impl FnOnce(&mut Snapshot)) {
        fill(self.input.input_buffer_mut());
        self.input.publish();
    }
}

impl TelemetryReader {
    /// The newest published snapshot (a clone).
    pub fn latest(&self) -> Snapshot {
        let mut out = self.output.lock().unwrap_or_else(|e| e.into_inner());
        out.read().clone()
    }
}
