//! The mean direction of an angle over the last gait cycle: [`SLOTS`] samples a
//! cycle apart by `cycle / SLOTS`, averaged as unit vectors (so ±π does not cancel).
//! A fixed array: pushing never allocates.

/// Samples per cycle.
pub const SLOTS: usize = 64;

#[derive(Debug, Clone)]
pub struct CycleMean {
    /// Time between samples, s.
    every_s: f64,
    /// Time since the last sample, s (a sample is taken at the first push).
    since_s: f64,
    cos: [f64; SLOTS],
    sin: [f64; SLOTS],
    next: usize,
    filled: usize,
}

impl CycleMean {
    /// For a cycle of `cycle_s` seconds (> 0).
    pub fn new(cycle_s: f64) -> Self {
        Self {
            every_s: cycle_s / SLOTS as f64,
            since_s: f64::INFINITY,
            cos: [0.0; SLOTS],
            sin: [0.0; SLOTS],
            next: 0,
            filled: 0,
        }
    }

    /// The cycle is now `cycle_s` long (> 0): samples are taken that far apart from
    /// now on; those taken keep their weight until they age out.
    pub fn set_cycle(&mut self, cycle_s: f64) {
        self.every_s = cycle_s / SLOTS as f64;
    }

    /// The angle `angle_rad` after `dt_s` more seconds.
    pub fn push(&mut self, dt_s: f64, angle_rad: f64) {
        self.since_s += dt_s;
        if self.since_s < self.every_s {
            return;
        }
        self.since_s = 0.0;
        self.cos[self.next] = angle_rad.cos();
        self.sin[self.next] = angle_rad.sin();
        self.next = (self.next + 1) % SLOTS;
        self.filled = (self.filled + 1).min(SLOTS);
    }

    /// The mean direction of the samples so far (up to a cycle), rad; `None` before
    /// the first or when they cancel.
    pub fn mean(&self) -> Option<f64> {
        let n = self.filled;
        let (c, s) = (
            self.cos[..n].iter().sum::<f64>(),
            self.sin[..n].iter().sum::<f64>(),
        );
        (n > 0 && c.hypot(s) > 1e-9 * n as f64).then(|| s.atan2(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_sway_about_a_direction_averages_to_it_across_the_cut() {
        let mut m = CycleMean::new(1.0);
        assert_eq!(m.mean(), None);
        // A sway of ±0.4 rad about π over exactly one cycle, sampled at 1 kHz.
        for k in 0..2000 {
            let t = k as f64 * 1e-3;
            m.push(1e-3, PI + 0.4 * (std::f64::consts::TAU * t).sin());
        }
        let mean = m.mean().unwrap();
        assert!(crate::num::wrap_pi(mean - PI).abs() < 0.02, "{mean}");
    }

    #[test]
    fn it_forgets_what_is_older_than_a_cycle() {
        let mut m = CycleMean::new(0.5);
        for _ in 0..1000 {
            m.push(1e-3, 0.0);
        }
        for _ in 0..600 {
            m.push(1e-3, 1.0);
        }
        assert!((m.mean().unwrap() - 1.0).abs() < 1e-9);
    }
}
