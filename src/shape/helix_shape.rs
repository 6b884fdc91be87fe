//! The rolling helix's radius shape function (SPEC §6, thesis §4.2): one shape
//! parameter per window, the helix parameter `R`, with the spatial frequency and the
//! amplitude tied to it, `ωS = R` and `A = R/k`, in both planes:
//!
//! `h_i = A(s_i)·cos φ(s_i)` on lateral joints, `A(s_i)·sin φ(s_i)` on dorsal ones,
//! `A(s) = R(s)/k`, `R(s) = Σ_j R_j·w_j(s)`, `φ(s) = Σ_j R_j·∫₀^s w_j − Ω`.
//!
//! A larger `R` coils the body tighter (more curvature per joint) and twists it faster
//! (more of a coil per body length) in proportion, so radius and pitch change together
//! and the helix keeps its angle: a good climbing helix at every size. The phase is the
//! integral of the local `R`, as slithering's (`slithering_shape`), so a window that
//! tightens does not make the coil behind it jump.

use super::function::ShapeFunction;
use super::window::Window;
use crate::gait::{BodyLayout, Plane};

/// The helix over windows: joints, window edges, the tie `k` and the phase `Ω`.
#[derive(Debug, Clone)]
pub struct HelixShape {
    /// (joint index, plane, s) of every joint with a wave (all of them).
    joints: Vec<(usize, Plane, f64)>,
    windows: Vec<Window>,
    /// Edge steepness, per unit normalised arc length.
    steepness: f64,
    /// `k = ωS / A`, fixed by the nominal helix.
    k: f64,
    /// Ω, rad: the rolling's temporal phase (time is an argument: the caller sets it).
    phase_rad: f64,
}

impl HelixShape {
    /// A helix on `layout` with `windows` (the shape parameters, in order), edges of
    /// steepness `steepness` and the tie `k = ωS/A` (> 0) of the nominal helix.
    pub fn new(layout: &BodyLayout, windows: &[Window], steepness: f64, k: f64) -> Self {
        debug_assert!(k > 0.0 && k.is_finite(), "k = {k}");
        Self {
            joints: (0..layout.planes.len())
                .map(|i| (i, layout.planes[i], layout.s[i]))
                .collect(),
            windows: windows.to_vec(),
            steepness,
            k,
            phase_rad: 0.0,
        }
    }

    /// `k` for a nominal helix of amplitude `amplitude_rad` and spatial frequency
    /// `spatial_freq_rad` (rad per body length): `R_0 = ωS` then gives `A_0`.
    pub fn tie(amplitude_rad: f64, spatial_freq_rad: f64) -> f64 {
        spatial_freq_rad / amplitude_rad
    }

    pub fn k(&self) -> f64 {
        self.k
    }

    /// Sets the tie `k` (> 0), as a new nominal helix does; allocation-free.
    pub fn set_tie(&mut self, k: f64) {
        debug_assert!(k > 0.0 && k.is_finite(), "k = {k}");
        self.k = k;
    }

    /// Ω, rad.
    pub fn phase(&self) -> f64 {
        self.phase_rad
    }

    /// Sets Ω, rad (the wave's travel; `ωT·t` for a steady roll).
    pub fn set_phase(&mut self, phase_rad: f64) {
        self.phase_rad = phase_rad;
    }

    /// A helix with room for up to `max_windows` windows ([`Self::set_windows`]), one
    /// open window to begin with.
    pub fn with_capacity(layout: &BodyLayout, max_windows: usize, steepness: f64, k: f64) -> Self {
        let mut h = Self::new(layout, &[Window::EVERYWHERE], steepness, k);
        h.windows.reserve(max_windows.saturating_sub(1));
        h
    }

    /// Replaces the windows (their number may change, e.g. as the window manager
    /// re-anchors them to the coil); allocation-free within the capacity it was built
    /// with (more panics in debug builds: the real-time path must not allocate).
    pub fn set_windows(&mut self, windows: impl IntoIterator<Item = Window>) {
        let capacity = self.windows.capacity();
        self.windows.clear();
        self.windows.extend(windows);
        debug_assert!(
            self.windows.capacity() == capacity,
            "more windows than room for"
        );
    }

    pub fn windows(&self) -> &[Window] {
        &self.windows
    }

    /// The windows' edge steepness, per unit normalised arc length.
    pub fn steepness(&self) -> f64 {
        self.steepness
    }

    /// How far round its axis the coil turns per radian of `∫R`: the tangent of a helix
    /// turns at `√(κ² + τ²)` per metre, and with `A = R/k` (`κ ≈ A/2l` per module of
    /// length `l`) and `ωS = R` (`τ = R/L` on a body of length `L`) that is
    /// `R·√((L/2kl)² + 1)` per body length. So the coil's angle at `s` is this ratio
    /// times `Σ_j R_j·∫₀^s w_j`: half a coil is π of it. `modules` = `L/l`.
    pub fn coil_ratio(&self, modules: f64) -> f64 {
        ((modules / (2.0 * self.k)).powi(2) + 1.0).sqrt()
    }

    /// `R(s)` and `φ(s)` for the parameters `r`.
    pub fn field_at(&self, r: &[f64], s: f64) -> (f64, f64) {
        let m = self.steepness;
        let (mut field, mut phase) = (0.0, -self.phase_rad);
        for (w, &rj) in self.windows.iter().zip(r) {
            field += rj * w.weight(s, m);
            phase += rj * w.integral(s, m);
        }
        (field, phase)
    }
}

impl ShapeFunction for HelixShape {
    fn joint_count(&self) -> usize {
        self.joints.len()
    }

    fn param_count(&self) -> usize {
        self.windows.len()
    }

    fn value(&self, sigma: &[f64], joints_out: &mut [f64]) {
        for &(i, plane, s) in &self.joints {
            let (r, phi) = self.field_at(sigma, s);
            let a = r / self.k;
            joints_out[i] = match plane {
                Plane::Lateral => a * phi.cos(),
                Plane::Dorsal => a * phi.sin(),
            };
        }
    }

    /// `∂h_i/∂R_j = w_j(s_i)/k · c(φ_i) + A(s_i)·c′(φ_i)·∫₀^{s_i} w_j`, c = cos on lateral
    /// joints, sin on dorsal ones.
    fn jacobian(&self, sigma: &[f64], jacobian_out: &mut [f64]) {
        let (m, steep) = (self.windows.len(), self.steepness);
        for &(i, plane, s) in &self.joints {
            let (r, phi) = self.field_at(sigma, s);
            let a = r / self.k;
            let (c, dc) = match plane {
                Plane::Lateral => (phi.cos(), -phi.sin()),
                Plane::Dorsal => (phi.sin(), phi.cos()),
            };
            for (j, w) in self.windows.iter().enumerate() {
                jacobian_out[i * m + j] =
                    w.weight(s, steep) / self.k * c + a * dc * w.integral(s, steep);
            }
        }
    }
}

#[cfg(test)]
#[path = "helix_shape_tests.rs"]
mod tests;
