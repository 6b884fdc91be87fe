//! Configuration of compliant slithering (SPEC §5): per parameter whether it complies,
//! how it is centralised and its admittance; the named ablations the lab compares.

use std::f64::consts::PI;

use super::admittance::{AdmittanceGains, Compliance};
use super::slithering_shape::Param;

/// How a parameter is spread along the body (SPEC §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Centralization {
    /// One value for the whole body.
    Central,
    /// One value per travelling half-wave window.
    Windowed,
    /// One value per lateral joint.
    PerJoint,
}

/// One parameter's compliance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamCompliance {
    /// Off: the parameter stays at its nominal value.
    pub enabled: bool,
    pub centralization: Centralization,
    pub gains: AdmittanceGains,
}

/// Everything that defines a compliant slithering controller besides the gait's nominal
/// parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlitheringCompliance {
    pub amplitude: ParamCompliance,
    pub spatial_freq: ParamCompliance,
    pub phase: ParamCompliance,
    pub compliance: Compliance,
    /// Low-pass cutoff of the joint torques, Hz.
    pub torque_cutoff_hz: f64,
    /// Torques below this (after filtering) are ignored, N·m.
    pub torque_deadband_nm: f64,
    /// Width of a window's edge, in modules (SPEC: about half a module).
    pub edge_width_modules: f64,
}

impl SlitheringCompliance {
    /// The full controller (A + ωS + Ω): spatial parameters windowed, phase central,
    /// all compliant. Gains tuned in the lab (docs/compliance.md).
    pub fn full() -> Self {
        Self {
            amplitude: ParamCompliance {
                enabled: true,
                centralization: Centralization::Windowed,
                gains: AdmittanceGains {
                    mass: 1.0,
                    damping: 6.0,
                    stiffness: 4.0,
                    min: 0.1,
                    max: 1.2,
                    bias_force: 0.0,
                },
            },
            spatial_freq: ParamCompliance {
                enabled: true,
                centralization: Centralization::Windowed,
                gains: AdmittanceGains {
                    mass: 0.05,
                    damping: 0.3,
                    stiffness: 0.3,
                    min: 2.0 * PI,
                    max: 4.0 * PI,
                    bias_force: 0.0,
                },
            },
            phase: ParamCompliance {
                enabled: true,
                centralization: Centralization::Central,
                gains: AdmittanceGains {
                    mass: 1.0,
                    damping: 6.0,
                    stiffness: 4.0,
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                    bias_force: 0.0,
                },
            },
            compliance: Compliance::Compliant,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
            edge_width_modules: 0.5,
        }
    }

    pub fn param(&self, p: Param) -> &ParamCompliance {
        match p {
            Param::Amplitude => &self.amplitude,
            Param::SpatialFreq => &self.spatial_freq,
            Param::Phase => &self.phase,
        }
    }

    pub fn param_mut(&mut self, p: Param) -> &mut ParamCompliance {
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

    /// The compliant entries of [`crate::shape::SLITHERING_CONTROLLERS`] (between
    /// `open_loop` and `cpg`), which this type's presets build.
    pub const PRESETS: &'static [&'static str] = crate::shape::SLITHERING_CONTROLLERS
        .split_at(1)
        .1
        .split_at(crate::shape::SLITHERING_CONTROLLERS.len() - 2)
        .0;

    /// Every gain valid, positive cutoff, non-negative band, positive edge width.
    pub fn validate(&self) -> Result<(), String> {
        for p in Param::ALL {
            self.param(p)
                .gains
                .validate()
                .map_err(|e| format!("{}: {e}", p.name()))?;
        }
        if !(self.torque_cutoff_hz.is_finite() && self.torque_cutoff_hz > 0.0) {
            return Err("torque_cutoff_hz must be finite and positive".into());
        }
        if !(self.torque_deadband_nm.is_finite() && self.torque_deadband_nm >= 0.0) {
            return Err("torque_deadband_nm must be finite and >= 0".into());
        }
        if !(self.edge_width_modules.is_finite() && self.edge_width_modules > 0.0) {
            return Err("edge_width_modules must be finite and positive".into());
        }
        Ok(())
    }
}
