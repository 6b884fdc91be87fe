//! `SimBus`: the loop's bus over an in-process [`Plant`], no network. Each `receive`
//! advances the plant by one period with the commands of the last `send` and reports
//! every module's feedback as fresh. The sim is always ready, so both
//! [`FeedbackWait`] variants behave the same and nothing ever blocks.
//!
//! Like a real module, a command older than `command_lifetime_s` (simulated time)
//! stops driving and the joint goes limp; `release` makes every joint limp at once.
//!
//! Ground truth (link poses, contacts) is the simulated bus's own: [`SimBus::plant`],
//! reached from the loop's `&dyn Bus` with [`SimBus::of`].

use std::any::Any;

use crate::bus::{Bus, BusCounters, BusError, FeedbackWait, GroupFeedback, ModuleState};
use crate::emu::Plant;
use crate::module::Command;

/// How the in-process bus runs its plant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimBusConfig {
    /// Simulated time advanced by each `receive`, s.
    pub period_s: f64,
    /// Commands older than this (simulated) are dropped and the joints go limp, s.
    pub command_lifetime_s: f64,
}

impl Default for SimBusConfig {
    fn default() -> Self {
        Self {
            period_s: 1e-3,
            // The modules' default (`Settings::default()`), without the f32 rounding.
            command_lifetime_s: 0.05,
        }
    }
}

/// The in-process bus (see the module docs).
pub struct SimBus {
    plant: Box<dyn Plant>,
    config: SimBusConfig,
    commands: Vec<Command>,
    applied: Vec<Command>,
    /// Simulated time of the last `send`.
    last_send_s: Option<f64>,
    seq: u64,
    counters: BusCounters,
}

impl SimBus {
    pub fn new(plant: Box<dyn Plant>, config: SimBusConfig) -> Self {
        let n = plant.module_count();
        Self {
            plant,
            config,
            commands: vec![Command::LIMP; n],
            applied: vec![Command::LIMP; n],
            last_send_s: None,
            seq: 0,
            counters: BusCounters::default(),
        }
    }

    /// `bus` as the simulated bus, if it is one (the loop holds its bus as `dyn Bus`).
    pub fn of(bus: &dyn Bus) -> Option<&SimBus> {
        (bus as &dyn Any).downcast_ref()
    }

    /// The simulated world, e.g. for ground truth in tests and the lab.
    pub fn plant(&self) -> &dyn Plant {
        self.plant.as_ref()
    }

    pub fn plant_mut(&mut self) -> &mut dyn Plant {
        self.plant.as_mut()
    }

    /// Commands the plant applied during the last step (LIMP where expired).
    pub fn applied(&self) -> &[Command] {
        &self.applied
    }
}

impl Bus for SimBus {
    fn module_count(&self) -> usize {
        self.commands.len()
    }

    fn send(&mut self, commands: &[Command]) -> Result<(), BusError> {
        if commands.len() != self.commands.len() {
            return Err(BusError::WrongCount {
                expected: self.commands.len(),
                got: commands.len(),
            });
        }
        self.commands.copy_from_slice(commands);
        self.last_send_s = Some(self.plant.time_s());
        self.seq += 1;
        self.counters.commands_sent += commands.len() as u64;
        Ok(())
    }

    fn receive(
        &mut self,
        group: &mut GroupFeedback,
        now_ns: u64,
        _wait: FeedbackWait,
    ) -> Result<(), BusError> {
        let n = self.commands.len();
        if group.len() != n {
            return Err(BusError::WrongCount {
                expected: n,
                got: group.len(),
            });
        }
        let t = self.plant.time_s();
        let alive = self
            .last_send_s
            .is_some_and(|at| t - at < self.config.command_lifetime_s);
        for (a, c) in self.applied.iter_mut().zip(&self.commands) {
            *a = if alive { *c } else { Command::LIMP };
        }
        self.plant.step(self.config.period_s, &self.applied);
        for (i, m) in group.modules.iter_mut().enumerate() {
            let mut feedback = self.plant.feedback(i);
            feedback.last_command_seq = self.seq;
            *m = ModuleState {
                feedback,
                received_ns: Some(now_ns),
                fresh: true,
                command_age_ns: None,
                clock_age_ns: None,
            };
        }
        self.counters.feedback_received += n as u64;
        Ok(())
    }

    fn counters(&self) -> BusCounters {
        self.counters
    }

    fn release(&mut self) {
        self.commands.fill(Command::LIMP);
        self.last_send_s = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::plant::{JointSpacePlant, NoiseConfig, PlantConfig};

    fn bus(n: usize) -> SimBus {
        let plant = JointSpacePlant::new(PlantConfig {
            noise: NoiseConfig::NONE,
            ..PlantConfig::new(n)
        })
        .unwrap();
        SimBus::new(Box::new(plant), SimBusConfig::default())
    }

    #[test]
    fn steps_once_per_receive_and_marks_everything_fresh() {
        let mut b = bus(3);
        let mut g = GroupFeedback::new(3);
        b.send(&[Command::position(0.2); 3]).unwrap();
        b.receive(&mut g, 42, FeedbackWait::None).unwrap();
        assert!((b.plant().time_s() - 1e-3).abs() < 1e-12);
        for m in &g.modules {
            assert!(m.fresh);
            assert_eq!(m.received_ns, Some(42));
            assert_eq!(m.feedback.module_time_us, 1000);
            assert_eq!(m.feedback.last_command_seq, 1);
        }
        let wait = FeedbackWait::Lockstep {
            min_module_time_us: 2000,
            timeout_ns: 1,
        };
        b.receive(&mut g, 43, wait).unwrap();
        assert_eq!(g.modules[0].feedback.module_time_us, 2000);
        assert_eq!(b.counters().feedback_received, 6);
        assert_eq!(b.counters().commands_sent, 3);
    }

    #[test]
    fn commands_move_the_joints() {
        let mut b = bus(2);
        let mut g = GroupFeedback::new(2);
        for k in 0..300 {
            b.send(&[Command::position(0.2), Command::position(-0.1)])
                .unwrap();
            b.receive(&mut g, k, FeedbackWait::None).unwrap();
        }
        assert!((g.modules[0].feedback.position_rad - 0.2).abs() < 1e-3);
        assert!((g.modules[1].feedback.position_rad + 0.1).abs() < 1e-3);
    }

    #[test]
    fn stale_commands_and_release_go_limp() {
        let mut b = bus(1);
        let mut g = GroupFeedback::new(1);
        b.send(&[Command::position(0.2)]).unwrap();
        // Sent at t = 0 with a 50 ms lifetime: drives the steps starting at 0..=49 ms.
        for k in 0..50 {
            b.receive(&mut g, k, FeedbackWait::None).unwrap();
            assert!(!b.applied()[0].is_limp(), "step {k}");
        }
        b.receive(&mut g, 50, FeedbackWait::None).unwrap();
        assert!(b.applied()[0].is_limp());
        b.send(&[Command::position(0.2)]).unwrap();
        b.release();
        b.receive(&mut g, 51, FeedbackWait::None).unwrap();
        assert!(b.applied()[0].is_limp());
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let mut b = bus(2);
        assert!(matches!(
            b.send(&[Command::LIMP]),
            Err(BusError::WrongCount {
                expected: 2,
                got: 1
            })
        ));
        let mut g = GroupFeedback::new(3);
        assert!(b.receive(&mut g, 0, FeedbackWait::None).is_err());
    }
}
