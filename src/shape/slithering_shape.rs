//! The slithering shape function (SPEC §5) over parameter fields:
//! `h_i = A(s_i)·sin φ(s_i)` on lateral joints (dorsal joints 0), with
//! `A(s) = Σ_j A_j·w_j(s)`, `φ(s) = Σ_j ωS_j·∫₀^s w_j − Σ_j Ω_j·w_j(s)`: the wave phase is
//! the integral of the local spatial frequency, so a local change never makes the wave
//! behind it jump. Each field has its own windows (one open window when central, fixed
//! windows per joint, or the window manager's travelling ones).

use super::function::ShapeFunction;
use super::window::Window;
use crate::gait::{BodyLayout, Plane};

/// The three slithering parameters, in the order of σ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// A, rad.
    Amplitude,
    /// ωS, rad per body length.
    SpatialFreq,
    /// Ω, the temporal phase, rad.
    Phase,
}

impl Param {
    pub const ALL: [Param; 3] = [Param::Amplitude, Param::SpatialFreq, Param::Phase];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Param::Amplitude => "amplitude",
            Param::SpatialFreq => "spatial_freq",
            Param::Phase => "phase",
        }
    }
}

/// Geometry of the slithering shape: joints, and each field's windows. σ is the
/// concatenation of the amplitude, spatial-frequency and phase fields' values.
#[derive(Debug, Clone)]
pub struct SlitheringShape {
    /// (joint index, s) of each lateral joint.
    lateral: Vec<(usize, f64)>,
    joints: usize,
    /// Edge steepness, per unit normalised arc length.
    steepness: f64,
    windows: [Vec<Window>; 3],
}

impl SlitheringShape {
    /// Lateral joints of `layout`; each field starts central. Windows are kept in
    /// vectors of capacity `max_windows` (set them with [`Self::set_windows`]).
    pub fn new(layout: &BodyLayout, steepness: f64, max_windows: usize) -> Self {
        let lateral = layout
            .planes
            .iter()
            .zip(&layout.s)
            .enumerate()
            .filter(|(_, (p, _))| **p == Plane::Lateral)
            .map(|(i, (_, &s))| (i, s))
            .collect();
        let field = || {
            let mut v = Vec::with_capacity(max_windows.max(1));
            v.push(Window::EVERYWHERE);
            v
        };
        Self {
            lateral,
            joints: layout.len(),
            steepness,
            windows: [field(), field(), field()],
        }
    }

    /// Normalised arc length of each lateral joint.
    pub fn lateral_s(&self) -> impl Iterator<Item = f64> + '_ {
        self.lateral.iter().map(|&(_, s)| s)
    }

    /// (joint index, s) of each lateral joint.
    pub fn lateral_joints(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.lateral.iter().copied()
    }

    pub fn lateral_count(&self) -> usize {
        self.lateral.len()
    }

    pub fn steepness(&self) -> f64 {
        self.steepness
    }

    /// Replaces `param`'s windows (no allocation within the capacity given at `new`).
    pub fn set_windows(&mut self, param: Param, windows: impl IntoIterator<Item = Window>) {
        let v = &mut self.windows[param.index()];
        v.clear();
        v.extend(windows);
    }

    pub fn windows(&self, param: Param) -> &[Window] {
        &self.windows[param.index()]
    }

    /// Offset of `param`'s values in σ.
    pub fn offset(&self, param: Param) -> usize {
        self.windows[..param.index()].iter().map(Vec::len).sum()
    }

    fn field<'a>(&self, sigma: &'a [f64], param: Param) -> &'a [f64] {
        let at = self.offset(param);
        &sigma[at..at + self.windows[param.index()].len()]
    }

    /// Field value at `s`: `Σ_j σ_j·w_j(s)`.
    pub fn field_at(&self, sigma: &[f64], param: Param, s: f64) -> f64 {
        let m = self.steepness;
        let w = &self.windows[param.index()];
        self.field(sigma, param)
            .iter()
            .zip(w)
            .map(|(v, win)| v * win.weight(s, m))
            .sum()
    }

    /// Wave phase `φ(s)`.
    pub fn phase_at(&self, sigma: &[f64], s: f64) -> f64 {
        let m = self.steepness;
        let ws = &self.windows[Param::SpatialFreq.index()];
        let integral: f64 = self
            .field(sigma, Param::SpatialFreq)
            .iter()
            .zip(ws)
            .map(|(v, win)| v * win.integral(s, m))
            .sum();
        integral - self.field_at(sigma, Param::Phase, s)
    }
}

impl ShapeFunction for SlitheringShape {
    fn joint_count(&self) -> usize {
        self.joints
    }

    fn param_count(&self) -> usize {
        self.windows.iter().map(Vec::len).sum()
    }

    fn value(&self, sigma: &[f64], joints_out: &mut [f64]) {
        joints_out.fill(0.0);
        for &(i, s) in &self.lateral {
            joints_out[i] =
                self.field_at(sigma, Param::Amplitude, s) * self.phase_at(sigma, s).sin();
        }
    }

    fn jacobian(&self, sigma: &[f64], jacobian_out: &mut [f64]) {
        let m_cols = self.param_count();
        let m = self.steepness;
        jacobian_out.fill(0.0);
        let [oa, ow, op] = Param::ALL.map(|p| self.offset(p));
        for &(i, s) in &self.lateral {
            let a = self.field_at(sigma, Param::Amplitude, s);
            let (sin, cos) = self.phase_at(sigma, s).sin_cos();
            let row = &mut jacobian_out[i * m_cols..(i + 1) * m_cols];
            for (j, w) in self.windows[Param::Amplitude.index()].iter().enumerate() {
                row[oa + j] = w.weight(s, m) * sin;
            }
            for (j, w) in self.windows[Param::SpatialFreq.index()].iter().enumerate() {
                row[ow + j] = a * cos * w.integral(s, m);
            }
            for (j, w) in self.windows[Param::Phase.index()].iter().enumerate() {
                row[op + j] = -a * cos * w.weight(s, m);
            }
        }
    }
}

#[cfg(test)]
#[path = "slithering_shape_tests.rs"]
mod tests;
