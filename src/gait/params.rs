//! Gait kinds and their parameters (SPEC §2). Units: rad, rad/s, m; spatial
//! frequency in rad per body length (3π = 1.5 waves on the body).
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GaitKind {
    LinearProgression,
    Slithering,
    Sidewinding,
    Rolling,
    RollingHelix,
    ConicalSidewinding,
}

impl GaitKind {
    pub const ALL: [GaitKind; 6] = [
        GaitKind::LinearProgression,
        GaitKind::Slithering,
        GaitKind::Sidewinding,
        GaitKind::Rolling,
        GaitKind::RollingHelix,
        GaitKind::ConicalSidewinding,
    ];

    /// The name used in the config, the socket and `snakectl`.
    pub fn name(self) -> &'static str {
        match self {
            GaitKind::LinearProgression => "linear_progression",
            GaitKind::Slithering => "slithering",
            GaitKind::Sidewinding => "sidewinding",
            GaitKind::Rolling => "rolling",
            GaitKind::RollingHelix => "rolling_helix",
            GaitKind::ConicalSidewinding => "conical_sidewinding",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    pub fn index(self) -> usize {
        self as usize
    }
}

/// One gait's parameters. Not every gait uses every field (see `docs/gaits.md`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GaitParams {
    /// Lateral wave amplitude A_lat, rad.
    pub amplitude_lat_rad: f64,
    /// Dorsal wave amplitude A_dor, rad.
    pub amplitude_dor_rad: f64,
    /// Lateral offset φ_lat, rad (steers slithering).
    pub offset_lat_rad: f64,
    /// Dorsal offset φ_dor, rad.
    pub offset_dor_rad: f64,
    /// Spatial frequency ωS, rad per body length.
    pub spatial_freq_rad: f64,
    /// Temporal frequency ωT, rad/s (the gait's speed; negative runs it backwards).
    pub temporal_freq_rad_s: f64,
    /// Phase shift δ of the dorsal wave relative to the lateral one, rad.
    pub phase_shift_rad: f64,
    /// Amplitude taper c along the body (conical sidewinding), |c| ≤ 0.8.
    pub taper: f64,
    /// Rolling helix radius r, m.
    pub helix_radius_m: f64,
    /// Rolling helix pitch parameter p (pitch = 2πp), m.
    pub helix_pitch_m: f64,
}

impl Default for GaitParams {
    fn default() -> Self {
        GaitParams {
            amplitude_lat_rad: 0.0,
            amplitude_dor_rad: 0.0,
            offset_lat_rad: 0.0,
            offset_dor_rad: 0.0,
            spatial_freq_rad: 0.0,
            temporal_freq_rad_s: 0.0,
            phase_shift_rad: 0.0,
            taper: 0.0,
            helix_radius_m: 0.0,
            helix_pitch_m: 0.0,
        }
    }
}

/// A partial update of a gait's parameters (what `params.set` carries to the loop).
/// `Copy`, so it crosses the channel without allocating.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamPatch {
    pub amplitude_lat_rad: Option<f64>,
    pub amplitude_dor_rad: Option<f64>,
    pub offset_lat_rad: Option<f64>,
    pub offset_dor_rad: Option<f64>,
    pub spatial_freq_rad: Option<f64>,
    pub temporal_freq_rad_s: Option<f64>,
    pub phase_shift_rad: Option<f64>,
    pub taper: Option<f64>,
    pub helix_radius_m: Option<f64>,
    pub helix_pitch_m: Option<f64>,
}

/// Why a parameter set was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("{field} must be finite")]
    NotFinite { field: &'static str },
    #[error("{field} = {value} is out of range [{min}, {max}]")]
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("{0}")]
    Invalid(String),
}

/// Parameters of every gait, indexed by `GaitKind::index`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GaitTable {
    pub gaits: [GaitParams; 6],
}

impl GaitTable {
    pub fn get(&self, kind: GaitKind) -> &GaitParams {
        &self.gaits[kind.index()]
    }
    pub fn get_mut(&mut self, kind: GaitKind) -> &mut GaitParams {
        &mut self.gaits[kind.index()]
    }
}

// TEMP: replaced at merge (the gait helper owns the real validation).
impl GaitParams {
    /// This gait's parameters with `patch` applied, validated (finite, in range,
    /// peak joint speed within the module's 3.46 rad/s).
    pub fn patched(&self, _kind: GaitKind, patch: &ParamPatch) -> Result<GaitParams, ParamError> {
        use std::f64::consts::PI;
        let mut p = *self;
        let fields: [(&'static str, Option<f64>, &mut f64, f64, f64); 10] = [
            (
                "amplitude_lat_rad",
                patch.amplitude_lat_rad,
                &mut p.amplitude_lat_rad,
                0.0,
                PI / 2.0,
            ),
            (
                "amplitude_dor_rad",
                patch.amplitude_dor_rad,
                &mut p.amplitude_dor_rad,
                0.0,
                PI / 2.0,
            ),
            (
                "offset_lat_rad",
                patch.offset_lat_rad,
                &mut p.offset_lat_rad,
                -PI / 2.0,
                PI / 2.0,
            ),
            (
                "offset_dor_rad",
                patch.offset_dor_rad,
                &mut p.offset_dor_rad,
                -PI / 2.0,
                PI / 2.0,
            ),
            (
                "spatial_freq_rad",
                patch.spatial_freq_rad,
                &mut p.spatial_freq_rad,
                0.0,
                6.0 * PI,
            ),
            (
                "temporal_freq_rad_s",
                patch.temporal_freq_rad_s,
                &mut p.temporal_freq_rad_s,
                -2.0 * PI,
                2.0 * PI,
            ),
            (
                "phase_shift_rad",
                patch.phase_shift_rad,
                &mut p.phase_shift_rad,
                -2.0 * PI,
                2.0 * PI,
            ),
            ("taper", patch.taper, &mut p.taper, -0.8, 0.8),
            (
                "helix_radius_m",
                patch.helix_radius_m,
                &mut p.helix_radius_m,
                0.0,
                1.0,
            ),
            (
                "helix_pitch_m",
                patch.helix_pitch_m,
                &mut p.helix_pitch_m,
                -1.0,
                1.0,
            ),
        ];
        for (field, new, slot, min, max) in fields {
            let value = new.unwrap_or(*slot);
            if !value.is_finite() {
                return Err(ParamError::NotFinite { field });
            }
            if !(min..=max).contains(&value) {
                return Err(ParamError::OutOfRange {
                    field,
                    value,
                    min,
                    max,
                });
            }
            *slot = value;
        }
        let amp = p.amplitude_lat_rad.max(p.amplitude_dor_rad) * (1.0 + p.taper.abs());
        let peak = amp * p.temporal_freq_rad_s.abs();
        if peak > 3.46 {
            return Err(ParamError::Invalid(format!(
                "peak joint speed {peak:.2} rad/s exceeds the modules' 3.46 rad/s"
            )));
        }
        Ok(p)
    }
}
