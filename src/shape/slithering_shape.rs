//! The slithering shape function (SPEC §5) over parameter fields:
//! `h_i = A(s_i)·sin φ(s_i)` on lateral joints (dorsal joints 0), with
//! `A(s) = Σ_j A_j·w_j(s)`, `φ(s) = Σ_j ωS_j·∫₀^s w_j − Σ_j Ω_j·w_j(s)`: the wave phase is
//! the integral of the local spatial frequency, so a local change never makes the wave
//! behind it jump. Each field has its own windows (one open window when central, fixed
//! windows per joint, or the window manager's travelling ones).

use nalgebra::{DVector, DVectorView};

use super::function::ShapeFunction;
use super::joint_samples::JointSamples;
use super::window::Window;
use super::window_set::WindowSet;
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
///
/// Each field's windows are sampled at the lateral joints when they are set, so a step
/// ([`Self::local_forces`], [`Self::set_points`]) costs matrix-vector products; fields
/// set together share their samples. The pointwise methods ([`Self::field_at`],
/// [`Self::phase_at`], the [`ShapeFunction`] impl) evaluate the windows where asked.
#[derive(Debug, Clone)]
pub struct SlitheringShape {
    /// (joint index, s) of each lateral joint.
    lateral: Vec<(usize, f64)>,
    joints: usize,
    /// Edge steepness, per unit normalised arc length.
    steepness: f64,
    /// Field `p` reads the windows and samples of field `source[p]` (itself, or the
    /// first of the fields it was set with). A source is its own source.
    source: [usize; 3],
    /// Where each field's values start in σ, and σ's length.
    bounds: [usize; 4],
    windows: [WindowSet; 3],
    samples: [JointSamples; 3],
    /// At the lateral joints: amplitude, phase field Ω(s), wave phase φ, sin φ, cos φ
    /// and the torque.
    amp: DVector<f64>,
    omega: DVector<f64>,
    phase: DVector<f64>,
    sin: Vec<f64>,
    cos: Vec<f64>,
    tau: Vec<f64>,
}

impl SlitheringShape {
    /// Lateral joints of `layout`; each field starts central and may hold up to
    /// `max_windows` windows (by parameter) without allocating.
    pub fn new(layout: &BodyLayout, steepness: f64, max_windows: [usize; 3]) -> Self {
        let lateral: Vec<(usize, f64)> = layout
            .planes
            .iter()
            .zip(&layout.s)
            .enumerate()
            .filter(|(_, (p, _))| **p == Plane::Lateral)
            .map(|(i, (_, &s))| (i, s))
            .collect();
        let rows = lateral.len();
        let s: Vec<f64> = lateral.iter().map(|&(_, s)| s).collect();
        let max_windows = max_windows.map(|w| w.max(1));
        let mut shape = Self {
            joints: layout.len(),
            steepness,
            source: [0; 3],
            bounds: [0; 4],
            windows: max_windows.map(|w| WindowSet::new(steepness, w)),
            samples: max_windows.map(|w| JointSamples::new(&s, w)),
            amp: DVector::zeros(rows),
            omega: DVector::zeros(rows),
            phase: DVector::zeros(rows),
            sin: vec![0.0; rows],
            cos: vec![0.0; rows],
            tau: vec![0.0; rows],
            lateral,
        };
        shape.set_windows(&Param::ALL, [Window::EVERYWHERE]);
        shape
    }

    /// Normalised arc length of each lateral joint.
    pub fn lateral_s(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
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

    /// Gives every field in `params` the same `windows` and samples them at the joints,
    /// once for all of them (no allocation when each listed field has room for them, by
    /// the capacities given at `new`).
    pub fn set_windows(&mut self, params: &[Param], windows: impl IntoIterator<Item = Window>) {
        let Some(first) = params.first() else {
            return;
        };
        let listed = |q: usize| params.iter().any(|p| p.index() == q);
        // A field left out that reads a listed field's windows takes a copy of its own.
        let source = self.source;
        for r in (0..3).filter(|&r| !listed(r) && listed(source[r])) {
            let (to, from) = pick(&mut self.windows, r, source[r]);
            to.copy_from(from);
            self.source[r] = r;
            self.resample(r);
        }
        let k = first.index();
        self.windows[k].set(windows);
        self.resample(k);
        for p in params {
            self.source[p.index()] = k;
        }
        for p in Param::ALL {
            let i = p.index();
            self.bounds[i + 1] = self.bounds[i] + self.windows(p).len();
        }
    }

    fn resample(&mut self, k: usize) {
        self.samples[k].fill(&self.windows[k]);
    }

    fn set(&self, param: Param) -> &WindowSet {
        &self.windows[self.source[param.index()]]
    }

    fn samples(&self, param: Param) -> &JointSamples {
        &self.samples[self.source[param.index()]]
    }

    pub fn windows(&self, param: Param) -> &[Window] {
        self.set(param).windows()
    }

    /// Offset of `param`'s values in σ.
    pub fn offset(&self, param: Param) -> usize {
        self.bounds[param.index()]
    }

    fn field<'a>(&self, sigma: &'a [f64], param: Param) -> &'a [f64] {
        let i = param.index();
        &sigma[self.bounds[i]..self.bounds[i + 1]]
    }

    /// Field value at `s`: `Σ_j σ_j·w_j(s)`.
    pub fn field_at(&self, sigma: &[f64], param: Param, s: f64) -> f64 {
        self.set(param).weighted_sum(self.field(sigma, param), s)
    }

    /// Wave phase `φ(s)`.
    pub fn phase_at(&self, sigma: &[f64], s: f64) -> f64 {
        let ws = self.field(sigma, Param::SpatialFreq);
        let mut integral = 0.0;
        let set = self.set(Param::SpatialFreq);
        set.sample(s, |j, _, int| integral += ws[j] * int);
        integral - self.field_at(sigma, Param::Phase, s)
    }

    /// `param`'s mean over the lateral joints (0 without any).
    pub fn lateral_mean(&self, sigma: &[f64], param: Param) -> f64 {
        let mean = self.samples(param).mean();
        self.field(sigma, param)
            .iter()
            .zip(mean)
            .map(|(v, m)| v * m)
            .sum()
    }

    /// Amplitude and phase at the lateral joints for `sigma` (the same sums, in the
    /// same order, as the pointwise methods).
    fn wave(&mut self, sigma: &[f64]) {
        let [a, ws, omega] = Param::ALL.map(|p| field_view(self.field(sigma, p)));
        let [sa, sws, somega] = self.source.map(|k| &self.samples[k]);
        self.amp.gemv(1.0, &sa.weight(), &a, 0.0);
        self.omega.gemv(1.0, &somega.weight(), &omega, 0.0);
        self.phase.gemv(1.0, &sws.integral(), &ws, 0.0);
        self.phase -= &self.omega;
    }

    /// The joints' set-points `h(σ)` into `joints_out` (length N), as
    /// [`ShapeFunction::value`] but from the samples.
    pub fn set_points(&mut self, sigma: &[f64], joints_out: &mut [f64]) {
        self.wave(sigma);
        joints_out.fill(0.0);
        for (k, &(i, _)) in self.lateral.iter().enumerate() {
            joints_out[i] = self.amp[k] * self.phase[k].sin();
        }
    }

    /// Shape forces with the SPEC's window-local Jacobian for the joint torques `tau`
    /// (length N) into `forces_out` (one per value of σ): a window collects torques only
    /// from the joints it covers (for the spatial frequency the exact column would also
    /// reach every joint behind the window, whose phase it shifts).
    pub fn local_forces(&mut self, sigma: &[f64], tau: &[f64], forces_out: &mut [f64]) {
        self.wave(sigma);
        for (k, &(i, _)) in self.lateral.iter().enumerate() {
            // A joint without torque adds exact zeros (and costs no sin, cos).
            self.tau[k] = tau[i];
            (self.sin[k], self.cos[k]) = if tau[i] == 0.0 {
                (0.0, 0.0)
            } else {
                self.phase[k].sin_cos()
            };
        }
        let [_, ws_at, omega_at, _] = self.bounds;
        let (fa, rest) = forces_out.split_at_mut(ws_at);
        let (fws, fomega) = rest.split_at_mut(omega_at - ws_at);
        let [sa, sws, somega] = self.source.map(|k| &self.samples[k]);
        let (a, sin, cos, tau) = (self.amp.as_slice(), &self.sin, &self.cos, &self.tau);
        let joints = || a.iter().zip(sin).zip(cos).zip(tau);
        for (j, f) in fa.iter_mut().enumerate() {
            let w = sa.column(j).0.iter();
            let terms = w.zip(joints()).map(|(w, (((_, s), _), t))| w * s * t);
            *f = terms.fold(0.0, |f, x| f + x);
        }
        for (j, f) in fws.iter_mut().enumerate() {
            let (w, int) = sws.column(j);
            let cells = w.iter().zip(int).zip(joints());
            let terms = cells.map(|((w, i), (((a, _), c), t))| w * a * c * i * t);
            *f = terms.fold(0.0, |f, x| f + x);
        }
        for (j, f) in fomega.iter_mut().enumerate() {
            let w = somega.column(j).0.iter();
            let terms = w.zip(joints()).map(|(w, (((a, _), c), t))| a * c * w * t);
            *f = terms.fold(0.0, |f, x| f - x);
        }
    }
}

/// `to` and `from` of `sets` (different indices).
fn pick(sets: &mut [WindowSet; 3], to: usize, from: usize) -> (&mut WindowSet, &WindowSet) {
    let (low, high) = sets.split_at_mut(to.max(from));
    if to < from {
        (&mut low[to], &high[0])
    } else {
        (&mut high[0], &low[from])
    }
}

fn field_view(values: &[f64]) -> DVectorView<'_, f64> {
    DVectorView::from_slice(values, values.len())
}

impl ShapeFunction for SlitheringShape {
    fn joint_count(&self) -> usize {
        self.joints
    }

    fn param_count(&self) -> usize {
        self.bounds[3]
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
        jacobian_out.fill(0.0);
        let [oa, ow, op] = Param::ALL.map(|p| self.offset(p));
        for &(i, s) in &self.lateral {
            let a = self.field_at(sigma, Param::Amplitude, s);
            let (sin, cos) = self.phase_at(sigma, s).sin_cos();
            let row = &mut jacobian_out[i * m_cols..(i + 1) * m_cols];
            self.set(Param::Amplitude)
                .sample(s, |j, w, _| row[oa + j] = w * sin);
            self.set(Param::SpatialFreq)
                .sample(s, |j, _, int| row[ow + j] = a * cos * int);
            self.set(Param::Phase)
                .sample(s, |j, w, _| row[op + j] = -a * cos * w);
        }
    }
}

#[cfg(test)]
#[path = "slithering_shape_tests.rs"]
mod tests;
