//! Who watches every cycle from inside the loop (the recorder, `record::LoopRecorder`):
//! the loop shows each cycle and tells each applied or refused request and set-point
//! fault. The loop knows observers only through [`CycleObserver`], so it does not
//! depend on what they do with it.

use crate::bus::{Bus, GroupFeedback};
use crate::controller_interface::BodyEstimate;
use crate::gait::GaitKind;
use crate::module::Command;
use crate::navigation::progress::ProgressReport;
use crate::navigation::state::NavigatorState;
use crate::rt::controller_slots::ControllerSlots;
use crate::rt::messages::LoopRequest;
use crate::rt::stats::LoopStats;
use crate::safety::failsafe::{Mode, Reason};

/// What a cycle shows its observer.
pub struct CycleView<'a> {
    pub cycle: u64,
    pub t_ns: u64,
    pub mode: Mode,
    pub reason: Reason,
    pub gait: GaitKind,
    pub group: &'a GroupFeedback,
    pub commands: &'a [Command],
    pub slots: &'a ControllerSlots,
    pub bus: &'a dyn Bus,
    pub stats: &'a LoopStats,
    pub body: &'a BodyEstimate,
    /// Whether the running gait makes way (the stuck detector).
    pub progress: ProgressReport,
    /// What the navigator does.
    pub navigator: NavigatorState,
}

/// Watches the loop from its thread: no method may allocate, lock or block (an
/// offline observer may wait for room when it says so, never the daemon's).
pub trait CycleObserver: Send {
    /// The cycle just run.
    fn cycle(&mut self, view: &CycleView<'_>);
    /// A request applied (`result` Ok) or refused, at loop time `t_ns`.
    fn request(
        &mut self,
        t_ns: u64,
        ticket: u64,
        request: LoopRequest,
        result: crate::rt::messages::LoopResult,
    );
    /// A non-finite set-point from `controller_id` at `joint` (the failsafe holds).
    fn setpoint_fault(&mut self, t_ns: u64, joint: usize, controller_id: u64);
    /// What it had to drop so far (a full ring), for the statistics.
    fn dropped(&self) -> u64;
}
