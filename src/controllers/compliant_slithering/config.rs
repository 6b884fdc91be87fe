//! Configuration of compliant slithering (SPEC §5): per parameter whether it complies,
//! how it is centralised and its admittance; the named ablations the lab compares.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_range, check_torque_filter};
use crate::controllers::steering::SteeringConfig;
use crate::gait::JOINT_LIMIT_RAD;
use crate::shape::admittance::{AdmittanceGains, AdmittanceSign};
use crate::shape::slithering_shape::Param;

/// How a parameter is spread along the body (SPEC §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Centralization {
    /// One value for the whole body.
    Central,
    /// One value per travelling half-wave window.
    Windowed,
    /// One value per lateral joint.
    PerJoint,
}

impl Centralization {
    pub fn name(self) -> &'static str {
        match self {
            Centralization::Central => "central",
            Centralization::Windowed => "windowed",
            Centralization::PerJoint => "per_joint",
        }
    }
}

/// One shape parameter's admittance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamConfig {
    /// Off: the parameter stays at its nominal value.
    pub enabled: bool,
    pub centralization: Centralization,
    pub gains: AdmittanceGains,
}

/// Everything that defines a compliant slithering controller besides the gait's nominal
/// parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompliantSlitheringConfig {
    pub amplitude: ParamConfig,
    pub spatial_freq: ParamConfig,
    pub phase: ParamConfig,
    /// `compliant` (the shape gives way to the force) or `anti_compliant`.
    pub sign: AdmittanceSign,
    /// Low-pass cutoff of the joint torques, Hz.
    pub torque_cutoff_hz: f64,
    /// Torques below this (after filtering) are ignored, N·m.
    pub torque_deadband_nm: f64,
    /// Width of a window's edge, in modules (SPEC: about half a module).
    pub edge_width_modules: f64,
    /// Holding a heading by the lateral offset (off until given a heading).
    #[serde(default)]
    pub steering: SteeringConfig,
}

/// Range every amplitude bound must lie in, rad.
/// The windowed spatial frequency's admittance (range 2π to 4π, the thesis's); also
/// directional compliance's when its spatial frequency complies.
pub const SPATIAL_FREQ_GAINS: AdmittanceGains = AdmittanceGains {
    mass: 0.05,
    damping: 0.3,
    stiffness: 0.3,
    min: 2.0 * PI,
    max: 4.0 * PI,
    bias_force: 0.0,
    max_rate: f64::INFINITY,
};

const AMPLITUDE_RANGE: (f64, f64) = (0.0, JOINT_LIMIT_RAD);
/// Range every spatial-frequency bound must lie in, rad per body length (up to four
/// waves on the body; the window manager keeps at most 16 windows).
const SPATIAL_FREQ_RANGE: (f64, f64) = (0.25 * PI, 8.0 * PI);
/// Largest steady phase shift a bias force may cause, rad (half a wave).
const PHASE_MAX_SHIFT_RAD: f64 = PI;

impl CompliantSlitheringConfig {
    /// The full controller (A + ωS + Ω): spatial parameters windowed, phase central,
    /// all compliant. Gains tuned in the lab (docs/compliance.md).
    pub fn full() -> Self {
        Self {
            amplitude: ParamConfig {
                enabled: true,
                centralization: Centralization::Windowed,
                gains: AdmittanceGains {
                    mass: 1.0,
                    damping: 6.0,
                    stiffness: 4.0,
                    min: 0.1,
                    max: 1.2,
                    bias_force: 0.0,
                    max_rate: f64::INFINITY,
                },
            },
            spatial_freq: ParamConfig {
                enabled: true,
                centralization: Centralization::Windowed,
                gains: SPATIAL_FREQ_GAINS,
            },
            phase: ParamConfig {
                enabled: true,
                centralization: Centralization::Central,
                gains: AdmittanceGains {
                    mass: 1.0,
                    damping: 6.0,
                    stiffness: 4.0,
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                    bias_force: 0.0,
                    max_rate: f64::INFINITY,
                },
            },
            sign: AdmittanceSign::Compliant,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
            edge_width_modules: 0.5,
            steering: SteeringConfig::DEFAULT,
        }
    }

    pub fn param(&self, p: Param) -> &ParamConfig {
        match p {
            Param::Amplitude => &self.amplitude,
            Param::SpatialFreq => &self.spatial_freq,
            Param::Phase => &self.phase,
        }
    }

    pub fn param_mut(&mut self, p: Param) -> &mut ParamConfig {
        match p {
            Param::Amplitude => &mut self.amplitude,
            Param::SpatialFreq => &mut self.spatial_freq,
            Param::Phase => &mut self.phase,
        }
    }

    /// The named variants the lab compares (`None` for an unknown name):
    /// `a`, `a_ws`, `a_ws_omega` (full), and the full controller with every parameter
    /// `central`, every one `per_joint`, or the phase `windowed` too.
    pub fn preset(name: &str) -> Option<Self> {
        let mut c = Self::full();
        match name {
            "a" => {
                c.spatial_freq.enabled = false;
                c.phase.enabled = false;
            }
            "a_ws" => c.phase.enabled = false,
            "a_ws_omega" => {}
            "a_ws_omega_central" => {
                for p in Param::ALL {
                    c.param_mut(p).centralization = Centralization::Central;
                }
            }
            "a_ws_omega_per_joint" => {
                for p in Param::ALL {
                    c.param_mut(p).centralization = Centralization::PerJoint;
                }
            }
            "a_ws_omega_windowed_phase" => c.phase.centralization = Centralization::Windowed,
            _ => return None,
        }
        Some(c)
    }

    /// The presets, the default first, with what each is.
    pub const PRESETS: &'static [(&'static str, &'static str)] = &[
        (
            "a_ws_omega",
            "full: amplitude and spatial frequency windowed, temporal phase central",
        ),
        ("a", "amplitude only, windowed"),
        ("a_ws", "amplitude and spatial frequency, windowed"),
        (
            "a_ws_omega_central",
            "the full controller, every parameter central",
        ),
        (
            "a_ws_omega_per_joint",
            "the full controller, every parameter per joint",
        ),
        (
            "a_ws_omega_windowed_phase",
            "the full controller with a windowed phase",
        ),
    ];

    /// Every bound (field paths relative to the configuration).
    pub fn check(&self) -> Result<(), ConfigError> {
        let ranges = [
            (AMPLITUDE_RANGE.0, AMPLITUDE_RANGE.1),
            (SPATIAL_FREQ_RANGE.0, SPATIAL_FREQ_RANGE.1),
            (f64::NEG_INFINITY, f64::INFINITY),
        ];
        for (p, (lo, hi)) in Param::ALL.into_iter().zip(ranges) {
            self.param(p)
                .gains
                .check(lo, hi, PHASE_MAX_SHIFT_RAD)
                .map_err(|e| e.under(&format!("{}.gains", p.name())))?;
        }
        check_torque_filter(self.torque_cutoff_hz, self.torque_deadband_nm)?;
        check_range("edge_width_modules", self.edge_width_modules, 0.05, 4.0)?;
        self.steering.check().map_err(|e| e.under("steering"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_passes_its_checks_and_bad_bounds_are_named() {
        for (name, _) in CompliantSlitheringConfig::PRESETS {
            let c = CompliantSlitheringConfig::preset(name).expect("a listed preset");
            c.check().unwrap();
        }
        let mut c = CompliantSlitheringConfig::full();
        c.spatial_freq.gains.bias_force = 1e308;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("spatial_freq.gains.bias_force"), "{e}");
        let mut c = CompliantSlitheringConfig::full();
        c.phase.gains.bias_force = 1e3;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("phase.gains.bias_force"), "{e}");
        let mut c = CompliantSlitheringConfig::full();
        c.amplitude.gains.max = 2.0;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("amplitude.gains.max"), "{e}");
        let mut c = CompliantSlitheringConfig::full();
        c.torque_cutoff_hz = 0.0;
        assert!(
            c.check()
                .unwrap_err()
                .to_string()
                .contains("torque_cutoff_hz")
        );
    }
}
