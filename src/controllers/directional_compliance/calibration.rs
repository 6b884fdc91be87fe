//! The ground's friction offset of the absition (SPEC §8): how far each window's
//! amplitude sits from nominal while the snake runs on open ground, measured over a
//! few gait cycles per plane and body third, on the operator's command
//! (`controller.calibrate`), and kept with the controller until cleared.

use super::config::{FrictionOffset, OFFSET_BINS, clamp_offset};
use crate::controller::CommandRefused;

/// Longest calibration accepted, s.
const MAX_DURATION_S: f64 = 3600.0;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    None,
    Running,
    Calibrated,
}

/// The offsets in use and a measurement in progress. `Copy`-sized; nothing allocates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    offsets: FrictionOffset,
    state: State,
    duration_s: f64,
    elapsed_s: f64,
    /// ∫ deviation dt and ∫ dt per plane and body third.
    sums: [[f64; OFFSET_BINS]; 2],
    times: [[f64; OFFSET_BINS]; 2],
}

pub const ZERO_OFFSET: FrictionOffset = FrictionOffset {
    lateral_rad: [0.0; OFFSET_BINS],
    dorsal_rad: [0.0; OFFSET_BINS],
};

impl Calibration {
    /// Calibrated from a configuration's offsets, or uncalibrated (offset 0).
    pub fn new(from_config: Option<FrictionOffset>) -> Self {
        Self {
            offsets: from_config.unwrap_or(ZERO_OFFSET),
            state: if from_config.is_some() {
                State::Calibrated
            } else {
                State::None
            },
            duration_s: 0.0,
            elapsed_s: 0.0,
            sums: [[0.0; OFFSET_BINS]; 2],
            times: [[0.0; OFFSET_BINS]; 2],
        }
    }

    /// Starts measuring over the controller's next `duration_s`.
    pub fn start(&mut self, duration_s: f64) -> Result<(), CommandRefused> {
        if !(duration_s.is_finite() && duration_s > 0.0 && duration_s <= MAX_DURATION_S) {
            return Err(CommandRefused::BadDuration);
        }
        self.duration_s = duration_s;
        self.state = State::Running;
        self.restart();
        Ok(())
    }

    /// A measurement in progress starts over (the controller was engaged afresh).
    pub fn restart(&mut self) {
        self.elapsed_s = 0.0;
        self.sums = [[0.0; OFFSET_BINS]; 2];
        self.times = [[0.0; OFFSET_BINS]; 2];
    }

    pub fn clear(&mut self) {
        *self = Self::new(None);
    }

    pub fn running(&self) -> bool {
        self.state == State::Running
    }

    /// Adds one window's amplitude deviation in `plane` and body third `bin` over `dt_s`.
    pub fn add(&mut self, plane: usize, bin: usize, deviation_rad: f64, dt_s: f64) {
        self.sums[plane][bin] += deviation_rad * dt_s;
        self.times[plane][bin] += dt_s;
    }

    /// Advances the measurement by `dt_s`; returns true when it has just finished
    /// (its offsets are then the ones in use).
    pub fn advance(&mut self, dt_s: f64) -> bool {
        if !self.running() {
            return false;
        }
        self.elapsed_s += dt_s;
        if self.elapsed_s < self.duration_s {
            return false;
        }
        let mean = |p: usize, k: usize| {
            let t = self.times[p][k];
            if t > 0.0 {
                clamp_offset(self.sums[p][k] / t)
            } else {
                0.0
            }
        };
        self.offsets = FrictionOffset {
            lateral_rad: std::array::from_fn(|k| mean(0, k)),
            dorsal_rad: std::array::from_fn(|k| mean(1, k)),
        };
        self.state = State::Calibrated;
        true
    }

    /// The offsets in use (the previous ones while a measurement runs).
    pub fn offsets(&self) -> FrictionOffset {
        self.offsets
    }

    /// As reported in the `calibration` signal: 0 none, 1 running, 2 calibrated.
    pub fn state_code(&self) -> f64 {
        match self.state {
            State::None => 0.0,
            State::Running => 1.0,
            State::Calibrated => 2.0,
        }
    }

    /// 0..1 while running; 1 when calibrated, 0 without.
    pub fn progress(&self) -> f64 {
        match self.state {
            State::None => 0.0,
            State::Running => (self.elapsed_s / self.duration_s).min(1.0),
            State::Calibrated => 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_the_mean_deviation_per_plane_and_third() {
        let mut c = Calibration::new(None);
        assert_eq!(c.state_code(), 0.0);
        assert_eq!(c.start(f64::NAN), Err(CommandRefused::BadDuration));
        assert_eq!(c.start(0.0), Err(CommandRefused::BadDuration));
        c.start(1.0).unwrap();
        let mut finished = 0;
        for k in 0..1000 {
            c.add(0, 0, 0.1, 1e-3);
            c.add(0, 2, if k % 2 == 0 { -0.2 } else { 0.0 }, 1e-3);
            c.add(1, 1, 0.05, 1e-3);
            finished += usize::from(c.advance(1e-3));
            if k == 499 {
                assert!((c.progress() - 0.5).abs() < 1e-9);
            }
        }
        assert_eq!(finished, 1);
        assert_eq!(c.state_code(), 2.0);
        let o = c.offsets();
        assert!((o.lateral_rad[0] - 0.1).abs() < 1e-9, "{o:?}");
        assert_eq!(o.lateral_rad[1], 0.0, "no window there: 0");
        assert!((o.lateral_rad[2] + 0.1).abs() < 1e-9, "{o:?}");
        assert!((o.dorsal_rad[1] - 0.05).abs() < 1e-9, "{o:?}");
        c.clear();
        assert_eq!(c.offsets(), ZERO_OFFSET);
        assert_eq!(c.state_code(), 0.0);
    }
}
