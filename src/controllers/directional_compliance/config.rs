//! Configuration of directional compliance (reference 001, SPEC §8): which amplitude
//! rates each window admits, the absition's thresholds and mean, the ground's friction
//! offset, and the two planes' waves and admittances.

use std::f64::consts::{FRAC_PI_2, PI};

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_range, check_torque_filter};
use crate::controllers::compliant_slithering::SPATIAL_FREQ_GAINS;
use crate::controllers::steering::SteeringConfig;
use crate::gait::JOINT_LIMIT_RAD;
use crate::shape::admittance::AdmittanceGains;

/// Most body sections (each keeps its absition and mode per plane; issue 26).
pub const MAX_SECTIONS: usize = 4;

/// Which amplitude rates the admittance admits (SPEC §8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// Nominal compliance: every rate (shape-based compliance as it was).
    Nc,
    /// Positive directional compliance in every window: the amplitude only grows.
    Pdc,
    /// Negative directional compliance in every window: the amplitude only shrinks.
    Ndc,
    /// Each window switches between NC, PDC and NDC by its absition.
    Switching,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Nc => "nc",
            Strategy::Pdc => "pdc",
            Strategy::Ndc => "ndc",
            Strategy::Switching => "switching",
        }
    }
}

/// What the absition is measured from while a window is in PDC or NDC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reference {
    /// The threshold it crossed is the absition's new zero ("these thresholds serve as
    /// new nominal ... when calculating the amplitude absition", reference §III-C):
    /// the window returns to NC when it has undone what it gathered beyond it.
    Threshold,
    /// The absition runs on from where it was; the window returns to NC at zero.
    Zero,
}

/// The switching thresholds on the absition, rad·s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Thresholds {
    /// PDC below it (the window was squeezed flatter than nominal for long), < 0.
    pub low_rad_s: f64,
    /// NDC above it (the window was bent further than nominal for long), > 0.
    pub high_rad_s: f64,
    pub reference: Reference,
    /// Where the amplitude's spring pulls while a window is directional, rad from
    /// nominal: `+shift` in PDC (the window pushes out), `−shift` in NDC (it narrows);
    /// 0: the reference's filter alone.
    #[serde(default)]
    pub shift_rad: f64,
}

/// The dorsal wave of the three-dimensional controller (reference eq. 10):
/// `θ = A_d(s)·sin(k_S·ωS·s − k_T·Ω(t) + δ)` on the dorsal joints.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DorsalWave {
    /// Off: the dorsal joints stay straight (planar).
    pub enabled: bool,
    /// Nominal amplitude A_d0, rad.
    pub amplitude_rad: f64,
    /// k_S: its spatial frequency over the lateral one.
    pub spatial_ratio: f64,
    /// k_T: its temporal frequency over the lateral one.
    pub temporal_ratio: f64,
    /// δ, rad.
    pub phase_shift_rad: f64,
    /// The gait's selector runs planar slithering: the dorsal wave fades in over this
    /// long after the takeover so nothing jumps, s.
    pub ramp_s: f64,
    /// Admittance of each window's dorsal amplitude (absolute range).
    pub gains: AdmittanceGains,
}

/// The central temporal phase's compliance (a jam delays the wave).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseCompliance {
    pub enabled: bool,
    pub gains: AdmittanceGains,
}

/// The windowed spatial frequency's compliance (compliant slithering's `ωS`, thesis
/// §4.1; not in reference 001, whose compliance acts on the amplitude alone): where a
/// window is squeezed it takes more waves. It complies in every mode (the directional
/// filters act on the amplitude), on the lateral wave only (a dorsal wave keeps the
/// nominal spatial frequency).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpatialFreqCompliance {
    pub enabled: bool,
    /// Admittance of each window's spatial frequency, rad per body length (absolute
    /// range).
    pub gains: AdmittanceGains,
}

impl SpatialFreqCompliance {
    /// Off, with compliant slithering's gains (range 2π to 4π).
    pub const OFF: SpatialFreqCompliance = SpatialFreqCompliance {
        enabled: false,
        gains: SPATIAL_FREQ_GAINS,
    };
}

impl Default for SpatialFreqCompliance {
    fn default() -> Self {
        Self::OFF
    }
}

/// The body sections whose absitions choose the windows' modes (reference 001, Fig. 2:
/// head, middle and tail).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionsConfig {
    /// Equal stretches of the body, head to tail (1..=4; the reference's 3).
    pub count: usize,
    /// The span of a section's mean amplitude `Ā`, in nominal gait cycles (`2π/ωT`;
    /// the reference's "about one gait cycle").
    pub mean_cycles: f64,
}

/// Which sections count as held (issue 26, point 2; docs/compliance.md, "Held or
/// helped"). Among obstacles a section's mean amplitude sits away from nominal whether
/// the obstacles hold it or help it along; what tells them apart in the physics is that
/// a held section's mean stays still from one gait cycle to the next while a section
/// carried past obstacles keeps changing. The absition accumulates `Ā − A₀ − c` by the
/// share `still = s²/(s² + a²)` (`a`: the change of the section's mean over the last
/// span, itself averaged over a span) and leaks for the rest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldConfig {
    /// `s`: the change of a section's mean amplitude from one span to the next at which
    /// half of `Ā − A₀ − c` accumulates, rad; 0: off (the reference's plain integral).
    pub still_rad: f64,
    /// Time constant of the leak while the section moves, s.
    pub leak_s: f64,
    /// Longest stay of a section in PDC or NDC, in nominal gait cycles; then it returns
    /// to NC with zero absition (0: no limit, the reference's rule alone).
    pub max_dwell_cycles: f64,
}

impl HoldConfig {
    /// Off: the reference's plain integral and return rule.
    pub const PLAIN: HoldConfig = HoldConfig {
        still_rad: 0.0,
        leak_s: 5.0,
        max_dwell_cycles: 0.0,
    };
}

/// One value per body section (a JSON array of 1..=4 numbers, head first).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionValues {
    values: [f64; MAX_SECTIONS],
    len: usize,
}

impl SectionValues {
    /// `len` zeros.
    pub fn zeros(len: usize) -> Self {
        Self {
            values: [0.0; MAX_SECTIONS],
            len: len.clamp(1, MAX_SECTIONS),
        }
    }

    /// From `values` (at most [`MAX_SECTIONS`] are kept).
    pub fn from_slice(values: &[f64]) -> Self {
        let mut v = Self::zeros(values.len());
        for (d, s) in v.values.iter_mut().zip(values) {
            *d = *s;
        }
        v
    }

    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Section `k`'s value (0 past the end).
    pub fn get(&self, k: usize) -> f64 {
        self.as_slice().get(k).copied().unwrap_or(0.0)
    }

    /// All [`MAX_SECTIONS`] slots, zero past the end.
    pub fn padded(&self) -> [f64; MAX_SECTIONS] {
        std::array::from_fn(|k| self.get(k))
    }
}

impl Serialize for SectionValues {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.as_slice().serialize(s)
    }
}

impl<'de> Deserialize<'de> for SectionValues {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<f64>::deserialize(d)?;
        if v.is_empty() || v.len() > MAX_SECTIONS {
            return Err(serde::de::Error::invalid_length(
                v.len(),
                &"1 to 4 values, one per body section",
            ));
        }
        Ok(Self::from_slice(&v))
    }
}

/// The ground's friction offset `c` of the absition per plane and body section, rad:
/// how far each section's mean amplitude sits from nominal on open ground.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionOffset {
    pub lateral_rad: SectionValues,
    pub dorsal_rad: SectionValues,
}

/// Everything that defines a directional-compliance controller besides the gait's
/// nominal parameters (the lateral wave's amplitude, spatial and temporal frequency).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionalComplianceConfig {
    pub strategy: Strategy,
    /// Admittance of each window's lateral amplitude (absolute range).
    pub lateral: AdmittanceGains,
    pub dorsal: DorsalWave,
    pub phase: PhaseCompliance,
    /// The lateral windows' spatial frequency (off: the reference's amplitude alone).
    #[serde(default)]
    pub spatial_freq: SpatialFreqCompliance,
    pub thresholds: Thresholds,
    /// The body sections that keep the absitions and set the windows' modes.
    pub sections: SectionsConfig,
    /// Which sections count as held.
    pub hold: HoldConfig,
    /// A calibration from an earlier run (`controller.calibrate` reports one); `null`:
    /// uncalibrated (offset 0) until calibrated.
    #[serde(default)]
    pub friction_offset: Option<FrictionOffset>,
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

/// The spatial frequencies the controller takes, rad per body length (a wave running
/// head to tail, at most four on the body).
pub const SPATIAL_FREQ_RANGE: (f64, f64) = (0.25 * PI, 8.0 * PI);

/// Largest friction offset a calibration may hold, rad.
const OFFSET_MAX_RAD: f64 = 0.5;

impl DirectionalComplianceConfig {
    /// The preset: planar (lateral wave only) or 3-D, with `strategy`. Gains as
    /// compliant slithering's amplitude; thresholds tuned in the lab
    /// (docs/measurements/directional-compliance.md).
    pub fn preset(strategy: Strategy, three_d: bool) -> Self {
        let amplitude = |min, max| AdmittanceGains {
            mass: 1.0,
            damping: 6.0,
            stiffness: 4.0,
            min,
            max,
            bias_force: 0.0,
            max_rate: f64::INFINITY,
        };
        Self {
            strategy,
            // Up to 1.5 rad (joint reach under the π/2 limit), not compliant
            // slithering's 1.2: the peg terrains need nominals of 1.2 rad and more
            // (docs/measurements/slithering.md, "Slithering among pegs"), and a range that ends at
            // the nominal lets no window open wider, so NDC would never be entered.
            lateral: amplitude(0.1, 1.5),
            dorsal: DorsalWave {
                enabled: three_d,
                amplitude_rad: 0.3,
                spatial_ratio: 2.0,
                temporal_ratio: 2.0,
                phase_shift_rad: -FRAC_PI_2,
                ramp_s: 2.0,
                gains: amplitude(0.0, 0.7),
            },
            // The reference's compliance acts on the amplitude alone; planar, that
            // measures best here too; in 3-D the compliant phase keeps the body from
            // colliding with itself (docs/measurements/directional-compliance.md,
            // "Directional compliance on the corrected friction").
            // [`Self::over_full_compliance`] adds the rest.
            phase: PhaseCompliance {
                enabled: three_d,
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
            spatial_freq: SpatialFreqCompliance::OFF,
            // Tuned on peg-array layouts 500-519
            // (docs/measurements/directional-compliance.md); the fixed strategies are the
            // reference's bare filters.
            thresholds: Thresholds {
                low_rad_s: -1.2,
                high_rad_s: 1.2,
                reference: Reference::Threshold,
                shift_rad: if strategy == Strategy::Switching {
                    0.2
                } else {
                    0.0
                },
            },
            sections: SectionsConfig {
                count: 3,
                mean_cycles: 1.0,
            },
            // The reference's plain integral: on the corrected friction a section
            // carried past obstacles sits at the open-ground level and a held one
            // below it (docs/compliance.md, "Held or helped"). In 3-D a longest stay
            // of 3 cycles in PDC/NDC; planar the reference's return rule alone.
            // Chosen on peg-array and rock-pile layouts 500-519; it only changes
            // what the fixed strategies report.
            hold: HoldConfig {
                still_rad: 0.0,
                leak_s: 5.0,
                max_dwell_cycles: if three_d { 3.0 } else { 0.0 },
            },
            friction_offset: None,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
            edge_width_modules: 0.5,
            steering: SteeringConfig::DEFAULT,
        }
    }

    /// The same directional amplitude over the thesis's full compliance: the phase and
    /// the windows' spatial frequency comply too (the `dc_full_*` presets; planar,
    /// 0.1 self-contacts a trial among pegs instead of 14 and as fast; docs/
    /// measurements/directional-compliance.md, "Directional compliance over the full compliance").
    pub fn over_full_compliance(mut self) -> Self {
        self.phase.enabled = true;
        self.spatial_freq.enabled = true;
        self
    }

    /// Every bound (field paths relative to the configuration).
    pub fn check(&self) -> Result<(), ConfigError> {
        let (lo, hi) = (0.0, JOINT_LIMIT_RAD);
        self.lateral
            .check(lo, hi, 0.0)
            .map_err(|e| e.under("lateral"))?;
        let d = &self.dorsal;
        d.gains
            .check(lo, hi, 0.0)
            .map_err(|e| e.under("dorsal.gains"))?;
        // Checked while the wave is off too: the configuration is stored and shown,
        // and turning the wave on must not find a runaway nominal in it.
        check_range(
            "dorsal.amplitude_rad",
            d.amplitude_rad,
            d.gains.min,
            d.gains.max,
        )?;
        check_range("dorsal.spatial_ratio", d.spatial_ratio, 0.0, 4.0)?;
        check_range("dorsal.temporal_ratio", d.temporal_ratio, 0.0, 4.0)?;
        check_range(
            "dorsal.phase_shift_rad",
            d.phase_shift_rad,
            -2.0 * PI,
            2.0 * PI,
        )?;
        check_range("dorsal.ramp_s", d.ramp_s, 0.0, 60.0)?;
        self.phase
            .gains
            .check(f64::NEG_INFINITY, f64::INFINITY, PI)
            .map_err(|e| e.under("phase.gains"))?;
        self.spatial_freq
            .gains
            .check(SPATIAL_FREQ_RANGE.0, SPATIAL_FREQ_RANGE.1, 0.0)
            .map_err(|e| e.under("spatial_freq.gains"))?;
        let t = &self.thresholds;
        check_range("thresholds.low_rad_s", t.low_rad_s, -100.0, -1e-3)?;
        check_range("thresholds.high_rad_s", t.high_rad_s, 1e-3, 100.0)?;
        check_range(
            "thresholds.shift_rad",
            t.shift_rad,
            0.0,
            JOINT_LIMIT_RAD / 2.0,
        )?;
        let sections = &self.sections;
        if !(1..=MAX_SECTIONS).contains(&sections.count) {
            return Err(ConfigError::invalid(
                "sections.count",
                format!("must be 1 to {MAX_SECTIONS}"),
            ));
        }
        check_range("sections.mean_cycles", sections.mean_cycles, 0.1, 10.0)?;
        check_range("hold.still_rad", self.hold.still_rad, 0.0, 1.0)?;
        check_range("hold.leak_s", self.hold.leak_s, 0.1, 600.0)?;
        check_range(
            "hold.max_dwell_cycles",
            self.hold.max_dwell_cycles,
            0.0,
            100.0,
        )?;
        if let Some(o) = &self.friction_offset {
            for (plane, values) in [
                ("lateral_rad", &o.lateral_rad),
                ("dorsal_rad", &o.dorsal_rad),
            ] {
                if values.len() != sections.count {
                    return Err(ConfigError::invalid(
                        format!("friction_offset.{plane}"),
                        format!(
                            "has {} values: one per body section ({}) is needed",
                            values.len(),
                            sections.count
                        ),
                    ));
                }
                for (k, &v) in values.as_slice().iter().enumerate() {
                    let field = format!("friction_offset.{plane}[{k}]");
                    check_range(&field, v, -OFFSET_MAX_RAD, OFFSET_MAX_RAD)?;
                }
            }
        }
        check_torque_filter(self.torque_cutoff_hz, self.torque_deadband_nm)?;
        check_range("edge_width_modules", self.edge_width_modules, 0.05, 4.0)?;
        self.steering.check().map_err(|e| e.under("steering"))
    }
}

/// Clamps a measured offset into what a configuration may hold.
pub fn clamp_offset(v: f64) -> f64 {
    v.clamp(-OFFSET_MAX_RAD, OFFSET_MAX_RAD)
}

/// Whether `next` can replace `old` in a running controller
/// ([`crate::controller_interface::Controller::reconfigure`]): the same structure
/// (strategy, sections, what complies, the windows' edges, the calibration) and every
/// admittance's range holding the old one (the values now lie in the old range).
pub fn fits_in_place(
    old: &DirectionalComplianceConfig,
    next: &DirectionalComplianceConfig,
) -> Result<(), crate::controller_interface::CannotFollow> {
    use crate::controller_interface::CannotFollow;
    let same = old.strategy == next.strategy
        && old.sections == next.sections
        && old.hold == next.hold
        && old.friction_offset == next.friction_offset
        && old.edge_width_modules == next.edge_width_modules
        && old.dorsal.enabled == next.dorsal.enabled
        && old.dorsal.amplitude_rad == next.dorsal.amplitude_rad
        && old.phase.enabled == next.phase.enabled
        && old.spatial_freq.enabled == next.spatial_freq.enabled;
    if !same {
        return Err(CannotFollow(
            "the strategy, the sections, what complies, the windows' edges or the \
             calibration change the controller's structure",
        ));
    }
    let holds = |a: &AdmittanceGains, b: &AdmittanceGains| b.min <= a.min && a.max <= b.max;
    if !(holds(&old.lateral, &next.lateral)
        && holds(&old.dorsal.gains, &next.dorsal.gains)
        && holds(&old.phase.gains, &next.phase.gains)
        && holds(&old.spatial_freq.gains, &next.spatial_freq.gains))
    {
        return Err(CannotFollow(
            "a narrower range could leave a value outside it",
        ));
    }
    Ok(())
}
