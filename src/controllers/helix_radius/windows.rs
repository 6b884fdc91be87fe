//! The windowed radius (SPEC §6): one ρ per half a coil. The window manager anchors
//! the windows where the coil's angle round its axis (`HelixShape::coil_ratio` times
//! `∫R`) crosses a multiple of π: fixed on the body while it rolls in place, resized
//! as the coil tightens or opens. Each window has its own admittance, shape force and
//! (adaptive) set point; a window born at an end starts at the nominal, one that
//! leaves is dropped with what it learnt.

use super::{AdaptiveConfig, HelixRadiusConfig};
use crate::controller_interface::report::{MAX_WINDOWS, WindowField};
use crate::shape::ShapeFunction;
use crate::shape::admittance::ParamState;
use crate::shape::helix_shape::HelixShape;
use crate::shape::window_manager::{Slope, WindowManager};

/// Windows kept on the body (a helix of 3 coils has 7 half turns).
pub const MAX_HALF_TURNS: usize = 16;

/// One half turn's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfTurn {
    pub rho: ParamState,
    pub set_point: f64,
    pub force: f64,
    pub grip: f64,
}

impl HalfTurn {
    const NOMINAL: Self = Self {
        rho: ParamState {
            deviation: 0.0,
            rate: 0.0,
        },
        set_point: 1.0,
        force: 0.0,
        grip: 0.0,
    };

    pub fn value(&self) -> f64 {
        self.rho.value(self.set_point)
    }
}

/// The windows and their scratch space; allocates at construction only.
pub struct RadiusWindows {
    manager: WindowManager<HalfTurn>,
    r: [f64; MAX_HALF_TURNS],
    jacobian: Vec<f64>,
    /// Normalised arc length of each joint.
    s: Vec<f64>,
    /// Modules on the body (`L/l`, for the coil's angle).
    modules: f64,
}

/// The set point's move this step: up below the band, down above it.
pub(super) fn adapt(
    a: &AdaptiveConfig,
    set_point: f64,
    grip: f64,
    lo: f64,
    hi: f64,
    dt: f64,
) -> f64 {
    if !a.enabled {
        return set_point;
    }
    let dir = if grip < a.low_nm {
        1.0
    } else if grip > a.high_nm {
        -1.0
    } else {
        0.0
    };
    (set_point + dir * a.rate_per_s * dt).clamp(lo, hi)
}

impl RadiusWindows {
    pub fn new(s: &[f64], modules: f64) -> Self {
        Self {
            manager: WindowManager::new(s.len() + 9, MAX_HALF_TURNS),
            r: [0.0; MAX_HALF_TURNS],
            jacobian: vec![0.0; s.len() * MAX_HALF_TURNS],
            s: s.to_vec(),
            modules,
        }
    }

    pub fn reset(&mut self) {
        self.manager.clear();
    }

    pub fn len(&self) -> usize {
        self.manager.len()
    }

    /// R of each window into `self.r`, `r0` times its ρ; returns how many.
    fn fill_r(&mut self, r0: f64) -> usize {
        let mut m = 0;
        for (r, w) in self.r.iter_mut().zip(self.manager.windows()) {
            *r = r0 * w.payload.value();
            m += 1;
        }
        m
    }

    /// One step: re-anchor the windows to the coil (`shape`'s phase set already), then
    /// each window's force, grip, set point and admittance; `shape` is left with the
    /// windows and `r` ready for [`Self::values`].
    pub fn step(
        &mut self,
        shape: &mut HelixShape,
        config: &HelixRadiusConfig,
        r0: f64,
        tau_ext: &[f64],
        dt: f64,
    ) {
        if self.manager.is_empty() {
            shape.set_windows([crate::shape::window::Window::EVERYWHERE]);
            self.r[0] = r0;
        } else {
            self.fill_r(r0);
        }
        let m_old = shape.windows().len();
        let probe = &*shape;
        let (r, omega, ratio) = (self.r, probe.phase(), probe.coil_ratio(self.modules));
        // The coil's angle: ratio × ∫R (the wave's phase without its travel Ω).
        self.manager.update(
            |s| ratio * (probe.field_at(&r[..m_old], s).1 + omega),
            HalfTurn::NOMINAL,
            Slope::Increasing,
        );
        shape.set_windows(self.manager.windows().map(|w| w.window));
        let m = self.fill_r(r0);
        let n = tau_ext.len();
        shape.jacobian(&self.r[..m], &mut self.jacobian[..n * m]);
        let g = &config.gains;
        let steep = shape.steepness();
        for (j, w) in self.manager.windows_mut().enumerate() {
            let (mut force, mut grip, mut weight) = (0.0, 0.0, 0.0);
            for (i, (&tau, &s)) in tau_ext.iter().zip(&self.s).enumerate() {
                force += self.jacobian[i * m + j] * tau;
                let wi = w.window.weight(s, steep);
                grip += wi * tau.abs();
                weight += wi;
            }
            let p = &mut w.payload;
            // ∂h/∂ρ_j = R_0·∂h/∂R_j.
            p.force = r0 * force;
            p.grip = if weight > 1e-9 { grip / weight } else { 0.0 };
            p.set_point = adapt(&config.adaptive, p.set_point, p.grip, g.min, g.max, dt);
            p.rho.step(g, config.sign, p.force, p.set_point, dt);
        }
        self.fill_r(r0);
    }

    /// The windows' R after [`Self::step`].
    pub fn values(&self) -> &[f64] {
        &self.r[..self.manager.len().max(1)]
    }

    /// ρ's mean, min and max over the windows.
    pub fn summary(&self) -> (f64, f64, f64) {
        let (mut sum, mut lo, mut hi, mut n) = (0.0, f64::INFINITY, f64::NEG_INFINITY, 0.0);
        for w in self.manager.windows() {
            let v = w.payload.value();
            sum += v;
            lo = lo.min(v);
            hi = hi.max(v);
            n += 1.0;
        }
        if n == 0.0 {
            (1.0, 1.0, 1.0)
        } else {
            (sum / n, lo, hi)
        }
    }

    /// The shape force summed, and the set point and grip averaged, over the windows.
    pub fn means(&self) -> (f64, f64, f64) {
        let (mut f, mut sp, mut g, mut n) = (0.0, 0.0, 0.0, 0.0);
        for w in self.manager.windows() {
            f += w.payload.force;
            sp += w.payload.set_point;
            g += w.payload.grip;
            n += 1.0;
        }
        if n == 0.0 {
            (0.0, 1.0, 0.0)
        } else {
            (f, sp / n, g / n)
        }
    }

    /// The windows as a report field: ρ, set point, shape force, grip.
    pub fn field(&self, out: &mut WindowField) {
        out.count = self.manager.len();
        for (k, w) in self.manager.windows().take(MAX_WINDOWS).enumerate() {
            out.a[k] = w.window.a;
            out.b[k] = w.window.b;
            let p = &w.payload;
            for (c, v) in [p.value(), p.set_point, p.force, p.grip]
                .into_iter()
                .enumerate()
            {
                out.columns[c][k] = v;
            }
        }
    }
}
