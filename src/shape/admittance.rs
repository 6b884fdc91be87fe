//! Admittance in shape space (SPEC §3), one parameter at a time:
//! `M·δ̈ + B·δ̇ + K·δ = s·F + τ_D` for the deviation `δ = σ − σ₀(t)` from the nominal
//! value. For a constant nominal this is the SPEC's equation; for the temporal phase,
//! whose nominal moves (`Ω₀ = ωT·t`), it makes damping act on the deviation's rate, so
//! an unforced wave runs at ωT instead of lagging by `B·ωT/K`.

/// Compliant (`+1`: the shape gives way to the force) or anti-compliant (`−1`: it
/// pushes back).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compliance {
    Compliant,
    AntiCompliant,
}

impl Compliance {
    pub fn sign(self) -> f64 {
        match self {
            Compliance::Compliant => 1.0,
            Compliance::AntiCompliant => -1.0,
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
    /// Range of σ (absolute, not of the deviation). Infinite bounds are allowed.
    pub min: f64,
    pub max: f64,
    /// τ_D, added to the force.
    #[serde(default)]
    pub bias_force: f64,
}

impl AdmittanceGains {
    /// Mass positive, damping and stiffness non-negative, all finite; `min ≤ max`.
    pub fn validate(&self) -> Result<(), String> {
        let finite = [self.mass, self.damping, self.stiffness, self.bias_force];
        if finite.iter().any(|v| !v.is_finite()) {
            return Err("mass, damping, stiffness and bias_force must be finite".into());
        }
        if self.mass <= 0.0 || self.damping < 0.0 || self.stiffness < 0.0 {
            return Err("mass must be > 0, damping and stiffness >= 0".into());
        }
        if self.min.is_nan() || self.max.is_nan() || self.min > self.max {
            return Err(format!("range [{}, {}] is empty", self.min, self.max));
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
        compliance: Compliance,
        force: f64,
        nominal: f64,
        dt_s: f64,
    ) {
        let accel = (compliance.sign() * force + g.bias_force
            - g.damping * self.rate
            - g.stiffness * self.deviation)
            / g.mass;
        self.rate += accel * dt_s;
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
        }
    }

    fn settle(force: f64, c: Compliance) -> f64 {
        let mut p = ParamState::default();
        for _ in 0..5000 {
            p.step(&gains(), c, force, 0.8, 1e-3);
        }
        p.value(0.8)
    }

    #[test]
    fn a_steady_force_moves_the_parameter_by_force_over_stiffness() {
        assert!((settle(1.6, Compliance::Compliant) - 0.9).abs() < 1e-6);
        assert!((settle(1.6, Compliance::AntiCompliant) - 0.7).abs() < 1e-6);
        assert!((settle(0.0, Compliance::Compliant) - 0.8).abs() < 1e-9);
    }

    #[test]
    fn released_it_returns_to_nominal_and_never_leaves_its_range() {
        let mut p = ParamState::default();
        for k in 0..6000 {
            let f = if k < 1000 { 100.0 } else { 0.0 };
            p.step(&gains(), Compliance::Compliant, f, 0.8, 1e-3);
            assert!((0.0..=1.5).contains(&p.value(0.8)));
        }
        assert!((p.value(0.8) - 0.8).abs() < 1e-4, "{p:?}");
    }

    #[test]
    fn bad_gains_are_refused() {
        let mut g = gains();
        g.mass = 0.0;
        assert!(g.validate().is_err());
        let mut g = gains();
        g.min = 2.0;
        assert!(g.validate().is_err());
        assert!(gains().validate().is_ok());
    }
}
