//! Admittance in shape space (SPEC §3), one parameter at a time:
//! `M·δ̈ + B·δ̇ + K·δ = s·F + τ_D` for the deviation `δ = σ − σ₀(t)` from the nominal
//! value. For a constant nominal this is the SPEC's equation; for the temporal phase,
//! whose nominal moves (`Ω₀ = ωT·t`), it makes damping act on the deviation's rate, so
//! an unforced wave runs at ωT instead of lagging by `B·ωT/K`.

use crate::controller_interface::config::{ConfigError, check_range};
use crate::num::Num;

/// Compliant (`+1`: the shape gives way to the force) or anti-compliant (`−1`: it
/// pushes back).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdmittanceSign {
    Compliant,
    AntiCompliant,
}

impl AdmittanceSign {
    /// `s` in the admittance: +1 or −1.
    pub fn factor(self) -> f64 {
        match self {
            AdmittanceSign::Compliant => 1.0,
            AdmittanceSign::AntiCompliant => -1.0,
        }
    }
}

/// Virtual mass, damping and stiffness of one parameter, its range and an optional
/// constant virtual force.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdmittanceGains {
    pub mass: f64,
    pub damping: f64,
    pub stiffness: f64,
    /// Range of σ (absolute, not of the deviation). Infinite bounds are allowed
    /// (`null` in JSON).
    #[serde(
        serialize_with = "crate::controller_interface::config::bound::serialize",
        deserialize_with = "crate::controller_interface::config::bound::lower"
    )]
    pub min: f64,
    #[serde(
        serialize_with = "crate::controller_interface::config::bound::serialize",
        deserialize_with = "crate::controller_interface::config::bound::upper"
    )]
    pub max: f64,
    /// τ_D, added to the force.
    #[serde(default)]
    pub bias_force: f64,
    /// Fastest the parameter may change, its unit per second (`null` or absent:
    /// unbounded). The joints follow a parameter at `∂θ/∂σ · σ̇`: an anti-compliant
    /// parameter against a stiff contact runs away (positive feedback), and this keeps
    /// that run within what the motors can follow (docs/compliance.md, "Speed budget").
    #[serde(
        default = "unbounded",
        serialize_with = "crate::controller_interface::config::bound::serialize",
        deserialize_with = "crate::controller_interface::config::bound::upper"
    )]
    pub max_rate: f64,
}

fn unbounded() -> f64 {
    f64::INFINITY
}

impl AdmittanceGains {
    /// Every bound of the gains, for a parameter whose values must lie in
    /// `[lo, hi]` (infinite for the temporal phase). Semi-implicit Euler at the loop's
    /// 1 ms stays stable and well damped only for moderate `K/M` and `B/M`; the bias
    /// force may shift the parameter at most across its range (or, for an unbounded
    /// parameter, by `max_shift`) against the stiffness, so a typo cannot run a
    /// parameter away.
    pub fn check(&self, lo: f64, hi: f64, max_shift: f64) -> Result<(), ConfigError> {
        check_range("mass", self.mass, 1e-3, 1e3)?;
        check_range("damping", self.damping, 0.0, 1e3 * self.mass)?;
        check_range("stiffness", self.stiffness, 0.0, 4e4 * self.mass)?;
        let (min, max) = (self.min, self.max);
        if lo.is_finite() || hi.is_finite() {
            check_range("min", min, lo, hi)?;
            check_range("max", max, lo, hi)?;
        } else if min.is_finite() || max.is_finite() {
            return Err(ConfigError::invalid(
                "min",
                "this parameter grows with time: its min and max must be unbounded (null)",
            ));
        }
        if min > max {
            return Err(ConfigError::invalid(
                "min",
                format!("min {} is above max {}", Num(min), Num(max)),
            ));
        }
        let shift = if lo.is_finite() && hi.is_finite() {
            hi - lo
        } else {
            max_shift
        };
        let bias = self.stiffness * shift;
        check_range("bias_force", self.bias_force, -bias, bias)?;
        if self.max_rate.is_nan() || self.max_rate <= 0.0 {
            return Err(ConfigError::invalid(
                "max_rate",
                "must be positive (or null: unbounded)",
            ));
        }
        Ok(())
    }
}

/// State of one parameter: deviation from nominal and its rate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ParamState {
    pub deviation: f64,
    pub rate: f64,
}

impl ParamState {
    /// Advances by `dt_s` under `force` (semi-implicit Euler), keeping
    /// `nominal + deviation` within the range (the rate stops at a bound).
    pub fn step(
        &mut self,
        g: &AdmittanceGains,
        sign: AdmittanceSign,
        force: f64,
        nominal: f64,
        dt_s: f64,
    ) {
        let accel = (sign.factor() * force + g.bias_force
            - g.damping * self.rate
            - g.stiffness * self.deviation)
            / g.mass;
        self.rate = (self.rate + accel * dt_s).clamp(-g.max_rate, g.max_rate);
        self.deviation += self.rate * dt_s;
        let value = nominal + self.deviation;
        if value > g.max || value < g.min {
            self.deviation = value.clamp(g.min, g.max) - nominal;
            self.rate = 0.0;
        }
    }

    pub fn value(&self, nominal: f64) -> f64 {
        nominal + self.deviation
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gains() -> AdmittanceGains {
        AdmittanceGains {
            mass: 1.0,
            damping: 8.0,
            stiffness: 16.0,
            min: 0.0,
            max: 1.5,
            bias_force: 0.0,
            max_rate: f64::INFINITY,
        }
    }

    fn settle(force: f64, c: AdmittanceSign) -> f64 {
        let mut p = ParamState::default();
        for _ in 0..5000 {
            p.step(&gains(), c, force, 0.8, 1e-3);
        }
        p.value(0.8)
    }

    #[test]
    fn a_steady_force_moves_the_parameter_by_force_over_stiffness() {
        assert!((settle(1.6, AdmittanceSign::Compliant) - 0.9).abs() < 1e-6);
        assert!((settle(1.6, AdmittanceSign::AntiCompliant) - 0.7).abs() < 1e-6);
        assert!((settle(0.0, AdmittanceSign::Compliant) - 0.8).abs() < 1e-9);
    }

    #[test]
    fn released_it_returns_to_nominal_and_never_leaves_its_range() {
        let mut p = ParamState::default();
        for k in 0..6000 {
            let f = if k < 1000 { 100.0 } else { 0.0 };
            p.step(&gains(), AdmittanceSign::Compliant, f, 0.8, 1e-3);
            assert!((0.0..=1.5).contains(&p.value(0.8)));
        }
        assert!((p.value(0.8) - 0.8).abs() < 1e-4, "{p:?}");
    }

    #[test]
    fn bad_gains_are_refused_naming_the_field() {
        let field = |g: AdmittanceGains| match g.check(0.0, 2.0, 1.0).unwrap_err() {
            ConfigError::OutOfRange { field, .. } | ConfigError::Invalid { field, .. } => field,
            e => panic!("{e}"),
        };
        let mut g = gains();
        g.mass = 0.0;
        assert_eq!(field(g), "mass");
        let mut g = gains();
        g.min = 1.8;
        assert_eq!(field(g), "min");
        let mut g = gains();
        g.bias_force = 1e308;
        assert_eq!(field(g), "bias_force");
        let mut g = gains();
        g.max = f64::INFINITY;
        assert_eq!(field(g), "max");
        assert!(gains().check(0.0, 2.0, 1.0).is_ok());
        // An unbounded parameter (the phase) must stay unbounded, its bias small.
        let mut g = gains();
        (g.min, g.max) = (f64::NEG_INFINITY, f64::INFINITY);
        assert!(g.check(f64::NEG_INFINITY, f64::INFINITY, 1.0).is_ok());
        g.bias_force = 1e3;
        assert!(g.check(f64::NEG_INFINITY, f64::INFINITY, 1.0).is_err());
        g.bias_force = 0.0;
        g.max = 100.0;
        assert!(g.check(f64::NEG_INFINITY, f64::INFINITY, 1.0).is_err());
        for bad in [0.0, -1.0, f64::NAN] {
            let mut g = gains();
            g.max_rate = bad;
            assert_eq!(field(g), "max_rate", "{bad}");
        }
    }

    #[test]
    fn a_rate_cap_bounds_how_fast_the_parameter_moves() {
        let mut g = gains();
        g.max_rate = 0.5;
        let mut p = ParamState::default();
        let mut last = p.value(0.8);
        for _ in 0..2000 {
            // Anti-compliant under a large force: it would run at tens of units/s.
            p.step(&g, AdmittanceSign::AntiCompliant, -100.0, 0.8, 1e-3);
            let v = p.value(0.8);
            assert!((v - last).abs() <= 0.5e-3 + 1e-12, "{} per ms", v - last);
            last = v;
        }
        assert!((p.value(0.8) - 1.5).abs() < 1e-9, "still reaches its bound");
    }
}
