//! One window's amplitude in one plane under directional compliance (SPEC §8): its
//! admittance with the mode's filter on the amplitude rate, its mean amplitude, its
//! absition, and the switching between NC, PDC and NDC. Pure and `Copy`.

use super::config::{Reference, Thresholds};
use crate::shape::admittance::AdmittanceGains;

/// The filter a window applies to its amplitude rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Every rate (nominal compliance).
    Nc,
    /// Only increases (`max(Ȧ, 0)`).
    Pdc,
    /// Only decreases (`min(Ȧ, 0)`).
    Ndc,
}

impl Mode {
    /// `f(Ȧ)`.
    pub fn filter(self, rate: f64) -> f64 {
        match self {
            Mode::Nc => rate,
            Mode::Pdc => rate.max(0.0),
            Mode::Ndc => rate.min(0.0),
        }
    }

    /// As reported: 0 NC, +1 PDC, −1 NDC.
    pub fn code(self) -> f64 {
        match self {
            Mode::Nc => 0.0,
            Mode::Pdc => 1.0,
            Mode::Ndc => -1.0,
        }
    }
}

/// A window's amplitude state in one plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneWindow {
    /// Deviation of the amplitude from nominal, rad, and its rate, rad/s.
    pub deviation: f64,
    pub rate: f64,
    /// Ā − A₀: the exponential mean of the deviation, rad.
    pub mean_deviation: f64,
    /// S: the running integral of `Ā − A₀ − c`, rad·s (from the crossed threshold while
    /// in PDC or NDC when the reference is the threshold).
    pub absition: f64,
    pub mode: Mode,
}

impl PlaneWindow {
    /// A window born at the head: nominal amplitude, zero absition, in `mode`.
    pub fn nominal(mode: Mode) -> Self {
        Self {
            deviation: 0.0,
            rate: 0.0,
            mean_deviation: 0.0,
            absition: 0.0,
            mode,
        }
    }

    /// Semi-implicit Euler of `M·δ̈ + B·δ̇ + K·(δ − δ_m) = F + τ_D` with the mode's filter
    /// on the rate: a filtered rate is the state's rate (no wind-up behind the filter),
    /// and the amplitude `nominal + δ` stays in the gains' range. `δ_m` is where the
    /// spring pulls in the window's mode: 0 in NC, `+shift` in PDC, `−shift` in NDC.
    pub fn step_amplitude(
        &mut self,
        g: &AdmittanceGains,
        force: f64,
        nominal: f64,
        shift: f64,
        dt_s: f64,
    ) {
        let rest = match self.mode {
            Mode::Nc => 0.0,
            Mode::Pdc => shift,
            Mode::Ndc => -shift,
        };
        let spring = g.stiffness * (self.deviation - rest);
        let accel = (force + g.bias_force - g.damping * self.rate - spring) / g.mass;
        self.rate = self.mode.filter(self.rate + accel * dt_s);
        self.deviation += self.rate * dt_s;
        let value = nominal + self.deviation;
        if value > g.max || value < g.min {
            self.deviation = value.clamp(g.min, g.max) - nominal;
            self.rate = 0.0;
        }
    }

    /// Advances the mean and the absition by `dt_s` with friction offset `offset`; with
    /// `switching`, changes the mode by the thresholds. Returns whether the mode changed.
    pub fn observe(
        &mut self,
        offset: f64,
        dt_s: f64,
        mean_time_s: f64,
        switching: Option<&Thresholds>,
    ) -> bool {
        let alpha = dt_s / (mean_time_s + dt_s);
        self.mean_deviation += alpha * (self.deviation - self.mean_deviation);
        self.absition += (self.mean_deviation - offset) * dt_s;
        let Some(t) = switching else {
            return false;
        };
        let rebase = |threshold: f64| match t.reference {
            Reference::Threshold => threshold,
            Reference::Zero => 0.0,
        };
        let s = self.absition;
        let next = match self.mode {
            Mode::Nc if s < t.low_rad_s => {
                self.absition -= rebase(t.low_rad_s);
                Mode::Pdc
            }
            Mode::Nc if s > t.high_rad_s => {
                self.absition -= rebase(t.high_rad_s);
                Mode::Ndc
            }
            Mode::Pdc if s >= 0.0 => Mode::Nc,
            Mode::Ndc if s <= 0.0 => Mode::Nc,
            m => m,
        };
        let changed = next != self.mode;
        self.mode = next;
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> AdmittanceGains {
        AdmittanceGains {
            mass: 1.0,
            damping: 6.0,
            stiffness: 4.0,
            min: 0.1,
            max: 1.2,
            bias_force: 0.0,
            max_rate: f64::INFINITY,
        }
    }

    const T: Thresholds = Thresholds {
        low_rad_s: -0.5,
        high_rad_s: 0.5,
        reference: Reference::Threshold,
        shift_rad: 0.0,
    };

    /// Steps `w` under `force(t)` for `seconds`, switching by `T`.
    fn run(w: &mut PlaneWindow, seconds: f64, switching: bool, force: impl Fn(f64) -> f64) {
        let dt = 1e-3;
        for k in 0..(seconds / dt) as usize {
            w.step_amplitude(&gains(), force(k as f64 * dt), 0.785, 0.0, dt);
            w.observe(0.0, dt, 1.5, switching.then_some(&T));
        }
    }

    #[test]
    fn the_filters_admit_one_direction_each() {
        // A push that opens the wave, then one that closes it, then none.
        let force = |t: f64| {
            if t < 2.0 {
                2.0
            } else if t < 4.0 {
                -2.0
            } else {
                0.0
            }
        };
        let mut nc = PlaneWindow::nominal(Mode::Nc);
        let mut pdc = PlaneWindow::nominal(Mode::Pdc);
        let mut ndc = PlaneWindow::nominal(Mode::Ndc);
        run(&mut nc, 2.0, false, force);
        run(&mut pdc, 2.0, false, force);
        run(&mut ndc, 2.0, false, force);
        assert!(nc.deviation > 0.3 && pdc.deviation > 0.3, "{nc:?} {pdc:?}");
        assert_eq!(ndc.deviation, 0.0, "NDC never opens");
        let pdc_high = pdc.deviation;
        // Closing push and release: NC follows, PDC holds what it gained (Fig. 3).
        for w in [&mut nc, &mut pdc, &mut ndc] {
            run(w, 6.0, false, |t| force(t + 2.0));
        }
        assert!(nc.deviation.abs() < 0.02, "NC returns to nominal: {nc:?}");
        assert!(
            pdc.deviation >= pdc_high - 1e-12,
            "PDC never closes: {pdc:?}"
        );
        assert!(
            ndc.deviation < -0.3,
            "NDC closed under the closing push: {ndc:?}"
        );
    }

    /// Steps `w` under `force(t)` from `t0` for `seconds`, switching by `T`; returns
    /// the times and new modes of its switches.
    fn switches(
        w: &mut PlaneWindow,
        t0: f64,
        seconds: f64,
        force: impl Fn(f64) -> f64,
    ) -> Vec<(f64, Mode)> {
        let dt = 1e-3;
        let mut out = Vec::new();
        for k in 0..(seconds / dt) as usize {
            let t = t0 + k as f64 * dt;
            w.step_amplitude(&gains(), force(t), 0.785, 0.0, dt);
            if w.observe(0.0, dt, 1.5, Some(&T)) {
                out.push((t, w.mode));
            }
        }
        out
    }

    /// The pegs a window passes push it both ways in turn.
    fn alternating(t: f64) -> f64 {
        2.0 * (std::f64::consts::TAU * t).sin()
    }

    #[test]
    fn a_squeezed_window_switches_to_pdc_and_back_to_nc_at_zero() {
        let mut w = PlaneWindow::nominal(Mode::Nc);
        // Squeezed flatter than nominal: the mean deviation is negative, S falls.
        let s = switches(&mut w, 0.0, 4.0, |_| -2.0);
        assert_eq!(s.len(), 1, "{s:?}");
        assert_eq!(s[0].1, Mode::Pdc);
        assert!(s[0].0 > 0.5, "{s:?}");
        // Then pushed both ways: PDC keeps every opening, so the mean rises above
        // nominal and the absition, measured from the threshold, returns to zero.
        let s = switches(&mut w, 4.0, 20.0, alternating);
        assert_eq!(s.first().map(|x| x.1), Some(Mode::Nc), "{s:?} {w:?}");
        // The same pushes in NC average out: no switch.
        let mut nc = PlaneWindow::nominal(Mode::Nc);
        assert!(
            switches(&mut nc, 0.0, 20.0, alternating).is_empty(),
            "{nc:?}"
        );
    }

    #[test]
    fn a_window_bent_further_switches_to_ndc_and_back_when_its_absition_returns() {
        let mut w = PlaneWindow::nominal(Mode::Nc);
        let s = switches(&mut w, 0.0, 4.0, |_| 2.0);
        assert_eq!(
            s.iter().map(|x| x.1).collect::<Vec<_>>(),
            [Mode::Ndc],
            "{w:?}"
        );
        // Still pushed open, harder than the spring pulls: NDC holds the amplitude
        // where it was (never opens further) and stays on.
        let held = w.deviation;
        assert!(switches(&mut w, 4.0, 2.0, |_| 2.0).is_empty());
        assert!(w.deviation <= held && w.absition > 0.0, "{w:?}");
        // Pushed both ways: only the closings are kept, the mean falls below nominal.
        let s = switches(&mut w, 6.0, 20.0, alternating);
        assert_eq!(s.first().map(|x| x.1), Some(Mode::Nc), "{s:?} {w:?}");
    }

    #[test]
    fn the_offset_is_subtracted_and_the_zero_reference_keeps_the_absition() {
        let mut w = PlaneWindow::nominal(Mode::Nc);
        w.deviation = 0.1;
        w.mean_deviation = 0.1;
        for _ in 0..1000 {
            w.observe(0.1, 1e-3, 1.5, None);
        }
        assert!(
            w.absition.abs() < 1e-12,
            "an offset equal to the mean: {w:?}"
        );
        let zero = Thresholds {
            reference: Reference::Zero,
            ..T
        };
        let mut w = PlaneWindow::nominal(Mode::Nc);
        w.absition = 0.49;
        w.mean_deviation = 0.2;
        w.deviation = 0.2;
        assert!(w.observe(0.0, 0.1, 1.5, Some(&zero)));
        assert_eq!(w.mode, Mode::Ndc);
        assert!(w.absition > 0.5, "runs on from where it was: {w:?}");
    }
}
