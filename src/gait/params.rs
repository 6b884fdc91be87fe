//! Gait kinds and their parameters (SPEC §2). Units: rad, rad/s, m; spatial
//! frequency in rad per body length (3π = 1.5 waves on the body).
//!
//! Which fields each gait uses, their ranges and the defaults (with reasons) are
//! tabulated in `docs/gaits.md`.
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_8, PI};

use serde::{Deserialize, Serialize};

use super::serpenoid::Serpenoid;
use crate::module::{MODULE_LENGTH_M, MODULE_MAX_SPEED_RAD_S};
use crate::num::Num;

/// Largest joint excursion a gait may command, rad (±90°: beyond it neighbouring
/// modules collide).
pub const JOINT_LIMIT_RAD: f64 = FRAC_PI_2;

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

/// Why a parameter set was refused. Every variant but `Invalid` is built without
/// allocating, so the loop can refuse a request without touching the heap.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("{field} must be finite")]
    NotFinite { field: &'static str },
    #[error("{field} = {} is out of range [{}, {}]", Num(*.value), Num(*.min), Num(*.max))]
    OutOfRange {
        field: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("{0}")]
    Invalid(String),
    /// The patch changes a field the gait does not use (it would have no effect).
    #[error("{gait} does not use {field}")]
    Unused {
        gait: &'static str,
        field: &'static str,
    },
    /// The gait would drive some joint faster than the actuator can turn.
    #[error(
        "{gait}: peak joint speed {peak_rad_s:.3} rad/s (amplitude x |temporal_freq_rad_s|) \
         exceeds the SEA module's maximum of {max_rad_s} rad/s; lower the amplitude or the \
         temporal frequency"
    )]
    TooFast {
        gait: &'static str,
        peak_rad_s: f64,
        max_rad_s: f64,
    },
    /// |offset| + amplitude would bend some joint past its range.
    #[error(
        "{gait}: {plane} joints would reach {} rad (|offset| + amplitude), beyond the joint \
         range of {} rad", Num(*.excursion_rad), Num(*.max_rad)
    )]
    JointRange {
        gait: &'static str,
        plane: &'static str,
        excursion_rad: f64,
        max_rad: f64,
    },
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

/// One field of [`GaitParams`] (names as in the config and on the socket).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    AmplitudeLat,
    AmplitudeDor,
    OffsetLat,
    OffsetDor,
    SpatialFreq,
    TemporalFreq,
    PhaseShift,
    Taper,
    HelixRadius,
    HelixPitch,
}

impl Field {
    pub const ALL: [Field; 10] = [
        Field::AmplitudeLat,
        Field::AmplitudeDor,
        Field::OffsetLat,
        Field::OffsetDor,
        Field::SpatialFreq,
        Field::TemporalFreq,
        Field::PhaseShift,
        Field::Taper,
        Field::HelixRadius,
        Field::HelixPitch,
    ];

    /// The serialised name.
    pub fn name(self) -> &'static str {
        match self {
            Field::AmplitudeLat => "amplitude_lat_rad",
            Field::AmplitudeDor => "amplitude_dor_rad",
            Field::OffsetLat => "offset_lat_rad",
            Field::OffsetDor => "offset_dor_rad",
            Field::SpatialFreq => "spatial_freq_rad",
            Field::TemporalFreq => "temporal_freq_rad_s",
            Field::PhaseShift => "phase_shift_rad",
            Field::Taper => "taper",
            Field::HelixRadius => "helix_radius_m",
            Field::HelixPitch => "helix_pitch_m",
        }
    }

    /// Allowed range `(min, max)`, inclusive. Joint range and speed are checked on top
    /// (by [`GaitParams::validate`]) because they combine fields.
    pub fn range(self) -> (f64, f64) {
        match self {
            Field::AmplitudeLat | Field::AmplitudeDor => (0.0, JOINT_LIMIT_RAD),
            Field::OffsetLat | Field::OffsetDor => (-JOINT_LIMIT_RAD, JOINT_LIMIT_RAD),
            // Up to 3 waves on the body: 9 joints per plane on 18 modules still sample
            // that at 3 joints per wave.
            Field::SpatialFreq => (0.0, 6.0 * PI),
            Field::TemporalFreq => (-10.0, 10.0),
            Field::PhaseShift => (-2.0 * PI, 2.0 * PI),
            Field::Taper => (-0.8, 0.8),
            // Backbone radius from just over the module radius (2.55 cm) to half a metre.
            Field::HelixRadius => (0.03, 0.5),
            Field::HelixPitch => (0.005, 0.5),
        }
    }

    pub fn get(self, p: &GaitParams) -> f64 {
        let mut copy = *p;
        *self.slot_mut(&mut copy)
    }

    pub fn set(self, p: &mut GaitParams, value: f64) {
        *self.slot_mut(p) = value;
    }

    /// This field's place in `p`.
    fn slot_mut(self, p: &mut GaitParams) -> &mut f64 {
        match self {
            Field::AmplitudeLat => &mut p.amplitude_lat_rad,
            Field::AmplitudeDor => &mut p.amplitude_dor_rad,
            Field::OffsetLat => &mut p.offset_lat_rad,
            Field::OffsetDor => &mut p.offset_dor_rad,
            Field::SpatialFreq => &mut p.spatial_freq_rad,
            Field::TemporalFreq => &mut p.temporal_freq_rad_s,
            Field::PhaseShift => &mut p.phase_shift_rad,
            Field::Taper => &mut p.taper,
            Field::HelixRadius => &mut p.helix_radius_m,
            Field::HelixPitch => &mut p.helix_pitch_m,
        }
    }

    /// This field's place in `patch`.
    pub fn in_patch_mut(self, patch: &mut ParamPatch) -> &mut Option<f64> {
        match self {
            Field::AmplitudeLat => &mut patch.amplitude_lat_rad,
            Field::AmplitudeDor => &mut patch.amplitude_dor_rad,
            Field::OffsetLat => &mut patch.offset_lat_rad,
            Field::OffsetDor => &mut patch.offset_dor_rad,
            Field::SpatialFreq => &mut patch.spatial_freq_rad,
            Field::TemporalFreq => &mut patch.temporal_freq_rad_s,
            Field::PhaseShift => &mut patch.phase_shift_rad,
            Field::Taper => &mut patch.taper,
            Field::HelixRadius => &mut patch.helix_radius_m,
            Field::HelixPitch => &mut patch.helix_pitch_m,
        }
    }

    /// Sets this field's value in `patch`.
    pub fn set_in_patch(self, patch: &mut ParamPatch, value: f64) {
        *self.in_patch_mut(patch) = Some(value);
    }

    /// Removes this field from `patch`.
    pub fn clear_in_patch(self, patch: &mut ParamPatch) {
        *self.in_patch_mut(patch) = None;
    }

    /// The patch's value for this field, if it carries one.
    pub fn in_patch(self, patch: &ParamPatch) -> Option<f64> {
        let mut copy = *patch;
        *self.in_patch_mut(&mut copy)
    }
}

impl GaitKind {
    /// Whether this gait reads `field` (the others are kept but have no effect).
    pub fn uses(self, field: Field) -> bool {
        use Field::*;
        match field {
            OffsetLat | OffsetDor | TemporalFreq => true,
            AmplitudeLat => !matches!(self, GaitKind::LinearProgression | GaitKind::RollingHelix),
            AmplitudeDor => matches!(
                self,
                GaitKind::LinearProgression | GaitKind::Sidewinding | GaitKind::ConicalSidewinding
            ),
            SpatialFreq => !matches!(self, GaitKind::Rolling | GaitKind::RollingHelix),
            PhaseShift => matches!(self, GaitKind::Sidewinding | GaitKind::ConicalSidewinding),
            Taper => self == GaitKind::ConicalSidewinding,
            HelixRadius | HelixPitch => self == GaitKind::RollingHelix,
        }
    }
}

impl GaitParams {
    /// Checks the set for `kind` on the SEA Snake (module length
    /// [`MODULE_LENGTH_M`], which the rolling helix's amplitude depends on).
    /// See [`GaitParams::validate_for`].
    pub fn validate(&self, kind: GaitKind) -> Result<(), ParamError> {
        self.validate_for(kind, MODULE_LENGTH_M)
    }

    /// Checks the set for `kind` on modules of `module_length_m`: every field finite,
    /// every field the gait uses within [`Field::range`], |offset| + amplitude within
    /// [`JOINT_LIMIT_RAD`] in each plane, and the peak joint speed (amplitude · taper ·
    /// |ωT|) within [`MODULE_MAX_SPEED_RAD_S`]. Allocates nothing.
    pub fn validate_for(&self, kind: GaitKind, module_length_m: f64) -> Result<(), ParamError> {
        for field in Field::ALL {
            let value = field.get(self);
            if !value.is_finite() {
                return Err(ParamError::NotFinite {
                    field: field.name(),
                });
            }
            let (min, max) = field.range();
            if kind.uses(field) && !(min..=max).contains(&value) {
                return Err(ParamError::OutOfRange {
                    field: field.name(),
                    value,
                    min,
                    max,
                });
            }
        }
        // Body length only changes ωS, which neither check below depends on.
        let wave = Serpenoid::from_params(kind, self, module_length_m, 1.0);
        for (plane, name) in [
            (super::body::Plane::Lateral, "lateral"),
            (super::body::Plane::Dorsal, "dorsal"),
        ] {
            let excursion_rad = wave.max_excursion_rad(plane);
            if excursion_rad.is_nan() || excursion_rad > JOINT_LIMIT_RAD {
                return Err(ParamError::JointRange {
                    gait: kind.name(),
                    plane: name,
                    excursion_rad,
                    max_rad: JOINT_LIMIT_RAD,
                });
            }
        }
        let peak_rad_s = wave.peak_joint_speed_rad_s();
        if peak_rad_s.is_nan() || peak_rad_s > MODULE_MAX_SPEED_RAD_S {
            return Err(ParamError::TooFast {
                gait: kind.name(),
                peak_rad_s,
                max_rad_s: MODULE_MAX_SPEED_RAD_S,
            });
        }
        Ok(())
    }

    /// `self` with `patch` applied, validated for `kind` on the SEA Snake. A patch that
    /// changes a field `kind` does not use is refused ([`ParamError::Unused`]) rather
    /// than silently ignored. Allocates nothing.
    pub fn patched(&self, kind: GaitKind, patch: &ParamPatch) -> Result<GaitParams, ParamError> {
        self.patched_for(kind, patch, MODULE_LENGTH_M)
    }

    /// [`GaitParams::patched`] for modules of `module_length_m`.
    pub fn patched_for(
        &self,
        kind: GaitKind,
        patch: &ParamPatch,
        module_length_m: f64,
    ) -> Result<GaitParams, ParamError> {
        let mut next = *self;
        for field in Field::ALL {
            let Some(value) = field.in_patch(patch) else {
                continue;
            };
            // Re-sending an unused field's current value (a full set read back from
            // telemetry) is harmless; changing it is a mistake worth reporting.
            if !kind.uses(field) && value.to_bits() != field.get(self).to_bits() {
                return Err(ParamError::Unused {
                    gait: kind.name(),
                    field: field.name(),
                });
            }
            field.set(&mut next, value);
        }
        next.validate_for(kind, module_length_m)?;
        Ok(next)
    }

    /// The field-wise defaults of `kind` (see [`GaitTable::default`]).
    pub fn default_for(kind: GaitKind) -> GaitParams {
        let base = GaitParams::default();
        match kind {
            // Two dorsal waves on the body: several ground contacts per wave.
            GaitKind::LinearProgression => GaitParams {
                amplitude_dor_rad: FRAC_PI_8,
                spatial_freq_rad: 4.0 * PI,
                temporal_freq_rad_s: 1.0,
                ..base
            },
            // Thesis §4.1 nominal values: A = π/4, ωS = 3π (1.5 waves).
            GaitKind::Slithering => GaitParams {
                amplitude_lat_rad: FRAC_PI_4,
                spatial_freq_rad: 3.0 * PI,
                temporal_freq_rad_s: 1.0,
                ..base
            },
            // δ = π/2 (the thesis's robot used 3π/4): the waves in quadrature, so the
            // reversal's wells β = 0, π run forward and backward alike and its hill
            // π/2 is where the travel stops (δ + β ≡ 0 mod π); with 3π/4 the travel
            // stalls at β = π/4, inside the 0 well (docs/compliance.md, "Sidewinding").
            // The dorsal wave only lifts, so half the lateral one.
            GaitKind::Sidewinding => GaitParams {
                amplitude_lat_rad: FRAC_PI_4,
                amplitude_dor_rad: FRAC_PI_8,
                spatial_freq_rad: 3.0 * PI,
                temporal_freq_rad_s: 1.0,
                phase_shift_rad: FRAC_PI_2,
                ..base
            },
            GaitKind::ConicalSidewinding => GaitParams {
                taper: 0.4,
                ..Self::default_for(GaitKind::Sidewinding)
            },
            // 9 joint pairs of 0.2 rad: a C of about 100°. A deeper C cannot roll without
            // slip (its two ends would have to move apart), so it twists in place.
            GaitKind::Rolling => GaitParams {
                amplitude_lat_rad: 0.2,
                temporal_freq_rad_s: 1.5,
                ..base
            },
            // r = 10 cm (a pole of about 15 cm diameter), pitch 2π·4 cm: A ≈ 1.09 rad,
            // about 1.8 coils on 18 modules; slow, climbing is not a race.
            GaitKind::RollingHelix => GaitParams {
                helix_radius_m: 0.10,
                helix_pitch_m: 0.04,
                temporal_freq_rad_s: 0.5,
                ..base
            },
        }
    }
}

impl Default for GaitTable {
    /// Defaults for an 18-module SEA Snake; every entry passes [`GaitParams::validate`].
    fn default() -> Self {
        GaitTable {
            gaits: GaitKind::ALL.map(GaitParams::default_for),
        }
    }
}

impl GaitTable {
    /// Validates every entry; the first failure names its gait.
    pub fn validate_for(&self, module_length_m: f64) -> Result<(), (GaitKind, ParamError)> {
        for kind in GaitKind::ALL {
            self.get(kind)
                .validate_for(kind, module_length_m)
                .map_err(|e| (kind, e))?;
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "params_tests.rs"]
mod tests;
