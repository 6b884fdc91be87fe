//! The compound serpenoid (SPEC §2), evaluated for a body layout.
//!
//! Every gait is resolved once (when it is chosen or its parameters change) into a
//! [`Serpenoid`]: one sine wave per plane,
//!
//! ```text
//! θ_i = φ_p + A_p · (1 − c·s_i) · sin(ωS_p · s_i − ψ + δ_p)
//! ```
//!
//! with `ψ` the gait's accumulated temporal phase (`ψ̇ = ωT`, integrated by the selector
//! so that a change of `ωT` never jumps the phase). Evaluating it per cycle is a few
//! multiplications and one `sin_cos` per joint; nothing allocates.
//! How each gait maps onto the two waves, and the rolling-helix derivation, are in
//! `docs/gaits.md`.
use std::f64::consts::FRAC_PI_2;

use super::body::{BodyLayout, Plane};
use super::params::{GaitKind, GaitParams};

/// One plane's wave: `offset + amplitude · sin(spatial_freq · s − ψ + phase)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wave {
    /// φ, rad.
    pub offset_rad: f64,
    /// A, rad (before the taper).
    pub amplitude_rad: f64,
    /// ωS, rad per body length.
    pub spatial_freq_rad: f64,
    /// δ, rad.
    pub phase_rad: f64,
}

/// A gait resolved into its two waves, ready to evaluate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Serpenoid {
    pub lateral: Wave,
    pub dorsal: Wave,
    /// Amplitude taper c: joint `i` gets `A · (1 − c·s_i)` (0 except conical sidewinding).
    pub taper: f64,
    /// ωT of the gait's parameters, rad/s (what the phase is integrated with).
    pub temporal_freq_rad_s: f64,
}

/// Joint amplitude and torsion of a rolling helix of radius `r` and pitch parameter `p`
/// (pitch `2πp`) built from modules of length `l`:
/// `κ = r/(r²+p²)`, `τ = p/(r²+p²)`, `A = 2κ·sin(τl)/τ` (→ `2κl` as `τ → 0`).
/// Returns `(A_rad, τ_rad_per_m)`. Derivation in `docs/gaits.md`.
pub fn helix_wave(radius_m: f64, pitch_m: f64, module_length_m: f64) -> (f64, f64) {
    let d = radius_m * radius_m + pitch_m * pitch_m;
    let kappa = radius_m / d;
    let tau = pitch_m / d;
    let x = tau * module_length_m;
    // sin(x)/x, with the removable singularity at x = 0 handled.
    let sinc = if x.abs() < 1e-9 { 1.0 } else { x.sin() / x };
    (2.0 * kappa * module_length_m * sinc, tau)
}

impl Serpenoid {
    /// Resolves `kind` with `params` for modules of `module_length_m` on a body of
    /// `body_length_m` (the length that normalised arc length 1 stands for; only the
    /// rolling helix needs lengths). Fields a gait does not use are ignored.
    pub fn from_params(
        kind: GaitKind,
        params: &GaitParams,
        module_length_m: f64,
        body_length_m: f64,
    ) -> Self {
        let p = params;
        let wave = |offset_rad, amplitude_rad, spatial_freq_rad, phase_rad| Wave {
            offset_rad,
            amplitude_rad,
            spatial_freq_rad,
            phase_rad,
        };
        let (lateral, dorsal, taper) = match kind {
            GaitKind::LinearProgression => (
                wave(p.offset_lat_rad, 0.0, 0.0, 0.0),
                wave(
                    p.offset_dor_rad,
                    p.amplitude_dor_rad,
                    p.spatial_freq_rad,
                    0.0,
                ),
                0.0,
            ),
            GaitKind::Slithering => (
                wave(
                    p.offset_lat_rad,
                    p.amplitude_lat_rad,
                    p.spatial_freq_rad,
                    0.0,
                ),
                wave(p.offset_dor_rad, 0.0, 0.0, 0.0),
                0.0,
            ),
            GaitKind::Sidewinding | GaitKind::ConicalSidewinding => (
                wave(
                    p.offset_lat_rad,
                    p.amplitude_lat_rad,
                    p.spatial_freq_rad,
                    0.0,
                ),
                wave(
                    p.offset_dor_rad,
                    p.amplitude_dor_rad,
                    p.spatial_freq_rad,
                    p.phase_shift_rad,
                ),
                if kind == GaitKind::ConicalSidewinding {
                    p.taper
                } else {
                    0.0
                },
            ),
            // ωS = 0, equal amplitudes (A_lat drives both), δ = π/2.
            GaitKind::Rolling => (
                wave(p.offset_lat_rad, p.amplitude_lat_rad, 0.0, 0.0),
                wave(p.offset_dor_rad, p.amplitude_lat_rad, 0.0, FRAC_PI_2),
                0.0,
            ),
            // Lateral A·cos(ωS·s − ψ) = A·sin(ωS·s − ψ + π/2), dorsal A·sin(ωS·s − ψ).
            GaitKind::RollingHelix => {
                let (a, tau) = helix_wave(p.helix_radius_m, p.helix_pitch_m, module_length_m);
                let ws = tau * body_length_m;
                (
                    wave(p.offset_lat_rad, a, ws, FRAC_PI_2),
                    wave(p.offset_dor_rad, a, ws, 0.0),
                    0.0,
                )
            }
        };
        Serpenoid {
            lateral,
            dorsal,
            taper,
            temporal_freq_rad_s: p.temporal_freq_rad_s,
        }
    }

    /// Resolves `kind` for `layout` (module length and body length from the layout).
    pub fn for_layout(kind: GaitKind, params: &GaitParams, layout: &BodyLayout) -> Self {
        Self::from_params(kind, params, layout.module_length_m, layout.body_length_m())
    }

    /// The wave of `plane`.
    pub fn wave(&self, plane: Plane) -> &Wave {
        match plane {
            Plane::Lateral => &self.lateral,
            Plane::Dorsal => &self.dorsal,
        }
    }

    /// Largest taper factor `1 − c·s` over `s ∈ [0, 1]`.
    pub fn max_taper_factor(&self) -> f64 {
        (1.0 - self.taper).max(1.0)
    }

    /// Largest |offset| + amplitude of `plane` over the body, rad.
    pub fn max_excursion_rad(&self, plane: Plane) -> f64 {
        let w = self.wave(plane);
        w.offset_rad.abs() + w.amplitude_rad.abs() * self.max_taper_factor()
    }

    /// Peak joint speed at phase rate `|ωT|`, rad/s: `max_p A_p · max taper · |ωT|`.
    pub fn peak_joint_speed_rad_s(&self) -> f64 {
        let a = self
            .lateral
            .amplitude_rad
            .abs()
            .max(self.dorsal.amplitude_rad.abs());
        a * self.max_taper_factor() * self.temporal_freq_rad_s.abs()
    }

    /// Angle and its derivative with respect to the phase ψ of a joint at `s` in `plane`.
    #[inline]
    pub fn joint(&self, plane: Plane, s: f64, psi_rad: f64) -> (f64, f64) {
        let w = self.wave(plane);
        let a = w.amplitude_rad * (1.0 - self.taper * s);
        let (sin, cos) = (w.spatial_freq_rad * s - psi_rad + w.phase_rad).sin_cos();
        (w.offset_rad + a * sin, -a * cos)
    }

    /// Joint angles at phase `psi_rad` into `positions_out` (one per joint of `layout`).
    pub fn evaluate(&self, layout: &BodyLayout, psi_rad: f64, positions_out: &mut [f64]) {
        for ((out, &plane), &s) in positions_out.iter_mut().zip(&layout.planes).zip(&layout.s) {
            *out = self.joint(plane, s, psi_rad).0;
        }
    }

    /// Joint angles at phase `psi_rad` and their exact time derivatives when the phase
    /// advances at `psi_rate_rad_s` (normally ωT): `θ̇_i = −A_i·cos(·)·ψ̇`.
    pub fn evaluate_with_velocity(
        &self,
        layout: &BodyLayout,
        psi_rad: f64,
        psi_rate_rad_s: f64,
        positions_out: &mut [f64],
        velocities_out: &mut [f64],
    ) {
        let joints = layout.planes.iter().zip(&layout.s);
        for ((pos, vel), (&plane, &s)) in positions_out.iter_mut().zip(velocities_out).zip(joints) {
            let (theta, dtheta_dpsi) = self.joint(plane, s, psi_rad);
            *pos = theta;
            *vel = dtheta_dpsi * psi_rate_rad_s;
        }
    }
}

#[cfg(test)]
#[path = "serpenoid_tests.rs"]
mod tests;
