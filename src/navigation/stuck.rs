//! Knowing the body is jammed, from the joint torques alone (issue 28, point 2).
//!
//! Why the torques' repetition: a body jammed among pegs settles into an exact limit
//! cycle (its centre repeats each gait cycle to the millimetre; its joint torques
//! repeat to the sensors' noise), while a body making way among irregular pegs meets
//! a new arrangement every cycle and its torques change. Measured on the sleeve board
//! (docs/measurements/crossing.md, "Knowing it is stuck"): cycles moving more than 0.1 m have
//! a repeat error (below) of 0.8-5, jammed ones 0.15-0.4. What it cannot tell: a body
//! that repeats while it moves (open ground, a lattice of pegs matched to its wave),
//! which the daemon, with no odometry, cannot see move either (proprioceptive
//! odometry assuming no sideways slip was tried and fails: it reads +0.5 m per cycle
//! where the body drifts back 0.04 m on open ground).
//!
//! The repeat error of a cycle: RMS over the cycle of `τ(t) − τ(t − T)` over the RMS
//! of `τ(t)`, all joints, sampled [`SLOTS`] times a cycle at the same phases. Stuck:
//! the last `confirm_cycles` whole cycles each below `threshold`.

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_range};

/// Samples per gait cycle.
pub const SLOTS: usize = 64;

/// The detector's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StuckConfig {
    /// A cycle whose repeat error is below this repeats (0.15 is the sensor noise).
    pub threshold: f64,
    /// Whole cycles in a row that must repeat before the body counts as stuck.
    pub confirm_cycles: u32,
}

impl StuckConfig {
    pub const DEFAULT: Self = Self {
        threshold: 0.5,
        confirm_cycles: 1,
    };

    pub fn check(&self) -> Result<(), ConfigError> {
        check_range("threshold", self.threshold, 0.0, 10.0)?;
        check_range("confirm_cycles", f64::from(self.confirm_cycles), 1.0, 100.0)
    }
}

impl Default for StuckConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why the body counts as stuck (or does not).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StuckReason {
    /// Not a whole cycle measured since the last reset.
    Measuring,
    /// The torques change from cycle to cycle: the body meets new terrain.
    Changing,
    /// The torques repeat each cycle: a limit cycle, jammed (or on terrain that
    /// repeats with the wave).
    TorquesRepeat,
}

/// The detector of one gait's run; allocates at construction only.
#[derive(Debug, Clone)]
pub struct StuckDetector {
    config: StuckConfig,
    joints: usize,
    every_s: f64,
    since_s: f64,
    /// The last cycle's samples, slot-major, and the slot the next sample fills.
    ring: Vec<f64>,
    slot: usize,
    /// Samples taken since the reset (the first cycle has nothing to compare with).
    samples: usize,
    diff: f64,
    norm: f64,
    repeating_cycles: u32,
    /// The last whole cycle's repeat error.
    pub repeat_error: Option<f64>,
}

impl StuckDetector {
    /// For `joints` joints and a gait cycle of `cycle_s` s.
    pub fn new(config: StuckConfig, joints: usize, cycle_s: f64) -> Self {
        let mut d = Self {
            config,
            joints,
            every_s: 1.0,
            since_s: 0.0,
            ring: vec![0.0; SLOTS * joints],
            slot: 0,
            samples: 0,
            diff: 0.0,
            norm: 0.0,
            repeating_cycles: 0,
            repeat_error: None,
        };
        d.reset(cycle_s);
        d
    }

    /// Starts afresh (a new gait, wave or controller) with a cycle of `cycle_s` s.
    pub fn reset(&mut self, cycle_s: f64) {
        let cycle_s = if cycle_s.is_finite() && cycle_s > 0.0 {
            cycle_s
        } else {
            std::f64::consts::TAU
        };
        self.every_s = cycle_s / SLOTS as f64;
        self.since_s = self.every_s; // sample at the first update
        self.slot = 0;
        self.samples = 0;
        self.diff = 0.0;
        self.norm = 0.0;
        self.repeating_cycles = 0;
        self.repeat_error = None;
    }

    /// `dt_s` later, the joints' torques `torque_nm` (non-finite ones count as 0).
    pub fn update(&mut self, dt_s: f64, torque_nm: &[f64]) {
        self.since_s += dt_s;
        if self.since_s < self.every_s {
            return;
        }
        self.since_s -= self.every_s;
        let row = &mut self.ring[self.slot * self.joints..(self.slot + 1) * self.joints];
        let compare = self.samples >= SLOTS;
        for (old, &tau) in row.iter_mut().zip(torque_nm) {
            let tau = if tau.is_finite() { tau } else { 0.0 };
            if compare {
                self.diff += (tau - *old).powi(2);
                self.norm += tau * tau;
            }
            *old = tau;
        }
        self.samples += 1;
        self.slot = (self.slot + 1) % SLOTS;
        if compare && self.slot == 0 {
            let e = if self.norm > 1e-12 {
                (self.diff / self.norm).sqrt()
            } else {
                0.0
            };
            self.repeat_error = Some(e);
            self.repeating_cycles = if e < self.config.threshold {
                self.repeating_cycles.saturating_add(1)
            } else {
                0
            };
            self.diff = 0.0;
            self.norm = 0.0;
        }
    }

    pub fn stuck(&self) -> bool {
        self.repeating_cycles >= self.config.confirm_cycles
    }

    pub fn reason(&self) -> StuckReason {
        match self.repeat_error {
            None => StuckReason::Measuring,
            Some(_) if self.stuck() => StuckReason::TorquesRepeat,
            Some(_) => StuckReason::Changing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// Feeds `cycles` cycles of torques `tau(t)` at 1 kHz.
    fn feed(d: &mut StuckDetector, t0: f64, cycles: f64, tau: impl Fn(f64, usize) -> f64) -> f64 {
        let steps = (cycles * TAU * 1000.0) as usize;
        let mut buf = [0.0; 4];
        for k in 0..steps {
            let t = t0 + k as f64 * 1e-3;
            for (j, b) in buf.iter_mut().enumerate() {
                *b = tau(t, j);
            }
            d.update(1e-3, &buf);
        }
        t0 + steps as f64 * 1e-3
    }

    #[test]
    fn a_repeating_torque_is_stuck_a_changing_one_is_not() {
        let mut d = StuckDetector::new(StuckConfig::DEFAULT, 4, TAU);
        assert_eq!(d.reason(), StuckReason::Measuring);
        // Changing: the pattern drifts in phase by a third of a cycle per cycle.
        let t = feed(&mut d, 0.0, 4.0, |t, j| (t * (1.0 + 0.33) + j as f64).sin());
        assert_eq!(d.reason(), StuckReason::Changing, "{:?}", d.repeat_error);
        assert!(d.repeat_error.unwrap() > 1.0);
        // Repeating (a gait-periodic torque with 5 % noise-like ripple at an odd rate).
        feed(&mut d, t, 3.0, |t, j| {
            (t + j as f64).sin() + 0.05 * (t * 37.3).sin()
        });
        assert!(d.stuck(), "{:?}", d.repeat_error);
        assert_eq!(d.reason(), StuckReason::TorquesRepeat);
        d.reset(TAU);
        assert!(!d.stuck());
        assert_eq!(d.reason(), StuckReason::Measuring);
    }

    #[test]
    fn settings_out_of_range_are_named() {
        let bad = StuckConfig {
            confirm_cycles: 0,
            ..StuckConfig::DEFAULT
        };
        assert!(
            bad.check()
                .unwrap_err()
                .to_string()
                .contains("confirm_cycles")
        );
    }
}
