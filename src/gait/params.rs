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
