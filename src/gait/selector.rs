//! The gait selector: owns the gait table and the active gait, integrates each gait's
//! temporal phase, and blends smoothly whenever the gait, its parameters or the
//! starting pose change. A final per-joint slew limit guarantees that no set-point
//! ever moves faster than the joint can.
//!
//! Blends nest: the commanded set-points are a stack of layers, the bottom one a
//! running gait or a frozen pose (the measured pose after a resync), every layer above
//! it a gait fading in over the layers below with a C1 weight. Every layer keeps
//! running while it fades out, so switching mid-blend is as smooth as switching from
//! a pure gait. A layer whose blend has finished hides everything below it and those
//! are dropped. See `docs/gaits.md` for the reasoning.
use super::body::BodyLayout;
use super::params::{GaitKind, GaitParams, GaitTable, ParamError, ParamPatch};
use super::serpenoid::Serpenoid;
use super::slew::SlewLimiter;

/// Blend time the daemon uses unless configured, s: long enough that switching
/// between any two default gaits stays well inside the joints' speed.
pub const DEFAULT_BLEND_TIME_S: f64 = 2.0;
/// Allowed blend times, s.
pub const BLEND_TIME_RANGE_S: (f64, f64) = (0.1, 30.0);
/// Layers kept at once. More switches within one blend time collapse the two oldest
/// layers into a frozen pose (continuous position, their velocity is dropped).
const MAX_LAYERS: usize = 8;
const KINDS: usize = GaitKind::ALL.len();

/// One gait with one parameter set, fading in from `start_s` over `duration_s`.
#[derive(Debug, Clone, Copy)]
struct Layer {
    kind: GaitKind,
    params: GaitParams,
    wave: Serpenoid,
    start_s: f64,
    duration_s: f64,
}

impl Layer {
    /// Blend weight and its time derivative at `t_s`.
    fn weight(&self, t_s: f64) -> (f64, f64) {
        smoothstep(t_s, self.start_s, self.duration_s)
    }

    fn progress(&self, t_s: f64) -> f64 {
        ((t_s - self.start_s) / self.duration_s).clamp(0.0, 1.0)
    }
}

/// The blend weight from 0 at `start_s` to 1 at `start_s + duration_s` and its time
/// derivative: smoothstep `3u² − 2u³`, C1 at both ends (zero slope where the blend
/// starts and where it ends). The one definition of the daemon's blends.
pub fn smoothstep(t_s: f64, start_s: f64, duration_s: f64) -> (f64, f64) {
    let u = ((t_s - start_s) / duration_s).clamp(0.0, 1.0);
    (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u) / duration_s)
}

/// A deviation from the layers' output that fades out: what a controller's set-points
/// differed from the selector's when it handed the joints back.
#[derive(Debug, Clone)]
struct FadingOffset {
    offset: Vec<f64>,
    start_s: f64,
    duration_s: f64,
    active: bool,
}

/// Blends between gaits and produces the joint set-points of every cycle.
#[derive(Debug, Clone)]
pub struct GaitSelector {
    layout: BodyLayout,
    table: GaitTable,
    active: GaitKind,
    blend_time_s: f64,
    /// `layers[..len]`; when `pose_base` every one of them blends over `pose`,
    /// otherwise `layers[0]` is the base (its blend is over).
    layers: [Layer; MAX_LAYERS],
    len: usize,
    pose_base: bool,
    pose: Vec<f64>,
    /// Temporal phase ψ of each gait kind, rad, and its rate at the last update.
    psi: [f64; KINDS],
    psi_rate: [f64; KINDS],
    last_t_s: Option<f64>,
    /// Limits the set-points against the last update's.
    slew: SlewLimiter,
    /// The layers' output of the last update, before the fading offset and the limit.
    last_raw: Vec<f64>,
    have_raw: bool,
    fading: FadingOffset,
    scratch_pos: Vec<f64>,
    scratch_vel: Vec<f64>,
    limited_cycles: u64,
}

impl GaitSelector {
    /// A selector running `initial` (pure, from phase 0) until the first
    /// [`GaitSelector::resync`]. `blend_time_s` is clamped into
    /// [`BLEND_TIME_RANGE_S`]. The table should have passed
    /// [`GaitTable::validate_for`]; it is not checked here.
    ///
    /// # Panics
    /// If `max_joint_speed_rad_s` is not positive and finite.
    pub fn new(
        layout: BodyLayout,
        table: GaitTable,
        initial: GaitKind,
        blend_time_s: f64,
        max_joint_speed_rad_s: f64,
    ) -> Self {
        assert!(
            max_joint_speed_rad_s.is_finite() && max_joint_speed_rad_s > 0.0,
            "max joint speed must be positive"
        );
        let n = layout.len();
        let blend_time_s = if blend_time_s.is_nan() {
            DEFAULT_BLEND_TIME_S
        } else {
            blend_time_s.clamp(BLEND_TIME_RANGE_S.0, BLEND_TIME_RANGE_S.1)
        };
        let base = Layer {
            kind: initial,
            params: *table.get(initial),
            wave: Serpenoid::for_layout(initial, table.get(initial), &layout),
            start_s: f64::NEG_INFINITY,
            duration_s: blend_time_s,
        };
        let mut psi_rate = [0.0; KINDS];
        psi_rate[initial.index()] = base.params.temporal_freq_rad_s;
        GaitSelector {
            layout,
            table,
            active: initial,
            blend_time_s,
            layers: [base; MAX_LAYERS],
            len: 1,
            pose_base: false,
            pose: vec![0.0; n],
            psi: [0.0; KINDS],
            psi_rate,
            last_t_s: None,
            slew: SlewLimiter::new(n, max_joint_speed_rad_s),
            last_raw: vec![0.0; n],
            have_raw: false,
            fading: FadingOffset {
                offset: vec![0.0; n],
                start_s: 0.0,
                duration_s: blend_time_s,
                active: false,
            },
            scratch_pos: vec![0.0; n],
            scratch_vel: vec![0.0; n],
            limited_cycles: 0,
        }
    }

    /// The gait being run or blended into.
    pub fn active(&self) -> GaitKind {
        self.active
    }

    /// Progress of the newest blend (or hand-back fade) at the last update, 0..1 (1 when
    /// none is running).
    pub fn blend_progress(&self) -> f64 {
        let layers = match (self.top_is_blend(), self.last_t_s) {
            (false, _) => 1.0,
            (true, None) => 0.0,
            (true, Some(t)) => self.layers[self.len - 1].progress(t),
        };
        let f = &self.fading;
        match (f.active, self.last_t_s) {
            (true, Some(t)) => layers.min(((t - f.start_s) / f.duration_s).clamp(0.0, 1.0)),
            (true, None) => 0.0,
            (false, _) => layers,
        }
    }

    /// While only changes of the active gait's parameters blend (every layer the active
    /// gait's, no hand-back fade, no frozen pose) and they differ only in what the blend
    /// mixes linearly (amplitudes, offsets, and ωT, the layers sharing the gait's phase),
    /// the output at the last update is that gait's serpenoid with these parameters: a
    /// controller may take over from them mid-blend and follow the rest of the change.
    /// `None` otherwise.
    pub fn same_gait_blend(&self) -> Option<GaitParams> {
        use super::params::Field::{self, *};
        const LINEAR: [Field; 5] = [
            AmplitudeLat,
            AmplitudeDor,
            OffsetLat,
            OffsetDor,
            TemporalFreq,
        ];
        let t = self.last_t_s?;
        if self.pose_base || self.fading.active || self.len < 2 {
            return None;
        }
        let layers = &self.layers[..self.len];
        if layers.iter().any(|l| l.kind != self.active) {
            return None;
        }
        let base = layers[0].params;
        let nonlinear = Field::ALL.into_iter().filter(|f| !LINEAR.contains(f));
        for f in nonlinear {
            if layers.iter().any(|l| f.get(&l.params) != f.get(&base)) {
                return None;
            }
        }
        // Each layer's share of the output, as `compose` mixes them.
        let mut p = base;
        for f in LINEAR {
            f.set(&mut p, 0.0);
        }
        let mut above = 1.0;
        for j in (0..self.len).rev() {
            let w = if j >= 1 { layers[j].weight(t).0 } else { 1.0 };
            for f in LINEAR {
                let mixed = f.get(&p) + above * w * f.get(&layers[j].params);
                f.set(&mut p, mixed);
            }
            above *= 1.0 - w;
        }
        p.temporal_freq_rad_s = self.psi_rate[self.active.index()];
        Some(p)
    }

    /// Duration of new blends, s.
    pub fn blend_time_s(&self) -> f64 {
        self.blend_time_s
    }

    pub fn table(&self) -> &GaitTable {
        &self.table
    }

    pub fn layout(&self) -> &BodyLayout {
        &self.layout
    }

    /// Temporal phase ψ of the active gait, rad (integrated, never wrapped).
    pub fn phase(&self) -> f64 {
        self.psi[self.active.index()]
    }

    /// The per-joint speed limit of the set-points, rad/s.
    pub fn max_joint_speed_rad_s(&self) -> f64 {
        self.slew.max_rad_s()
    }

    /// Update cycles in which the slew limiter had to clamp some joint.
    pub fn limited_cycles(&self) -> u64 {
        self.limited_cycles
    }

    /// Blends from what is commanded now into `kind` (with its parameters from the
    /// table), starting at `t_s`. Everything currently commanded keeps running while
    /// it fades out. Nothing happens if `kind` is already the newest layer with the
    /// table's parameters.
    pub fn set_gait(&mut self, kind: GaitKind, t_s: f64) {
        self.active = kind;
        let params = *self.table.get(kind);
        if let Some(top) = self.layers[..self.len].last()
            && top.kind == kind
            && top.params == params
        {
            return;
        }
        self.push(kind, params, t_s);
    }

    /// Validates `patch` against `kind`'s current parameters and stores the result.
    /// If `kind` is active the change is blended in from `t_s` like a gait switch
    /// (phase continuous, no step). Allocates nothing, also when it refuses.
    pub fn set_params(
        &mut self,
        kind: GaitKind,
        patch: &ParamPatch,
        t_s: f64,
    ) -> Result<(), ParamError> {
        let next = self
            .table
            .get(kind)
            .patched_for(kind, patch, self.layout.module_length_m)?;
        *self.table.get_mut(kind) = next;
        if kind == self.active {
            self.set_gait(kind, t_s);
        }
        Ok(())
    }

    /// Sets the duration of blends started from now on, s (within
    /// [`BLEND_TIME_RANGE_S`]).
    pub fn set_blend_time(&mut self, s: f64) -> Result<(), ParamError> {
        let (min, max) = BLEND_TIME_RANGE_S;
        if !s.is_finite() {
            return Err(ParamError::NotFinite {
                field: "blend_time_s",
            });
        }
        if !(min..=max).contains(&s) {
            return Err(ParamError::OutOfRange {
                field: "blend_time_s",
                value: s,
                min,
                max,
            });
        }
        self.blend_time_s = s;
        Ok(())
    }

    /// Restarts from `measured` (one angle per joint, rad): the next set-points equal
    /// it exactly and blend into the active gait over the blend time. A non-finite
    /// entry (which the failsafe never lets through) starts that joint on the gait.
    pub fn resync(&mut self, measured: &[f64], t_s: f64) {
        debug_assert_eq!(measured.len(), self.pose.len(), "one angle per joint");
        let kind = self.active;
        let params = *self.table.get(kind);
        let wave = Serpenoid::for_layout(kind, &params, &self.layout);
        wave.evaluate(&self.layout, self.psi[kind.index()], &mut self.scratch_pos);
        for ((pose, &m), &fallback) in self.pose.iter_mut().zip(measured).zip(&self.scratch_pos) {
            *pose = if m.is_finite() { m } else { fallback };
        }
        self.pose_base = true;
        self.len = 0;
        self.push(kind, params, t_s);
        self.fading.active = false;
        self.slew.reset_to(&self.pose);
        self.last_t_s = Some(t_s);
    }

    /// Set-points for the cycle at `t_s` (non-decreasing; an earlier time counts as no
    /// time passed): positions, rad, and their velocity feed-forward, rad/s.
    ///
    /// # Panics
    /// If a slice does not hold exactly one entry per joint.
    pub fn update(&mut self, t_s: f64, positions_out: &mut [f64], velocities_out: &mut [f64]) {
        debug_assert_eq!(positions_out.len(), self.pose.len());
        debug_assert_eq!(velocities_out.len(), self.pose.len());
        let dt = match self.last_t_s {
            Some(last) => (t_s - last).max(0.0),
            None => 0.0,
        };
        self.prune(t_s);
        self.advance_phases(t_s, dt);
        self.compose(t_s, positions_out, velocities_out);
        self.last_raw.copy_from_slice(positions_out);
        self.have_raw = true;
        self.fade(t_s, positions_out, velocities_out);
        if self.slew.apply(dt, positions_out, velocities_out, false) {
            self.limited_cycles += 1;
        }
        self.last_t_s = Some(t_s);
    }

    /// Takes the joints back from a controller that sent `commanded` last cycle while
    /// the layers ran underneath: the difference fades out over the blend time on top
    /// of the layers, which keep moving (no frozen pose, no stall), so the next
    /// set-points continue from `commanded`. Before any update it is a [`Self::resync`].
    pub fn hand_back(&mut self, commanded: &[f64], t_s: f64) {
        debug_assert_eq!(commanded.len(), self.last_raw.len(), "one angle per joint");
        if !self.have_raw {
            self.resync(commanded, t_s);
            return;
        }
        let f = &mut self.fading;
        for ((o, &c), &raw) in f.offset.iter_mut().zip(commanded).zip(&self.last_raw) {
            *o = if c.is_finite() { c - raw } else { 0.0 };
        }
        f.start_s = t_s;
        f.duration_s = self.blend_time_s;
        f.active = true;
        self.slew.reset_to(commanded);
    }

    /// Adds what is left of the fading offset (and its rate) to the set-points.
    fn fade(&mut self, t_s: f64, pos: &mut [f64], vel: &mut [f64]) {
        let f = &mut self.fading;
        if !f.active {
            return;
        }
        let (w, w_dot) = smoothstep(t_s, f.start_s, f.duration_s);
        for ((p, v), &o) in pos.iter_mut().zip(vel.iter_mut()).zip(&f.offset) {
            *p += (1.0 - w) * o;
            *v -= w_dot * o;
        }
        f.active = w < 1.0;
    }

    /// Whether a hand-back's offset is still fading out.
    pub fn handing_back(&self) -> bool {
        self.fading.active
    }

    fn top_is_blend(&self) -> bool {
        self.pose_base || self.len > 1
    }

    /// First layer index that blends over what is below it.
    fn first_blend(&self) -> usize {
        if self.pose_base { 0 } else { 1 }
    }

    fn push(&mut self, kind: GaitKind, params: GaitParams, t_s: f64) {
        self.prune(t_s);
        if self.len == MAX_LAYERS {
            self.collapse_oldest();
        }
        if !self.layers[..self.len].iter().any(|l| l.kind == kind) {
            // A kind that starts running again starts at its own ωT.
            self.psi_rate[kind.index()] = params.temporal_freq_rad_s;
        }
        self.layers[self.len] = Layer {
            kind,
            params,
            wave: Serpenoid::for_layout(kind, &params, &self.layout),
            start_s: t_s,
            duration_s: self.blend_time_s,
        };
        self.len += 1;
    }

    /// Drops every layer hidden under a finished blend.
    fn prune(&mut self, t_s: f64) {
        let first = self.first_blend();
        let finished = (first..self.len)
            .rev()
            .find(|&j| self.layers[j].progress(t_s) >= 1.0);
        if let Some(j) = finished {
            self.layers.copy_within(j..self.len, 0);
            self.len -= j;
            self.pose_base = false;
        }
    }

    /// Freezes the base and the first blend over it into `pose`, as they were at the
    /// last update (a switch arrives between updates, so this moves nothing by more
    /// than one cycle's motion, which the slew limiter bounds anyway).
    fn collapse_oldest(&mut self) {
        let t = self.last_t_s.unwrap_or(f64::NEG_INFINITY);
        let first = self.first_blend();
        if !self.pose_base {
            let base = self.layers[0];
            base.wave
                .evaluate(&self.layout, self.psi[base.kind.index()], &mut self.pose);
        }
        let layer = self.layers[first];
        layer.wave.evaluate(
            &self.layout,
            self.psi[layer.kind.index()],
            &mut self.scratch_pos,
        );
        let (w, _) = layer.weight(t);
        for (p, &g) in self.pose.iter_mut().zip(&self.scratch_pos) {
            *p += w * (g - *p);
        }
        self.layers.copy_within(first + 1..self.len, 0);
        self.len -= first + 1;
        self.pose_base = true;
    }

    /// Integrates each running kind's phase (trapezoid) with its ωT, averaged over
    /// that kind's layers by their weight in the output, so a change of ωT blends in
    /// and the phase never jumps.
    fn advance_phases(&mut self, t_s: f64, dt: f64) {
        let mut num = [0.0; KINDS];
        let mut den = [0.0; KINDS];
        let mut newest = [f64::NAN; KINDS];
        // Effective weight of layer j: w_j · Π_{i>j} (1 − w_i); the base gets Π (1 − w_i).
        let mut above = 1.0;
        let first = self.first_blend();
        for j in (0..self.len).rev() {
            let layer = &self.layers[j];
            let w = if j >= first { layer.weight(t_s).0 } else { 1.0 };
            let k = layer.kind.index();
            num[k] += above * w * layer.params.temporal_freq_rad_s;
            den[k] += above * w;
            if newest[k].is_nan() {
                newest[k] = layer.params.temporal_freq_rad_s;
            }
            above *= 1.0 - w;
        }
        for k in 0..KINDS {
            if newest[k].is_nan() {
                continue;
            }
            let rate = if den[k] > 1e-12 {
                num[k] / den[k]
            } else {
                newest[k]
            };
            self.psi[k] += 0.5 * (self.psi_rate[k] + rate) * dt;
            self.psi_rate[k] = rate;
        }
    }

    /// Evaluates the layer stack at `t_s` into `pos`/`vel`.
    fn compose(&mut self, t_s: f64, pos: &mut [f64], vel: &mut [f64]) {
        let first = self.first_blend();
        if self.pose_base {
            pos.copy_from_slice(&self.pose);
            vel.fill(0.0);
        } else {
            let base = &self.layers[0];
            let k = base.kind.index();
            base.wave
                .evaluate_with_velocity(&self.layout, self.psi[k], self.psi_rate[k], pos, vel);
        }
        for j in first..self.len {
            let layer = &self.layers[j];
            let k = layer.kind.index();
            layer.wave.evaluate_with_velocity(
                &self.layout,
                self.psi[k],
                self.psi_rate[k],
                &mut self.scratch_pos,
                &mut self.scratch_vel,
            );
            let (w, w_dot) = layer.weight(t_s);
            let layer_out = self.scratch_pos.iter().zip(&self.scratch_vel);
            for ((p, v), (&g, &g_dot)) in pos.iter_mut().zip(vel.iter_mut()).zip(layer_out) {
                let diff = g - *p;
                *v += w * (g_dot - *v) + w_dot * diff;
                *p += w * diff;
            }
        }
    }
}

#[cfg(test)]
#[path = "selector_tests.rs"]
mod tests;
