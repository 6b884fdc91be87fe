//! The control loop: read → update → write, once per cycle.
//!
//! Nothing in [`ControlLoop::cycle`] allocates, locks or logs: buffers are sized
//! in [`ControlLoop::new`], requests arrive through `try_recv`, answers and
//! telemetry leave through `try_send` and a triple buffer. The daemon's other
//! threads log what the telemetry shows.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crossbeam_channel::{Receiver, Sender};

use crate::bus::{Bus, GroupFeedback};
use crate::controller_interface::{BodyEstimate, Estimator, Imu, Observation};
use crate::gait::{GaitKind, GaitSelector, ParamPatch};
use crate::module::Command;
use crate::navigation::progress::{ProgressMonitor, ProgressReport};
use crate::navigation::state::NavigatorState;
use crate::navigation::stuck::StuckConfig;
use crate::rt::controller_slots::{ControllerSlots, Installed};
use crate::rt::gait_clock::{DEFAULT_STOP_S, GaitClock, STOP_TIME_RANGE_S};
use crate::rt::messages::{Ack, Continuity, Envelope, LoopRequest, LoopResult, Refusal, Rejection};
use crate::rt::observer::CycleObserver;
use crate::rt::pacer::{Cycle, Pacer};
use crate::rt::setpoint_guard::{NonFiniteSetpoint, SetpointGuard};
use crate::rt::stats::{LoopStats, StatsReport};
use crate::rt::telemetry::TelemetryWriter;
use crate::safety::failsafe::{Event, Failsafe, Mode, Output};

/// Requests applied per cycle at most, so a flood cannot stretch a cycle.
pub const MAX_REQUESTS_PER_CYCLE: usize = 8;

/// The ack channel for a request channel of `requests`: a full queue and one cycle's
/// answers. The server keeps no more requests in flight than this (`operator::router`),
/// so the loop's `try_send` of an answer never finds it full; while the server takes
/// the answers within a cycle, only a full queue makes it answer "busy".
pub const fn ack_capacity(requests: usize) -> usize {
    requests + MAX_REQUESTS_PER_CYCLE
}

/// Everything the loop is built from.
pub struct LoopParts {
    pub bus: Box<dyn Bus>,
    pub pacer: Box<dyn Pacer>,
    pub selector: GaitSelector,
    pub failsafe: Failsafe,
    pub requests: Receiver<Envelope>,
    pub acks: Sender<Ack>,
    pub telemetry: TelemetryWriter,
    /// Incremented every cycle; the watchdog pings systemd only while it moves.
    pub heartbeat: Arc<AtomicU64>,
    /// Set by the signal handler: the loop runs its safe stop and exits.
    pub stop: Arc<AtomicBool>,
    pub velocity_feedforward: bool,
    /// Hold the measured pose after start-up instead of running the gait.
    pub hold_at_start: bool,
    /// Controllers the loop replaced or refused, for the control side to free
    /// (bounded; the loop only `try_send`s).
    pub retired: Sender<Installed>,
    /// The controllers to start with, per gait (a gait without one runs the
    /// selector's serpenoid).
    pub controllers: Vec<(GaitKind, Installed)>,
    /// Fill the body estimate each cycle before the controllers run, in order.
    pub estimators: Vec<Box<dyn Estimator>>,
    /// Where every cycle is recorded (`None`: not recorded).
    pub observer: Option<Box<dyn CycleObserver>>,
}

/// Whether the loop goes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Finished,
}

pub struct ControlLoop {
    p: LoopParts,
    group: GroupFeedback,
    commands: Vec<Command>,
    positions: Vec<f64>,
    velocities: Vec<f64>,
    measured: Vec<f64>,
    measured_velocity: Vec<f64>,
    /// Reported joint torques, N·m (what compliant controllers feel).
    torques: Vec<f64>,
    imu: Vec<Imu>,
    body: BodyEstimate,
    /// Whether the running gait makes way (issue 28): restarted by every change.
    progress: ProgressMonitor,
    /// What the navigator does, as its runner last said.
    navigator: NavigatorState,
    slots: ControllerSlots,
    /// The gait side's time: the loop's, but for controlled stops.
    clock: GaitClock,
    guard: SetpointGuard,
    observer: Option<Box<dyn CycleObserver>>,
    held: Vec<f64>,
    held_valid: bool,
    stats: LoopStats,
    last_module_time_us: Option<u64>,
    applied: u64,
    refused: u64,
    stop_seen: bool,
    started: bool,
    pending_acks: [Ack; MAX_REQUESTS_PER_CYCLE],
    pending: usize,
}

impl ControlLoop {
    pub fn new(mut parts: LoopParts) -> Self {
        let n = parts.bus.module_count();
        let mut slots = ControllerSlots::new(parts.retired.clone());
        for (gait, c) in parts.controllers.drain(..) {
            // Not driving yet: no hand-back, the commanded pose is not used.
            slots.install(gait, c, &mut parts.selector, &[], 0.0);
        }
        let guard = SetpointGuard::new(n, parts.selector.max_joint_speed_rad_s());
        let observer = parts.observer.take();
        Self {
            p: parts,
            group: GroupFeedback::new(n),
            commands: vec![Command::LIMP; n],
            positions: vec![0.0; n],
            velocities: vec![0.0; n],
            measured: vec![0.0; n],
            measured_velocity: vec![0.0; n],
            torques: vec![0.0; n],
            imu: vec![Imu::default(); n],
            body: BodyEstimate::default(),
            progress: ProgressMonitor::new(StuckConfig::DEFAULT, n),
            navigator: NavigatorState::OFF,
            slots,
            clock: GaitClock::new(),
            guard,
            observer,
            held: vec![0.0; n],
            held_valid: false,
            stats: LoopStats::default(),
            last_module_time_us: None,
            applied: 0,
            refused: 0,
            stop_seen: false,
            started: false,
            pending_acks: [Ack {
                ticket: 0,
                result: Ok(None),
            }; MAX_REQUESTS_PER_CYCLE],
            pending: 0,
        }
    }

    /// Run until the safe stop finishes; hands the modules back and returns the statistics.
    pub fn run(mut self) -> StatsReport {
        loop {
            let cycle = self.p.pacer.next_cycle();
            if self.cycle(&cycle) == Flow::Finished {
                break;
            }
        }
        self.p.bus.release();
        self.stats.report()
    }

    /// Wait for the next cycle and run it (what `run` does, one cycle at a time).
    pub fn step(&mut self) -> Flow {
        let cycle = self.p.pacer.next_cycle();
        self.cycle(&cycle)
    }

    /// Commands sent in the last cycle, head first.
    pub fn commands(&self) -> &[Command] {
        &self.commands
    }

    pub fn stats(&self) -> &LoopStats {
        &self.stats
    }

    /// The failsafe's mode after the last cycle.
    pub fn mode(&self) -> Mode {
        self.p.failsafe.mode()
    }

    /// The bus (e.g. for a simulated plant's ground truth).
    pub fn bus(&self) -> &dyn Bus {
        self.p.bus.as_ref()
    }

    /// What the set-point guard changed so far.
    pub fn guard_counters(&self) -> crate::rt::setpoint_guard::GuardCounters {
        self.guard.counters()
    }

    /// The estimators' body estimate of the last cycle.
    pub fn body(&self) -> &BodyEstimate {
        &self.body
    }

    /// Whether the running gait makes way (the stuck detector).
    pub fn progress(&self) -> ProgressReport {
        self.progress.report()
    }

    /// What the navigator does, as its runner last told the loop.
    pub fn navigator(&self) -> NavigatorState {
        self.navigator
    }

    /// The controller slots (which one drives, its last report).
    /// The gait the selector runs or blends into.
    pub fn gait(&self) -> crate::gait::GaitKind {
        self.p.selector.active()
    }

    pub fn controllers(&self) -> &ControllerSlots {
        &self.slots
    }

    /// One cycle: read feedback, apply requests, run the failsafe and the gait,
    /// write commands, record statistics and telemetry.
    pub fn cycle(&mut self, c: &Cycle) -> Flow {
        let started_ns = self.p.pacer.elapsed_ns();
        let now_s = c.clock_ns as f64 * 1e-9;
        let t_s = c.t_ns as f64 * 1e-9;
        // The gait side's time this cycle (the loop's unless a controlled stop ran).
        let tau = self.clock.advance(t_s);

        // Read.
        let wait = self.p.pacer.feedback_wait(c, self.last_module_time_us);
        let (bus, io_started_ns) = (&mut self.p.bus, self.p.pacer.elapsed_ns());
        if bus.receive(&mut self.group, c.clock_ns, wait).is_err() {
            self.stats.bus_errors += 1;
        }
        let mut io_ns = self.p.pacer.elapsed_ns().saturating_sub(io_started_ns);
        let health = self.assess(c);

        // Operator requests, at the cycle boundary.
        if self.p.stop.load(Ordering::Relaxed) && !self.stop_seen {
            self.stop_seen = true;
            let _ = self.p.failsafe.request(now_s, Event::Shutdown);
        }
        for _ in 0..MAX_REQUESTS_PER_CYCLE {
            let Ok(env) = self.p.requests.try_recv() else {
                break;
            };
            let request = env.request;
            let result = self.apply(request, env.controller, now_s, t_s, tau);
            if let Some(o) = self.observer.as_mut() {
                o.request(c.t_ns, env.ticket, request, result);
            }
            if result.is_ok() {
                if changes_the_gait(&request) {
                    self.progress.restart();
                }
                self.applied += 1;
            } else {
                self.refused += 1;
            }
            self.pending_acks[self.pending] = Ack {
                ticket: env.ticket,
                result,
            };
            self.pending += 1;
        }

        // Update.
        let output = self.p.failsafe.update(now_s, &health);
        let mut fault = None;
        let flow = match output {
            Output::Resync => {
                // From rest (the measured pose): the blend in starts at zero speed.
                self.clock.run();
                self.p.selector.resync(&self.measured, tau);
                self.slots.pause();
                self.guard.forget();
                self.p.failsafe.resynced(now_s);
                if self.p.hold_at_start && !self.started {
                    let _ = self.p.failsafe.request(now_s, Event::Hold);
                    self.hold_commands();
                } else {
                    fault = self.run_commands(t_s, tau, now_s);
                }
                self.started = true;
                Flow::Continue
            }
            Output::Run => {
                fault = self.run_commands(t_s, tau, now_s);
                Flow::Continue
            }
            Output::Hold => {
                self.hold_commands();
                Flow::Continue
            }
            Output::Limp => {
                self.limp_commands();
                Flow::Continue
            }
            Output::Finished => {
                self.limp_commands();
                Flow::Finished
            }
        };

        // Write.
        let send_started_ns = self.p.pacer.elapsed_ns();
        if self.p.bus.send(&self.commands).is_err() {
            self.stats.bus_errors += 1;
        }
        io_ns += self.p.pacer.elapsed_ns().saturating_sub(send_started_ns);
        self.stats.bus_io.record(io_ns);

        // Measure and publish.
        let compute_ns = self.p.pacer.elapsed_ns().saturating_sub(started_ns);
        self.record(c, compute_ns);
        self.publish(c);
        self.record_cycle(c, fault);
        // Answers leave after the telemetry that shows their effect (read-your-writes).
        // The server never has more requests in flight than the channel holds, so
        // `try_send` does not fail while it runs (`ack_capacity`).
        for ack in &self.pending_acks[..self.pending] {
            let _ = self.p.acks.try_send(*ack);
        }
        self.pending = 0;
        self.p.heartbeat.fetch_add(1, Ordering::Release);
        flow
    }

    /// Applies one request; `t_s` is the loop's time, `tau` the gait clock's.
    fn apply(
        &mut self,
        req: LoopRequest,
        controller: Option<Installed>,
        now_s: f64,
        t_s: f64,
        tau: f64,
    ) -> LoopResult {
        // E-stop freezes intent: what would run after `arm` changes only before the stop.
        if self.p.failsafe.mode() == Mode::EStop && !allowed_while_estopped(&req) {
            if let Some(c) = controller {
                self.slots.refuse(c);
            }
            return Err(Rejection::Failsafe(Refusal::EStopLatched));
        }
        match req {
            LoopRequest::SetParams { gait: kind, patch } => {
                return self.set_params(kind, &patch, controller, tau);
            }
            LoopRequest::SetController { gait: kind } => {
                let c = controller.ok_or(Rejection::NoController)?;
                let (selector, commanded) = (&mut self.p.selector, &self.positions);
                return Ok(Some(self.slots.install(kind, c, selector, commanded, tau)));
            }
            _ => {
                if let Some(c) = controller {
                    self.slots.refuse(c);
                }
            }
        }
        let fs = &mut self.p.failsafe;
        let done = match req {
            LoopRequest::SetGait { gait: kind } => {
                // Setting a gait also arms a held or limp robot, never an e-stopped one:
                // only an explicit arm releases the e-stop.
                match fs.mode() {
                    Mode::EStop => return Err(Rejection::Failsafe(Refusal::EStopLatched)),
                    Mode::Running => {}
                    Mode::Hold | Mode::Limp => fs.request(now_s, Event::Arm)?,
                }
                self.p.selector.set_gait(kind, tau);
                if self.slots.engaged().is_some_and(|g| g != kind) {
                    let (selector, commanded) = (&mut self.p.selector, &self.positions);
                    self.slots.hand_back(selector, commanded, tau);
                }
                // Asking for a gait asks for motion: a controlled stop ends.
                self.clock.resume(t_s, DEFAULT_STOP_S);
                Ok(())
            }
            LoopRequest::ControllerCommand {
                gait: kind,
                command,
            } => self.slots.command(kind, command),
            LoopRequest::SetBlendTime { blend_time_s: s } => self
                .p
                .selector
                .set_blend_time(s)
                .map_err(|_| Rejection::InvalidParams),
            LoopRequest::StopGait { within_s } | LoopRequest::ResumeGait { within_s } => {
                let (lo, hi) = STOP_TIME_RANGE_S;
                if !(lo..=hi).contains(&within_s) {
                    return Err(Rejection::InvalidParams);
                }
                if matches!(req, LoopRequest::StopGait { .. }) {
                    self.clock.stop(t_s, within_s);
                } else {
                    self.clock.resume(t_s, within_s);
                }
                Ok(())
            }
            LoopRequest::Hold => Ok(fs.request(now_s, Event::Hold)?),
            LoopRequest::Limp => Ok(fs.request(now_s, Event::Limp)?),
            LoopRequest::EStop => Ok(fs.request(now_s, Event::EStop)?),
            LoopRequest::Arm => Ok(fs.request(now_s, Event::Arm)?),
            LoopRequest::Shutdown => {
                self.stop_seen = true;
                Ok(fs.request(now_s, Event::Shutdown)?)
            }
            LoopRequest::Navigation { state } => {
                self.navigator = state;
                Ok(())
            }
            LoopRequest::SetParams { .. } | LoopRequest::SetController { .. } => {
                unreachable!("handled above")
            }
        };
        done.map(|()| None)
    }

    /// A gait's new parameters, and maybe a new controller for it, at this cycle
    /// boundary. The controller that will run the gait must accept them. The selector
    /// blends into them; a driving controller follows them where it can, else hands
    /// back and takes over again when the blend ends (`ControllerSlots::follow`). The
    /// answer says which; with a new controller, what became of that.
    fn set_params(
        &mut self,
        kind: GaitKind,
        patch: &ParamPatch,
        controller: Option<Installed>,
        t_s: f64,
    ) -> LoopResult {
        let selector = &self.p.selector;
        let length = selector.layout().module_length_m;
        let checked = match selector.table().get(kind).patched_for(kind, patch, length) {
            Err(_) => Err(Rejection::InvalidParams),
            Ok(next) => match &controller {
                Some(c) => c.controller.accepts(&next),
                None => self.slots.accepts(kind, &next),
            }
            .map_err(Rejection::ControllerRefuses),
        };
        if let Err(why) = checked {
            if let Some(c) = controller {
                self.slots.refuse(c);
            }
            return Err(why);
        }
        let (selector, commanded) = (&mut self.p.selector, &self.positions);
        selector
            .set_params(kind, patch, t_s)
            .map_err(|_| Rejection::InvalidParams)?;
        let next = *selector.table().get(kind);
        let followed = self.slots.follow(kind, &next, selector, commanded, t_s);
        let Some(c) = controller else {
            return Ok(Some(followed));
        };
        let installed = self.slots.install(kind, c, selector, commanded, t_s);
        // The new configuration taken in place by a controller that had to hand back
        // still waits for the blend: say the hand-back.
        Ok(Some(match (followed, installed) {
            (Continuity::HandedBack { .. }, Continuity::Reconfigured) => followed,
            _ => installed,
        }))
    }

    /// Runs the gait (selector, estimators, controller, guard) into the commands, the
    /// gait side on the gait clock's `tau`; a refused non-finite set-point is returned
    /// (the loop holds instead).
    fn run_commands(&mut self, t_s: f64, tau: f64, now_s: f64) -> Option<NonFiniteSetpoint> {
        self.held_valid = false;
        self.p
            .selector
            .update(tau, &mut self.positions, &mut self.velocities);
        let rate = self.clock.rate();
        if rate != 1.0 {
            // The selector's velocities are per unit of gait time.
            self.velocities.iter_mut().for_each(|v| *v *= rate);
        }
        let previous = self.body;
        let mut obs = Observation {
            position_rad: &self.measured,
            velocity_rad_s: &self.measured_velocity,
            torque_nm: &self.torques,
            imu: &self.imu,
            body: &previous,
        };
        for e in &mut self.p.estimators {
            e.update(t_s, &obs, &mut self.body);
        }
        obs.body = &self.body;
        let drove = self
            .slots
            .drive(tau, &self.p.selector, &obs, &mut self.positions);
        let table = self.p.selector.table();
        // A stopped gait is not stuck: only full-rate cycles are measured.
        let steady = self.p.selector.blend_progress() >= 1.0 && rate == 1.0;
        let freq = table
            .get(self.p.selector.active())
            .temporal_freq_rad_s
            .abs();
        let cycle_s = (steady && freq > 1e-6).then(|| std::f64::consts::TAU / freq);
        self.progress.update(t_s, cycle_s, &self.torques);
        let checked = self
            .guard
            .check(t_s, &mut self.positions, &mut self.velocities, drove);
        if let Err(fault) = checked {
            // Not sent: hold what was sent last cycle, say why, wait for the operator.
            self.p.failsafe.setpoint_fault(now_s);
            self.hold_commands();
            for (p, c) in self.positions.iter_mut().zip(&self.commands) {
                *p = f64::from(c.position_rad);
            }
            return Some(fault);
        }
        for i in 0..self.commands.len() {
            let velocity = if self.p.velocity_feedforward {
                self.velocities[i] as f32
            } else {
                f32::NAN
            };
            self.commands[i] = Command {
                position_rad: self.positions[i] as f32,
                velocity_rad_s: velocity,
                torque_nm: f32::NAN,
            };
        }
        None
    }

    /// Freeze the set-points: the last commanded ones when there are any, else the
    /// measured pose (coming out of limp).
    fn hold_commands(&mut self) {
        self.progress.restart();
        self.slots.pause();
        self.guard.forget();
        if !self.held_valid {
            for i in 0..self.commands.len() {
                let last = self.commands[i].position_rad;
                self.held[i] = if last.is_finite() {
                    last as f64
                } else {
                    self.measured[i]
                };
            }
            self.held_valid = true;
        }
        for i in 0..self.commands.len() {
            self.commands[i] = Command {
                position_rad: self.held[i] as f32,
                velocity_rad_s: 0.0,
                torque_nm: f32::NAN,
            };
        }
    }

    fn limp_commands(&mut self) {
        self.progress.restart();
        self.slots.pause();
        self.guard.forget();
        self.held_valid = false;
        self.commands.fill(Command::LIMP);
    }
}

mod io;

#[cfg(test)]
#[path = "control_loop_tests.rs"]
mod tests;

/// What an e-stopped loop still takes: the stops, `arm`, shutdown and the navigator's
/// report. Everything else would change what runs after `arm`.
fn allowed_while_estopped(request: &LoopRequest) -> bool {
    matches!(
        request,
        LoopRequest::Hold
            | LoopRequest::Limp
            | LoopRequest::EStop
            | LoopRequest::Arm
            | LoopRequest::Shutdown
            | LoopRequest::Navigation { .. }
            | LoopRequest::StopGait { .. }
    )
}

/// Whether an applied request changes what the body does, so the progress monitor must
/// measure afresh: not a new nominal heading (steering towards it changes the torques
/// from one cycle to the next, which the monitor reads as not stuck anyway; a
/// navigator that re-aims would otherwise never get a whole cycle measured) and not the
/// navigator's report.
fn changes_the_gait(request: &LoopRequest) -> bool {
    !matches!(
        request,
        LoopRequest::Navigation { .. }
            | LoopRequest::ControllerCommand {
                command: crate::controller_interface::ControllerCommand::SetHeading { .. },
                ..
            }
    )
}
