//! The ground's friction offset of the absition (SPEC §8): how far each body section's
//! amplitude sits from nominal while the snake runs on open ground, measured over a
//! few gait cycles per plane and section, on the operator's command
//! (`controller.calibrate`), and kept with the controller until cleared.

use super::config::{FrictionOffset, MAX_SECTIONS, SectionValues, clamp_offset};
use crate::controller_interface::CommandRefused;

/// Longest calibration accepted, s.
const MAX_DURATION_S: f64 = 3600.0;
/// Share of a calibration spent letting the shape settle before it measures.
pub const SETTLE_SHARE: f64 = 1.0 / 3.0;

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
    sections: usize,
    state: State,
    duration_s: f64,
    elapsed_s: f64,
    /// ∫ deviation dt and ∫ dt per plane and body section.
    sums: [[f64; MAX_SECTIONS]; 2],
    times: [[f64; MAX_SECTIONS]; 2],
}

/// No offset, for `sections` body sections.
pub fn zero_offset(sections: usize) -> FrictionOffset {
    FrictionOffset {
        lateral_rad: SectionValues::zeros(sections),
        dorsal_rad: SectionValues::zeros(sections),
    }
}

impl Calibration {
    /// Calibrated from a configuration's offsets, or uncalibrated (offset 0), for
    /// `sections` body sections.
    pub fn new(from_config: Option<FrictionOffset>, sections: usize) -> Self {
        Self {
            offsets: from_config.unwrap_or(zero_offset(sections)),
            sections,
            state: if from_config.is_some() {
                State::Calibrated
            } else {
                State::None
            },
            duration_s: 0.0,
            elapsed_s: 0.0,
            sums: [[0.0; MAX_SECTIONS]; 2],
            times: [[0.0; MAX_SECTIONS]; 2],
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
        self.sums = [[0.0; MAX_SECTIONS]; 2];
        self.times = [[0.0; MAX_SECTIONS]; 2];
    }

    pub fn clear(&mut self) {
        *self = Self::new(None, self.sections);
    }

    pub fn running(&self) -> bool {
        self.state == State::Running
    }

    /// Adds a section's amplitude deviation in `plane` over `dt_s`. The first
    /// [`SETTLE_SHARE`] of the measurement is not counted: the shape settles onto the
    /// ground's friction first (a drag that opens the wave does so over a few seconds).
    pub fn add(&mut self, plane: usize, section: usize, deviation_rad: f64, dt_s: f64) {
        if self.elapsed_s < SETTLE_SHARE * self.duration_s {
            return;
        }
        self.sums[plane][section] += deviation_rad * dt_s;
        self.times[plane][section] += dt_s;
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
        let plane = |p: usize| {
            let values: [f64; MAX_SECTIONS] = std::array::from_fn(|k| mean(p, k));
            SectionValues::from_slice(&values[..self.sections])
        };
        self.offsets = FrictionOffset {
            lateral_rad: plane(0),
            dorsal_rad: plane(1),
        };
        self.state = State::Calibrated;
        true
    }

    /// The offsets in use (the previous ones while a measurement runs).
    pub fn offsets(&self) -> FrictionOffset {
        self.offsets
    }

    /// Where it stands.
    pub fn state(&self) -> crate::controller_interface::CalibrationState {
        use crate::controller_interface::CalibrationState as S;
        match self.state {
            State::None => S::None,
            State::Running => S::Running,
            State::Calibrated => S::Calibrated,
        }
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
    fn measures_the_mean_deviation_per_plane_and_section() {
        let mut c = Calibration::new(None, 3);
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
        assert_eq!(o.lateral_rad.len(), 3);
        assert!((o.lateral_rad.get(0) - 0.1).abs() < 1e-9, "{o:?}");
        assert_eq!(o.lateral_rad.get(1), 0.0, "nothing measured there: 0");
        assert!((o.lateral_rad.get(2) + 0.1).abs() < 1e-9, "{o:?}");
        assert!((o.dorsal_rad.get(1) - 0.05).abs() < 1e-9, "{o:?}");
        c.clear();
        assert_eq!(c.offsets(), zero_offset(3));
        assert_eq!(c.state_code(), 0.0);
    }
}
