//! Directional compliance's two pieces of state (SPEC §8): a travelling window's
//! amplitude, whose admittance passes the amplitude rate through its mode's filter,
//! and a body section's absition, which chooses the mode (NC, PDC, NDC). Pure and
//! `Copy`.

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

/// A travelling window's amplitude in one plane: its deviation from nominal and its
/// rate, stepped through the filter of the mode it is given (its section's).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AmplitudeState {
    /// Deviation of the amplitude from nominal, rad, and its rate, rad/s.
    pub deviation: f64,
    pub rate: f64,
}

impl AmplitudeState {
    /// Semi-implicit Euler of `M·δ̈ + B·δ̇ + K·(δ − δ_m) = F + τ_D` with `mode`'s filter
    /// on the rate: a filtered rate is the state's rate (no wind-up behind the filter),
    /// and the amplitude `nominal + δ` stays in the gains' range. `δ_m` is where the
    /// spring pulls in the mode: 0 in NC, `+shift` in PDC, `−shift` in NDC.
    pub fn step(
        &mut self,
        g: &AdmittanceGains,
        mode: Mode,
        force: f64,
        nominal: f64,
        shift: f64,
        dt_s: f64,
    ) {
        let rest = match mode {
            Mode::Nc => 0.0,
            Mode::Pdc => shift,
            Mode::Ndc => -shift,
        };
        let spring = g.stiffness * (self.deviation - rest);
        let accel = (force + g.bias_force - g.damping * self.rate - spring) / g.mass;
        self.rate = mode
            .filter(self.rate + accel * dt_s)
            .clamp(-g.max_rate, g.max_rate);
        self.deviation += self.rate * dt_s;
        let value = nominal + self.deviation;
        if value > g.max || value < g.min {
            self.deviation = value.clamp(g.min, g.max) - nominal;
            self.rate = 0.0;
        }
    }
}

/// A body section's absition in one plane and the mode it sets (SPEC §8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Absition {
    /// S: the running integral of `Ā − A₀ − c`, rad·s (from the crossed threshold while
    /// in PDC or NDC when the reference is the threshold).
    pub absition: f64,
    pub mode: Mode,
    /// Time since the mode last changed, s.
    pub in_mode_s: f64,
}

/// How one step of the absition is weighed (issue 26, point 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weighing {
    /// How still the section is, 0..=1: the share of `Ā − A₀ − c` that accumulates;
    /// the rest of the step the absition leaks (1: the reference's plain integral).
    pub still: f64,
    /// The leak's time constant, s (infinite: no leak).
    pub leak_s: f64,
    /// Longest stay in PDC or NDC, s (then NC with zero absition; infinite: no limit).
    pub max_dwell_s: f64,
}

impl Weighing {
    /// The reference's plain integral: no leak, no dwell limit.
    pub const PLAIN: Weighing = Weighing {
        still: 1.0,
        leak_s: f64::INFINITY,
        max_dwell_s: f64::INFINITY,
    };
}

impl Absition {
    /// Zero absition, in `mode`.
    pub fn new(mode: Mode) -> Self {
        Self {
            absition: 0.0,
            mode,
            in_mode_s: 0.0,
        }
    }

    /// Advances the absition by `dt_s` with the mean deviation `mean_deviation` (`Ā −
    /// A₀`) and friction offset `offset`, weighed by `w`; with `switching`, changes the
    /// mode by the thresholds. Returns whether the mode changed.
    pub fn observe(
        &mut self,
        mean_deviation: f64,
        offset: f64,
        dt_s: f64,
        w: &Weighing,
        switching: Option<&Thresholds>,
    ) -> bool {
        let still = w.still.clamp(0.0, 1.0);
        let leak = (1.0 - still) * self.absition / w.leak_s;
        self.absition += (still * (mean_deviation - offset) - leak) * dt_s;
        self.in_mode_s += dt_s;
        let Some(t) = switching else {
            return false;
        };
        let rebase = |threshold: f64| match t.reference {
            Reference::Threshold => threshold,
            Reference::Zero => 0.0,
        };
        let s = self.absition;
        let expired = self.in_mode_s >= w.max_dwell_s;
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
            Mode::Pdc | Mode::Ndc if expired => {
                self.absition = 0.0;
                Mode::Nc
            }
            m => m,
        };
        let changed = next != self.mode;
        if changed {
            self.in_mode_s = 0.0;
        }
        self.mode = next;
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controllers::directional_compliance::sections::Boxcar;

    /// A window that is its own section (the old per-window state, for these tests):
    /// its amplitude, its mean over 1.5 s and its absition.
    #[derive(Debug, Clone, Copy)]
    struct PlaneWindow {
        amplitude: AmplitudeState,
        mean: Boxcar,
        state: Absition,
    }

    impl PlaneWindow {
        fn nominal(mode: Mode) -> Self {
            Self {
                amplitude: AmplitudeState::default(),
                mean: Boxcar::new(1.5),
                state: Absition::new(mode),
            }
        }

        fn step_amplitude(&mut self, g: &AdmittanceGains, force: f64, nominal: f64, dt: f64) {
            self.amplitude
                .step(g, self.state.mode, force, nominal, 0.0, dt);
        }

        fn observe(&mut self, offset: f64, dt: f64, switching: Option<&Thresholds>) -> bool {
            self.mean.add(self.amplitude.deviation, dt);
            self.state
                .observe(self.mean.mean(), offset, dt, &Weighing::PLAIN, switching)
        }
    }

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
            w.step_amplitude(&gains(), force(k as f64 * dt), 0.785, dt);
            w.observe(0.0, dt, switching.then_some(&T));
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
        assert!(
            nc.amplitude.deviation > 0.3 && pdc.amplitude.deviation > 0.3,
            "{nc:?} {pdc:?}"
        );
        assert_eq!(ndc.amplitude.deviation, 0.0, "NDC never opens");
        let pdc_high = pdc.amplitude.deviation;
        // Closing push and release: NC follows, PDC holds what it gained (Fig. 3).
        for w in [&mut nc, &mut pdc, &mut ndc] {
            run(w, 6.0, false, |t| force(t + 2.0));
        }
        assert!(
            nc.amplitude.deviation.abs() < 0.02,
            "NC returns to nominal: {nc:?}"
        );
        assert!(
            pdc.amplitude.deviation >= pdc_high - 1e-12,
            "PDC never closes: {pdc:?}"
        );
        assert!(
            ndc.amplitude.deviation < -0.3,
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
            w.step_amplitude(&gains(), force(t), 0.785, dt);
            if w.observe(0.0, dt, Some(&T)) {
                out.push((t, w.state.mode));
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
        let held = w.amplitude.deviation;
        assert!(switches(&mut w, 4.0, 2.0, |_| 2.0).is_empty());
        assert!(
            w.amplitude.deviation <= held && w.state.absition > 0.0,
            "{w:?}"
        );
        // Pushed both ways: only the closings are kept, the mean falls below nominal.
        let s = switches(&mut w, 6.0, 20.0, alternating);
        assert_eq!(s.first().map(|x| x.1), Some(Mode::Nc), "{s:?} {w:?}");
    }

    #[test]
    fn the_offset_is_subtracted_and_the_zero_reference_keeps_the_absition() {
        let mut a = Absition::new(Mode::Nc);
        for _ in 0..1000 {
            a.observe(0.1, 0.1, 1e-3, &Weighing::PLAIN, None);
        }
        assert!(
            a.absition.abs() < 1e-12,
            "an offset equal to the mean: {a:?}"
        );
        let zero = Thresholds {
            reference: Reference::Zero,
            ..T
        };
        let mut a = Absition::new(Mode::Nc);
        a.absition = 0.49;
        assert!(a.observe(0.2, 0.0, 0.1, &Weighing::PLAIN, Some(&zero)));
        assert_eq!(a.mode, Mode::Ndc);
        assert!(a.absition > 0.5, "runs on from where it was: {a:?}");
    }

    /// A section being moved past obstacles (still 0) forgets its absition with the
    /// leak's time constant instead of accumulating its offset; a still one
    /// accumulates all of it.
    #[test]
    fn a_moving_section_leaks_and_a_still_one_accumulates() {
        let moving = Weighing {
            still: 0.0,
            leak_s: 2.0,
            max_dwell_s: f64::INFINITY,
        };
        let mut a = Absition::new(Mode::Nc);
        a.absition = -1.0;
        for _ in 0..2000 {
            a.observe(-0.4, 0.0, 1e-3, &moving, None);
        }
        let expected = -(-1.0f64).exp(); // 2 s at a 2 s time constant
        assert!((a.absition - expected).abs() < 1e-3, "{a:?}");
        let still = Weighing {
            still: 1.0,
            ..moving
        };
        let mut a = Absition::new(Mode::Nc);
        for _ in 0..2000 {
            a.observe(-0.4, 0.0, 1e-3, &still, None);
        }
        assert!((a.absition + 0.8).abs() < 1e-9, "{a:?}");
    }

    /// A section PDC could not free returns to NC after the longest stay, with zero
    /// absition; without a limit it stays.
    #[test]
    fn a_directional_section_returns_after_its_longest_stay() {
        let dwell = Weighing {
            max_dwell_s: 3.0,
            ..Weighing::PLAIN
        };
        for (w, back) in [(dwell, true), (Weighing::PLAIN, false)] {
            let mut a = Absition::new(Mode::Nc);
            let mut changes = Vec::new();
            for k in 0..10_000usize {
                if a.observe(-0.5, 0.0, 1e-3, &w, Some(&T)) {
                    changes.push((k, a.mode));
                }
            }
            assert_eq!(changes[0].1, Mode::Pdc, "{changes:?}");
            if back {
                // PDC at 1 s (0.5 rad·s), NC 3 s later, PDC again 1 s after that.
                assert_eq!(changes[1].1, Mode::Nc, "{changes:?}");
                assert!(
                    (changes[1].0 - changes[0].0).abs_diff(3000) <= 1,
                    "{changes:?}"
                );
                assert_eq!(changes.len(), 5, "{changes:?}");
            } else {
                assert_eq!(changes.len(), 1, "{changes:?}");
            }
        }
    }
}
