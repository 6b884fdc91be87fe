//! The sidewinding controller's **heading adjustment** (thesis §4.3.3, SPEC §7), pure
//! and with time as an argument: outside a dead-band around the nominal heading an
//! amplitude gradient along the body blends in and turns the body back; inside it the
//! gait goes straight, where "straight" is a learnt trim, because the plain gait drifts.

use std::f64::consts::TAU;

use serde::{Deserialize, Serialize};

use super::reversal::wrap_pi;

/// The amplitude factor of the taper `c` at normalised arc length `s` (0 at the head):
/// a gradient `1 + c·(1 − 2s)` along the body, head-heavy for c > 0, tail-heavy for
/// c < 0, the body's mean amplitude unchanged. Measured (`examples/sidewinding_turns.rs`,
/// docs/compliance.md): ±0.4 turns the body about 0.05 rad/s either way, 4× the gait's
/// own drift; growing one end only (a cone with its apex beyond the other) turns it a
/// tenth as much.
pub fn taper_factor(c: f64, s: f64) -> f64 {
    1.0 + c * (1.0 - 2.0 * s)
}

/// The heading adjustment's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadingConfig {
    pub enabled: bool,
    /// Half-width of the dead-band around the nominal heading, rad: beyond it the body
    /// turns back.
    pub deadband_rad: f64,
    /// The turn goes on until the heading is this close to the nominal, rad
    /// (≤ `deadband_rad`): it stops near the nominal, not at the band's edge.
    #[serde(default = "HeadingConfig::default_settle")]
    pub settle_rad: f64,
    /// The gradient's size while turning ([`taper_factor`]), ≤ 0.8; it bounds the trim
    /// too, so no joint's amplitude grows by more than `1 + turn_taper`.
    pub turn_taper: f64,
    /// How fast the taper blends in and out, per second.
    pub taper_rate_per_s: f64,
    /// Which way a positive (head-heavy) taper turns the body's heading while β is in
    /// its 0 well: +1 (counter-clockwise) or −1. Measured in the physics (clockwise,
    /// `physics_tests`; β at π mirrors it).
    pub turn_sign: f64,
    /// How much of the heading's rate over a straight gait cycle the trim corrects,
    /// taper per rad/s (0 turns the trim off). The physics turns about 0.11 rad/s per
    /// unit of taper, so 4.5 corrects half the drift each cycle.
    #[serde(default = "HeadingConfig::default_trim_gain")]
    pub trim_gain: f64,
    /// Largest |trim|, ≤ `turn_taper`.
    #[serde(default = "HeadingConfig::default_trim_max")]
    pub trim_max: f64,
    /// The head leads: the heading held is the nominal turned this much towards the
    /// direction of travel (mirrored when the gait is reversed), rad. Among obstacles
    /// the lateral wave pushes on them as slithering's does and the body also goes
    /// head first along its axis; a head turned forward makes that axial motion carry
    /// it across instead of sideways (docs/measurements/crossing.md, "Sidewinding goes
    /// head first among obstacles"). 0 holds the nominal itself.
    #[serde(default)]
    pub lead_rad: f64,
}

impl HeadingConfig {
    pub const DEFAULT: Self = Self {
        enabled: true,
        deadband_rad: 0.35,
        settle_rad: 0.1,
        turn_taper: 0.4,
        taper_rate_per_s: 0.2,
        turn_sign: -1.0,
        trim_gain: 4.5,
        trim_max: 0.25,
        lead_rad: 0.0,
    };

    fn default_settle() -> f64 {
        Self::DEFAULT.settle_rad
    }

    fn default_trim_gain() -> f64 {
        Self::DEFAULT.trim_gain
    }

    fn default_trim_max() -> f64 {
        Self::DEFAULT.trim_max
    }
}

/// The taper now, and what it has learnt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingAdjust {
    pub taper: f64,
    /// The taper that goes straight, in the 0 well's sense (the reversed gait drifts
    /// and turns mirrored, so the same trim serves both).
    pub trim: f64,
    /// Turning back toward the nominal (from leaving the dead-band until settled).
    pub turning: bool,
    /// The gait period, s: the trim compares whole cycles, so the sway within a cycle
    /// cancels.
    cycle_s: f64,
    /// The straight stretch's current cycle: ∫error dt and its length.
    sum: f64,
    elapsed: f64,
    /// The mean error over the previous whole straight cycle.
    last_mean: Option<f64>,
    well: f64,
}

impl Default for HeadingAdjust {
    fn default() -> Self {
        Self::new(TAU)
    }
}

impl HeadingAdjust {
    /// The gait's period is now `cycle_s` (a followed change of speed); the trim and
    /// the cycle under way stay.
    pub fn set_cycle(&mut self, cycle_s: f64) {
        if cycle_s.is_finite() && cycle_s > 0.0 {
            self.cycle_s = cycle_s;
        }
    }

    /// At rest, for a gait of period `cycle_s`.
    pub fn new(cycle_s: f64) -> Self {
        Self {
            taper: 0.0,
            trim: 0.0,
            turning: false,
            cycle_s: if cycle_s.is_finite() && cycle_s > 0.0 {
                cycle_s
            } else {
                TAU
            },
            sum: 0.0,
            elapsed: 0.0,
            last_mean: None,
            well: 0.0,
        }
    }

    /// `error_rad`: heading minus the nominal (for the well β is in), wrapped; `well`:
    /// 0 or π. Without an estimate (`None`) it goes straight on its trim.
    pub fn step(&mut self, c: &HeadingConfig, dt_s: f64, error_rad: Option<f64>, well: f64) {
        let mirror = if well == 0.0 { 1.0 } else { -1.0 };
        let error = error_rad.filter(|_| c.enabled);
        if let Some(e) = error {
            if e.abs() > c.deadband_rad {
                self.turning = true;
            } else if e.abs() < c.settle_rad {
                self.turning = false;
            }
        } else {
            self.turning = false;
        }
        let target = match error {
            // Turn against the error: the heading must fall when e > 0.
            Some(e) if self.turning => -e.signum() * c.turn_sign * mirror * c.turn_taper,
            _ => self.trim,
        };
        let step = c.taper_rate_per_s * dt_s;
        self.taper += (target - self.taper).clamp(-step, step);
        let straight = !self.turning && (self.taper - self.trim).abs() < 1e-9;
        match error {
            Some(e) if straight && well == self.well => self.learn(c, dt_s, e, mirror),
            _ => self.restart_learning(well),
        }
    }

    /// One straight step: at the end of each whole cycle, the heading's rate since the
    /// previous one corrects the trim.
    fn learn(&mut self, c: &HeadingConfig, dt_s: f64, e: f64, mirror: f64) {
        self.sum += e * dt_s;
        self.elapsed += dt_s;
        if self.elapsed < self.cycle_s {
            return;
        }
        let mean = self.sum / self.elapsed;
        if let Some(last) = self.last_mean {
            let rate = wrap_pi(mean - last) / self.elapsed;
            let fix = c.trim_gain * rate * c.turn_sign * mirror;
            self.trim = (self.trim - fix).clamp(-c.trim_max, c.trim_max);
        }
        self.last_mean = Some(mean);
        (self.sum, self.elapsed) = (0.0, 0.0);
    }

    /// Turning, blending, no estimate or a new well: the next straight cycle starts
    /// afresh.
    fn restart_learning(&mut self, well: f64) {
        (self.sum, self.elapsed, self.last_mean) = (0.0, 0.0, None);
        self.well = well;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn the_taper_blends_in_outside_the_deadband_and_out_inside() {
        let c = HeadingConfig {
            turn_sign: 1.0,
            trim_gain: 0.0,
            ..HeadingConfig::DEFAULT
        };
        let mut a = HeadingAdjust::default();
        for _ in 0..1000 {
            a.step(&c, 1e-3, Some(0.2), 0.0);
        }
        assert_eq!(a.taper, 0.0, "inside the dead-band");
        for _ in 0..1000 {
            a.step(&c, 1e-3, Some(0.8), 0.0);
        }
        assert!((a.taper + 0.2).abs() < 1e-9, "1 s at 0.2/s: {}", a.taper);
        for _ in 0..5000 {
            a.step(&c, 1e-3, Some(0.8), 0.0);
        }
        assert!((a.taper + c.turn_taper).abs() < 1e-9);
        // Back inside the dead-band but not yet settled: it keeps turning.
        for _ in 0..1000 {
            a.step(&c, 1e-3, Some(0.2), 0.0);
        }
        assert!(a.turning && (a.taper + c.turn_taper).abs() < 1e-9);
        // Reversed, the same error turns with the opposite taper.
        let mut r = HeadingAdjust::default();
        for _ in 0..5000 {
            r.step(&c, 1e-3, Some(0.8), PI);
        }
        assert!((r.taper - c.turn_taper).abs() < 1e-9);
        // Settled, or no estimate: straight again, smoothly.
        for _ in 0..1000 {
            a.step(&c, 1e-3, None, 0.0);
        }
        assert!(!a.turning);
        assert!((a.taper + c.turn_taper - 0.2).abs() < 1e-9);
        for _ in 0..1000 {
            a.step(&c, 1e-3, Some(0.05), 0.0);
        }
        assert!((a.taper + c.turn_taper - 0.4).abs() < 1e-9);
    }

    /// A body that drifts by itself at `drift` rad/s, sways ±0.05 rad within a cycle and
    /// turns `gain` rad/s per unit of taper (the physics' figures, turn sign −1), seen
    /// through the controller's 1 s low-pass: the trim learns the taper that cancels
    /// the drift, in both wells, and the heading settles inside the dead-band.
    #[test]
    fn the_trim_cancels_a_steady_drift() {
        let c = HeadingConfig::DEFAULT;
        let (drift, gain) = (-0.013, 0.11 * c.turn_sign);
        for well in [0.0, PI] {
            let mirror = if well == 0.0 { 1.0 } else { -1.0 };
            let mut a = HeadingAdjust::default();
            let (mut h, mut seen) = (0.0_f64, 0.0_f64);
            let mut worst: f64 = 0.0;
            for k in 0..300_000 {
                let t = k as f64 * 1e-3;
                let sway = 0.05 * t.sin();
                seen += (h + sway - seen) * 1e-3;
                a.step(&c, 1e-3, Some(seen), well);
                h += mirror * (drift + gain * a.taper) * 1e-3;
                if t > 150.0 {
                    worst = worst.max(h.abs());
                }
            }
            let straight = -drift / gain;
            let why = format!("{well}: trim {} vs {straight}, worst {worst}", a.trim);
            assert!((a.trim - straight).abs() < 0.02, "{why}");
            assert!(worst < c.deadband_rad, "{why}");
        }
        // Turning, the trim does not learn.
        let mut a = HeadingAdjust::default();
        for k in 0..100_000 {
            a.step(&c, 1e-3, Some(1.0 - k as f64 * 1e-6), 0.0);
        }
        assert_eq!(a.trim, 0.0);
        assert!((a.taper.abs() - c.turn_taper).abs() < 1e-9);
    }

    #[test]
    fn the_gradient_keeps_the_mean_amplitude() {
        let n = 17;
        for c in [-0.4, 0.3, 0.8] {
            let mean = (0..=n)
                .map(|k| taper_factor(c, k as f64 / n as f64))
                .sum::<f64>()
                / (n + 1) as f64;
            assert!((mean - 1.0).abs() < 1e-12, "{c}: {mean}");
            assert!((taper_factor(c, 0.0) - (1.0 + c)).abs() < 1e-12);
        }
    }
}
