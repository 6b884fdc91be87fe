//! `EchoBus`: an ideal plant for tests and benchmarks. Every module instantly
//! reaches its position set-point (or stays put when limp) and reports it, with a
//! simulated clock that advances one period per `receive`. Modules can be made to
//! fall silent or report non-finite data, to exercise the failsafe, and report torques
//! from a scripted model, to exercise compliant controllers.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::bus::{Bus, BusCounters, BusError, FeedbackWait, GroupFeedback};
use crate::module::{Command, Feedback};

pub struct EchoBus {
    period_us: u64,
    time_us: u64,
    positions: Vec<f32>,
    faults: Arc<EchoFaults>,
    seq: u64,
    counters: BusCounters,
    torque: Option<TorqueModel>,
}

/// Reported torque, N·m, of joint `i` at position `position_rad` (the protocol's sign:
/// the torque the motor applies to the output, so an obstacle pushing the joint toward
/// negative angles reads positive).
pub type TorqueModel = fn(i: usize, position_rad: f32) -> f32;

impl EchoBus {
    pub fn new(n: usize, period_ns: u64) -> Self {
        Self {
            period_us: period_ns / 1000,
            time_us: 0,
            positions: vec![0.0; n],
            faults: Arc::new(EchoFaults {
                silent: (0..n).map(|_| AtomicBool::new(false)).collect(),
                corrupt: (0..n).map(|_| AtomicBool::new(false)).collect(),
            }),
            seq: 0,
            counters: BusCounters::default(),
            torque: None,
        }
    }

    /// Report torques from `model` (otherwise 0).
    pub fn with_torque(mut self, model: TorqueModel) -> Self {
        self.torque = Some(model);
        self
    }

    /// Start from this pose.
    pub fn with_positions(mut self, positions: &[f32]) -> Self {
        self.positions.copy_from_slice(positions);
        self
    }

    /// A handle to inject faults while the bus is owned by a loop.
    pub fn faults(&self) -> Arc<EchoFaults> {
        self.faults.clone()
    }

    pub fn positions(&self) -> &[f32] {
        &self.positions
    }
}

impl Bus for EchoBus {
    fn module_count(&self) -> usize {
        self.positions.len()
    }

    fn send(&mut self, commands: &[Command]) -> Result<(), BusError> {
        if commands.len() != self.positions.len() {
            return Err(BusError::WrongCount {
                expected: self.positions.len(),
                got: commands.len(),
            });
        }
        for (p, c) in self.positions.iter_mut().zip(commands) {
            if c.position_rad.is_finite() {
                *p = c.position_rad;
            }
        }
        self.counters.commands_sent += commands.len() as u64;
        Ok(())
    }

    fn receive(
        &mut self,
        group: &mut GroupFeedback,
        now_ns: u64,
        _wait: FeedbackWait,
    ) -> Result<(), BusError> {
        self.time_us += self.period_us;
        self.seq += 1;
        for (i, m) in group.modules.iter_mut().enumerate() {
            let silent = self.faults.silent[i].load(Ordering::Relaxed);
            m.fresh = !silent;
            if silent {
                continue;
            }
            let corrupt = self.faults.corrupt[i].load(Ordering::Relaxed);
            m.feedback = Feedback {
                module_time_us: self.time_us,
                last_command_seq: self.seq,
                position_rad: if corrupt { f32::NAN } else { self.positions[i] },
                torque_nm: self.torque.map_or(0.0, |model| model(i, self.positions[i])),
                accel_m_s2: [0.0, 0.0, 9.81],
                ..Feedback::default()
            };
            m.received_ns = Some(now_ns);
            self.counters.feedback_received += 1;
        }
        Ok(())
    }

    fn counters(&self) -> BusCounters {
        self.counters
    }
}

/// Faults an `EchoBus` injects, settable from another thread.
pub struct EchoFaults {
    silent: Vec<AtomicBool>,
    corrupt: Vec<AtomicBool>,
}

impl EchoFaults {
    /// Module `i` stops (or resumes) reporting.
    pub fn set_silent(&self, i: usize, silent: bool) {
        self.silent[i].store(silent, Ordering::Relaxed);
    }

    /// Module `i` reports NaN positions (or stops doing so).
    pub fn set_corrupt(&self, i: usize, corrupt: bool) {
        self.corrupt[i].store(corrupt, Ordering::Relaxed);
    }
}
