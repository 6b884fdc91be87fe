//! The sidewinding controller's **direction reversal** (thesis §4.3.3, SPEC §7), pure
//! and with time as an argument: the dorsal offset β follows a bistable system driven
//! by the heading, so a body turned round reverses its gait.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use serde::{Deserialize, Serialize};

pub use crate::num::wrap_pi;

/// The reversal's gains.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReversalConfig {
    pub enabled: bool,
    /// `K_b` of `β̇ = K_b·(β − 0)(β − π/2)(β − π) + K_h·(h − β)`, 1/(rad²·s); negative,
    /// so 0 and π are the stable wells and π/2 the hill.
    pub k_b: f64,
    /// `K_h`, 1/s: how hard the heading drags β.
    pub k_h: f64,
    /// Largest |β̇|, rad/s: a jump of the heading estimate cannot jump the wave.
    pub max_rate_rad_s: f64,
}

impl ReversalConfig {
    /// Switches when the heading is about 110° off (`K_h·(h − 0.66) = 1.49·|K_b|`, the
    /// hill's steepest pull) and crosses in about a second; tuned in simulation
    /// (docs/compliance.md, "Sidewinding").
    pub const DEFAULT: Self = Self {
        enabled: true,
        k_b: -1.66,
        k_h: 2.0,
        max_rate_rad_s: 2.0,
    };

    /// Whether β has two stable states near the hill: the heading's pull `K_h` is
    /// weaker than the hill's push there, `|K_b|·π²/4` at π/2 (4.1 with `K_b` −1.66).
    /// Beyond it β has one equilibrium for every heading: it follows the heading
    /// through a step about 90° that is the steeper the nearer `K_h` is to the bound,
    /// and comes back when the heading does.
    pub fn bistable(&self) -> bool {
        self.k_h < self.k_b.abs() * PI * PI / 4.0
    }

    /// The heading |h − well| beyond which β leaves its well (the hill's pull is
    /// `|K_b|·1.49` at β ≈ 0.66 rad from the well); meaningful only when
    /// [`Self::bistable`] (otherwise β leaves no well: it follows).
    pub fn switch_heading_rad(&self) -> f64 {
        const STEEPEST_AT: f64 = FRAC_PI_2 - FRAC_PI_2 / 1.732_050_807_568_877_2;
        let pull = (self.k_b * STEEPEST_AT * (STEEPEST_AT - FRAC_PI_2) * (STEEPEST_AT - PI)).abs();
        STEEPEST_AT + pull / self.k_h
    }
}

/// β's drift from the bistable potential at `beta` (any angle): the SPEC's cubic on
/// [0, π] (zero at both ends), repeated every π. So β is modular (the turn can repeat):
/// wells at 0 and π, hills of the same height at π/2 and 3π/2, and the drift is
/// continuous everywhere.
fn well_drift(k_b: f64, beta: f64) -> f64 {
    let b = beta.rem_euclid(PI);
    k_b * b * (b - FRAC_PI_2) * (b - PI)
}

/// The state of β.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// β, rad, in [0, 2π).
    pub beta_rad: f64,
    /// Completed crossings from one well to the other.
    pub reversals: u64,
    well: f64,
}

impl Default for Reversal {
    fn default() -> Self {
        Self {
            beta_rad: 0.0,
            reversals: 0,
            well: 0.0,
        }
    }
}

impl Reversal {
    /// The well β sits in (or last sat in): 0 or π.
    pub fn well(&self) -> f64 {
        self.well
    }

    /// Advances by `dt_s` with the heading `h_rad` (relative to the nominal direction);
    /// `None` (no valid estimate) holds β where it is.
    pub fn step(&mut self, c: &ReversalConfig, dt_s: f64, h_rad: Option<f64>) {
        let Some(h) = h_rad.filter(|_| c.enabled) else {
            return;
        };
        let rate = well_drift(c.k_b, self.beta_rad) + c.k_h * wrap_pi(h - self.beta_rad);
        let rate = rate.clamp(-c.max_rate_rad_s, c.max_rate_rad_s);
        self.beta_rad = (self.beta_rad + rate * dt_s).rem_euclid(TAU);
        // In a well once within 0.2 rad of it (past the hill, the cubic does the rest).
        let near = if wrap_pi(self.beta_rad).abs() < 0.2 {
            Some(0.0)
        } else if wrap_pi(self.beta_rad - PI).abs() < 0.2 {
            Some(PI)
        } else {
            None
        };
        if let Some(w) = near
            && w != self.well
        {
            self.well = w;
            self.reversals += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(r: &mut Reversal, h: f64, seconds: f64) {
        let c = ReversalConfig::DEFAULT;
        for _ in 0..(seconds * 1000.0) as usize {
            r.step(&c, 1e-3, Some(h));
        }
    }

    #[test]
    fn small_heading_noise_leaves_beta_in_its_well() {
        let mut r = Reversal::default();
        let c = ReversalConfig::DEFAULT;
        // ±60° of heading, swinging at the gait's frequency, for a minute.
        for k in 0..60_000 {
            let h = 1.05 * (k as f64 * 1e-3).sin();
            r.step(&c, 1e-3, Some(h));
            assert!(
                wrap_pi(r.beta_rad).abs() < 1.0,
                "β left its well: {}",
                r.beta_rad
            );
        }
        assert_eq!(r.reversals, 0);
        assert!(c.switch_heading_rad() > 1.5 && c.switch_heading_rad() < 2.2);
    }

    #[test]
    fn a_turned_body_drags_beta_over_the_hill_and_it_repeats() {
        let mut r = Reversal::default();
        run(&mut r, PI, 6.0);
        assert!(wrap_pi(r.beta_rad - PI).abs() < 0.05, "{}", r.beta_rad);
        assert_eq!((r.reversals, r.well()), (1, PI));
        // Turned round again (heading back at 0, i.e. 2π): β wraps on to 2π ≡ 0.
        run(&mut r, 0.0, 6.0);
        assert!(wrap_pi(r.beta_rad).abs() < 0.05, "{}", r.beta_rad);
        assert_eq!((r.reversals, r.well()), (2, 0.0));
        // Held headings just short of the switch stay put.
        let mut r = Reversal::default();
        run(
            &mut r,
            ReversalConfig::DEFAULT.switch_heading_rad() - 0.15,
            10.0,
        );
        assert_eq!(r.reversals, 0, "{}", r.beta_rad);
        // No estimate: β holds.
        let before = r.beta_rad;
        r.step(&ReversalConfig::DEFAULT, 1.0, None);
        assert_eq!(r.beta_rad, before);
    }

    /// β's state after `seconds` at the heading `h` with `c`, from `r`.
    fn settle(c: &ReversalConfig, r: &mut Reversal, h: f64, seconds: f64) -> f64 {
        for _ in 0..(seconds * 1000.0) as usize {
            r.step(c, 1e-3, Some(h));
        }
        wrap_pi(r.beta_rad)
    }

    /// The default is bistable: a heading between the two switches leaves β where it
    /// came from (hysteresis). `K_h` 6 (the sidewinding presets') is not: β follows the
    /// heading, past π/2 only once the heading is, and back when the heading comes back.
    #[test]
    fn past_the_bound_beta_follows_the_heading_without_hysteresis() {
        let bi = ReversalConfig::DEFAULT;
        assert!(bi.bistable());
        let (mut up, mut down) = (Reversal::default(), Reversal::default());
        settle(&bi, &mut down, PI, 6.0);
        let h = 1.5; // between π − 1.90 and 1.90
        let (u, d) = (
            settle(&bi, &mut up, h, 20.0),
            settle(&bi, &mut down, h, 20.0),
        );
        assert!(
            u.abs() < 0.6 && (d - PI).abs() < 0.6,
            "hysteresis: {u} / {d}"
        );

        let follow = ReversalConfig {
            k_h: 6.0,
            ..ReversalConfig::DEFAULT
        };
        assert!(!follow.bistable());
        let (mut up, mut down) = (Reversal::default(), Reversal::default());
        settle(&follow, &mut down, PI, 6.0);
        let (u, d) = (
            settle(&follow, &mut up, h, 20.0),
            settle(&follow, &mut down, h, 20.0),
        );
        assert!((u - d).abs() < 1e-3, "one equilibrium: {u} / {d}");
        assert!((u - FRAC_PI_2).abs() < 0.3, "near the hill: {u}");
        // Off the step it stays near a well, short of counting a reversal: a heading
        // of 0.6 rad moves β by about half of it.
        let mut r = Reversal::default();
        let b = settle(&follow, &mut r, 0.6, 20.0);
        assert!(b > 0.2 && b < 0.4, "{b}");
        assert_eq!(r.reversals, 0);
        // Turned round, it reverses; turned back, it comes back.
        settle(&follow, &mut r, PI, 6.0);
        assert_eq!((r.reversals, r.well()), (1, PI));
        let b = settle(&follow, &mut r, 0.0, 6.0);
        assert!(b.abs() < 0.05, "{b}");
        assert_eq!((r.reversals, r.well()), (2, 0.0));
    }

    #[test]
    fn beta_never_jumps() {
        let mut r = Reversal::default();
        let c = ReversalConfig::DEFAULT;
        let mut last = r.beta_rad;
        for k in 0..20_000 {
            // A heading that jumps about wildly.
            let h = if (k / 700) % 2 == 0 { 3.0 } else { -2.5 };
            r.step(&c, 1e-3, Some(h));
            let d = wrap_pi(r.beta_rad - last).abs();
            assert!(d <= c.max_rate_rad_s * 1e-3 + 1e-12, "{d}");
            last = r.beta_rad;
        }
    }

    #[test]
    fn wrap_is_into_minus_pi_pi() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(-3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(0.5) - 0.5).abs() < 1e-12);
        assert!((wrap_pi(TAU - 0.5) + 0.5).abs() < 1e-12);
    }
}
