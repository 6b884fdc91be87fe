//! Configuration of anti-compliant sidewinding (thesis §4.3, SPEC §7): the lateral
//! amplitude (windowed) and spatial frequency (central) admittances, their sign, and
//! the inertial steering; the thesis's ablations as presets.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::heading::HeadingConfig;
use super::reversal::ReversalConfig;
use crate::controller_interface::config::{ConfigError, check_range, check_torque_filter};
use crate::controllers::compliant_slithering::{
    Centralization, CompliantSlitheringConfig, ParamConfig,
};
use crate::gait::JOINT_LIMIT_RAD;
use crate::shape::admittance::{AdmittanceGains, AdmittanceSign};

/// Everything that defines the controller besides the gait's nominal parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SidewindingConfig {
    /// The lateral amplitude, per travelling half-wave window.
    pub amplitude: ParamConfig,
    /// The spatial frequency of both waves, one value for the body.
    pub spatial_freq: ParamConfig,
    /// `anti_compliant` (the thesis's: the body pushes back) or `compliant`.
    pub sign: AdmittanceSign,
    /// Low-pass cutoff of the joint torques, Hz.
    pub torque_cutoff_hz: f64,
    /// Torques below this (after filtering) are ignored, N·m.
    pub torque_deadband_nm: f64,
    /// Width of a window's edge, in modules.
    pub edge_width_modules: f64,
    /// The heading the steering uses is low-passed over this long, s (the thesis
    /// averages it over a gait cycle: the chassis sways within one).
    pub heading_filter_s: f64,
    pub reversal: ReversalConfig,
    pub heading: HeadingConfig,
}

/// Range every amplitude bound must lie in, rad.
const AMPLITUDE_RANGE: (f64, f64) = (0.0, JOINT_LIMIT_RAD);
/// Range every spatial-frequency bound must lie in, rad per body length.
const SPATIAL_FREQ_RANGE: (f64, f64) = (0.25 * PI, 8.0 * PI);

impl SidewindingConfig {
    /// AC-SFC: both parameters anti-compliant, steering on. Gains from the compliant
    /// slithering controller's, tuned on the peg array; the spatial frequency's damping
    /// and both rate caps set by the joints' speed budget (docs/compliance.md,
    /// "Speed budget").
    pub fn full() -> Self {
        Self {
            amplitude: ParamConfig {
                enabled: true,
                centralization: Centralization::Windowed,
                gains: AdmittanceGains {
                    mass: 1.0,
                    damping: 6.0,
                    stiffness: 4.0,
                    min: 0.3,
                    // With the turning taper's growth (1 + 0.4) it stays within the
                    // joints' ±π/2: 1.1 × 1.4 = 1.54 rad.
                    max: 1.1,
                    bias_force: 0.0,
                    // ∂θ/∂A = sin φ (× the taper's 1.4 at most): ≤ 0.98 rad/s of joint
                    // speed on top of the wave's own (the budget: docs/compliance.md).
                    max_rate: 0.7,
                },
            },
            spatial_freq: ParamConfig {
                enabled: true,
                centralization: Centralization::Central,
                // Against a stiff peg anti-compliance is positive feedback: ωS runs to
                // a bound at about F/B. With damping 0.3 that was ~10 rad/BL/s, which
                // asks the tail joints (∂θ/∂ωS = A·s) for 8-12 rad/s: the guard then
                // slew-limited 8 % of cycles and the body chattered (issue 25). Damping
                // 3 and the cap keep it within the motors; the stiffness stays low so ωS
                // may sit at a bound while it squeezes through (stiffer did worse:
                // docs/measurements/sidewinding.md, "Chatter among pegs").
                gains: AdmittanceGains {
                    mass: 0.05,
                    damping: 3.0,
                    stiffness: 0.3,
                    min: 2.0 * PI,
                    max: 4.0 * PI,
                    bias_force: 0.0,
                    // ∂θ/∂ωS = A·s ≤ 1.54 rad: ≤ 0.92 rad/s of joint speed. With the
                    // wave's 1.54 and the amplitude's 0.98: 3.44, within the motor's 3.46.
                    max_rate: 0.6,
                },
            },
            sign: AdmittanceSign::AntiCompliant,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
            edge_width_modules: 0.5,
            heading_filter_s: 1.0,
            // K_h 6, not the bistable 2: among the pegs β then follows the heading
            // (through a steep step at 90°, no hysteresis, `ReversalConfig::bistable`)
            // instead of holding its well until 110°. It got `ac_sfc` through the peg
            // array more often, with the gait's δ = π/2 too (the tallies:
            // docs/measurements/sidewinding.md, "Why δ = π/2 and K_h 6", and
            // docs/lab-results/sidewinding/REPORT.md); the thesis's snap between the
            // wells is lost.
            reversal: ReversalConfig {
                k_h: 6.0,
                ..ReversalConfig::DEFAULT
            },
            heading: HeadingConfig::DEFAULT,
        }
    }

    /// `ac_sfc_lead`'s lead: crossing boards of pegs, on layouts no evaluation uses
    /// (seed-base 100, bare skin, three families), 0.4 rad crossed 28 of 60 against
    /// ac_sfc's 19, +0.15 ± 0.07 paired, and 0.7 rad 25 (docs/measurements/crossing.md,
    /// "Sidewinding goes head first among obstacles").
    pub const LEAD_RAD: f64 = 0.4;

    /// The thesis's ablations (`None` for an unknown name): `ac_sfc` (both), `ac`
    /// (amplitude only), `sfc` (spatial frequency only), `sw_open_loop` (neither; the
    /// inertial steering stays on in all four, as in the thesis's experiment).
    pub fn preset(name: &str) -> Option<Self> {
        let mut c = Self::full();
        match name {
            "ac_sfc" => {}
            "ac_sfc_lead" => c.heading.lead_rad = Self::LEAD_RAD,
            "ac" => c.spatial_freq.enabled = false,
            "sfc" => c.amplitude.enabled = false,
            "sw_open_loop" => {
                c.amplitude.enabled = false;
                c.spatial_freq.enabled = false;
            }
            _ => return None,
        }
        Some(c)
    }

    pub const PRESETS: &'static [(&'static str, &'static str)] = &[
        (
            "ac_sfc",
            "anti-compliant amplitude (windowed) and spatial frequency (central), with reversal and heading adjustment",
        ),
        (
            "ac_sfc_lead",
            "ac_sfc with the head held 0.4 rad towards the travel (it goes head first among obstacles)",
        ),
        ("ac", "anti-compliant amplitude only, with the steering"),
        (
            "sfc",
            "anti-compliant spatial frequency only, with the steering",
        ),
        (
            "sw_open_loop",
            "the nominal sidewinding wave with the steering, no compliance",
        ),
    ];

    /// The lateral wave's engine: compliant slithering's admittance with the temporal
    /// phase off (the wave keeps its pace) and this sign.
    pub fn lateral(&self) -> CompliantSlitheringConfig {
        let mut c = CompliantSlitheringConfig::full();
        c.amplitude = self.amplitude;
        c.spatial_freq = self.spatial_freq;
        c.phase.enabled = false;
        c.sign = self.sign;
        c.torque_cutoff_hz = self.torque_cutoff_hz;
        c.torque_deadband_nm = self.torque_deadband_nm;
        c.edge_width_modules = self.edge_width_modules;
        c
    }

    /// Every bound (field paths relative to the configuration).
    pub fn check(&self) -> Result<(), ConfigError> {
        self.amplitude
            .gains
            .check(AMPLITUDE_RANGE.0, AMPLITUDE_RANGE.1, 0.0)
            .map_err(|e| e.under("amplitude.gains"))?;
        self.spatial_freq
            .gains
            .check(SPATIAL_FREQ_RANGE.0, SPATIAL_FREQ_RANGE.1, 0.0)
            .map_err(|e| e.under("spatial_freq.gains"))?;
        if self.spatial_freq.centralization != Centralization::Central {
            return Err(ConfigError::invalid(
                "spatial_freq.centralization",
                "must be `central`: one spatial frequency keeps both waves in step",
            ));
        }
        if self.amplitude.centralization == Centralization::PerJoint {
            return Err(ConfigError::invalid(
                "amplitude.centralization",
                "must be `windowed` or `central`",
            ));
        }
        check_torque_filter(self.torque_cutoff_hz, self.torque_deadband_nm)?;
        check_range("edge_width_modules", self.edge_width_modules, 0.05, 4.0)?;
        check_range("heading_filter_s", self.heading_filter_s, 0.0, 30.0)?;
        let r = &self.reversal;
        check_range("reversal.k_b", r.k_b, -100.0, -1e-3)?;
        check_range("reversal.k_h", r.k_h, 1e-3, 100.0)?;
        check_range("reversal.max_rate_rad_s", r.max_rate_rad_s, 1e-3, 20.0)?;
        let h = &self.heading;
        check_range("heading.deadband_rad", h.deadband_rad, 0.0, PI)?;
        check_range("heading.turn_taper", h.turn_taper, 0.0, 0.8)?;
        check_range("heading.taper_rate_per_s", h.taper_rate_per_s, 1e-3, 10.0)?;
        check_range("heading.settle_rad", h.settle_rad, 0.0, h.deadband_rad)?;
        check_range("heading.trim_gain", h.trim_gain, 0.0, 100.0)?;
        check_range("heading.trim_max", h.trim_max, 0.0, h.turn_taper)?;
        let quarter = std::f64::consts::FRAC_PI_4;
        check_range("heading.lead_rad", h.lead_rad, -quarter, quarter)?;
        if h.turn_sign != 1.0 && h.turn_sign != -1.0 {
            return Err(ConfigError::invalid("heading.turn_sign", "must be 1 or -1"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_pass_their_checks_and_bad_values_are_named() {
        for (name, _) in SidewindingConfig::PRESETS {
            SidewindingConfig::preset(name).unwrap().check().unwrap();
        }
        assert!(SidewindingConfig::preset("nope").is_none());
        let mut c = SidewindingConfig::full();
        c.reversal.k_b = 1.0;
        assert!(c.check().unwrap_err().to_string().contains("reversal.k_b"));
        let mut c = SidewindingConfig::full();
        c.spatial_freq.centralization = Centralization::Windowed;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("spatial_freq.centralization"), "{e}");
        let mut c = SidewindingConfig::full();
        c.heading.turn_taper = f64::NAN;
        assert!(c.check().unwrap_err().to_string().contains("turn_taper"));
        let mut c = SidewindingConfig::full();
        c.heading.trim_max = c.heading.turn_taper + 0.1;
        assert!(c.check().unwrap_err().to_string().contains("trim_max"));
        let mut c = SidewindingConfig::full();
        c.amplitude.gains.max = 9.0;
        assert!(
            c.check()
                .unwrap_err()
                .to_string()
                .contains("amplitude.gains")
        );
    }

    /// The speed budget (docs/compliance.md): at the default gait the nominal wave and
    /// the two parameters at their rate caps, each at its largest `∂θ/∂σ`, move a joint
    /// no faster than the motor turns.
    #[test]
    fn the_presets_fit_the_joints_speed_at_the_default_gait() {
        use crate::gait::{GaitKind, GaitParams};
        use crate::module::MODULE_MAX_SPEED_RAD_S;
        let c = SidewindingConfig::full();
        let wt = GaitParams::default_for(GaitKind::Sidewinding).temporal_freq_rad_s;
        let grow = 1.0 + c.heading.turn_taper;
        let a_max = c.amplitude.gains.max * grow;
        let wave = a_max * wt.abs();
        let amplitude = c.amplitude.gains.max_rate * grow;
        let spatial = c.spatial_freq.gains.max_rate * a_max;
        let total = wave + amplitude + spatial;
        assert!(
            total <= MODULE_MAX_SPEED_RAD_S,
            "{wave:.2} + {amplitude:.2} + {spatial:.2} = {total:.2} rad/s"
        );
    }
}
