//! Where the body is in the world of an outside position source (motion capture, a
//! total station): the external fixes (`external_pose`) fused with the body's own
//! motion between them (contact odometry and the heading, `BodyEstimate`).
//!
//! The source's world and the estimate's are both z up; one is the other turned by a
//! yaw ψ and shifted by t (in the ground plane). Each cycle the chassis' own estimate
//! goes into a short history; a fix is compared with where the tracked point (the
//! chassis, or a marker on the head at an offset) was **when the fix was measured**
//! (the source's latency compensated from the history), not where it is now.
//!
//! - **Aligning**: the first fix with an orientation gives ψ at once (the tracked body's
//!   yaw in both worlds); without one, ψ comes from the direction both saw the point
//!   travel once it has moved [`ALIGN_TRAVEL_M`]. t then puts the point on the fix.
//! - **Tracking**: t follows each fix by a Kalman gain (the fix's variance against the
//!   odometry's drift since the last), ψ slowly by the orientation where there is one
//!   (the estimate's yaw drifts with the gyros). A fix farther than the gate from where
//!   the point should be is rejected and counted; so many in a row mean the alignment
//!   is wrong (a source that re-based, a slipped marker): it aligns afresh.
//! - **Stale**: no fix accepted for `max_age_s`: the position is no longer given as
//!   valid (the heading-only estimate of the body's own sensors remains), never a stale
//!   position taken as fresh; the next fix resumes tracking.
//!
//! The history is allocated once; updates allocate nothing.

use super::external_pose::{ExternalFixEstimator, Fix, PoseReader};
pub use crate::controller_interface::position::{PositionState, WorldPosition};
use crate::controller_interface::{BodyEstimate, Estimator, Observation};
use crate::num::wrap_pi;

/// Without an orientation, the point must travel this far in both worlds before their
/// yaw is taken from the directions, m.
pub const ALIGN_TRAVEL_M: f64 = 0.3;
/// Cycles of history kept (2 s at 1 kHz): fixes measured longer ago are too late.
pub const HISTORY: usize = 2048;

/// What the source tracks.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Tracked {
    /// The virtual chassis' origin (a rigid set of markers along the backbone, a
    /// simulated source).
    Chassis,
    /// A marker on the head link, at `marker_offset_m` in the head's frame.
    Head,
}

/// How the fixes are fused (`[pose]` in the daemon's configuration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusionConfig {
    pub tracked: Tracked,
    /// The marker in the head link's frame (x toward the nose, z up), m (`Head` only).
    pub marker_offset_m: [f64; 2],
    /// A fix's standard deviation when the source gives none, m.
    pub default_sd_m: f64,
    /// How fast odometry drifts between fixes, m per √s (the prediction's noise).
    pub drift_m_per_sqrt_s: f64,
    /// And how much of what odometry reads between fixes may be wrong (among pegs
    /// contact odometry reads the gait's open-ground motion, and jumps when the links'
    /// contacts change): the prediction's deviation grows by this share of it.
    pub drift_per_m: f64,
    /// Fixes farther than this, or `gate_sigmas` of the fix's deviation, are rejected, m.
    pub gate_m: f64,
    pub gate_sigmas: f64,
    /// This many rejections in a row align afresh.
    pub realign_after: u32,
    /// How much of the orientation's yaw error each fix corrects (0..1).
    pub yaw_gain: f64,
    /// Without an accepted fix for this long the position is stale, s.
    pub max_age_s: f64,
    /// The velocity's low-pass time constant, s.
    pub velocity_tau_s: f64,
}

impl Default for FusionConfig {
    fn default() -> Self {
        Self {
            tracked: Tracked::Chassis,
            marker_offset_m: [0.0; 2],
            default_sd_m: 0.005,
            drift_m_per_sqrt_s: 0.05,
            drift_per_m: 0.5,
            gate_m: 0.15,
            gate_sigmas: 5.0,
            realign_after: 10,
            yaw_gain: 0.05,
            max_age_s: 0.5,
            velocity_tau_s: 0.2,
        }
    }
}

/// One cycle of the body's own estimate, as the history keeps it.
#[derive(Debug, Clone, Copy, Default)]
struct Sample {
    t_s: f64,
    /// The chassis origin in the estimate's world (contact odometry), m.
    chassis: [f64; 2],
    /// The tracked point there, m.
    point: [f64; 2],
    /// The tracked body's yaw there, rad.
    yaw: f64,
}

fn lerp(a: f64, b: f64, w: f64) -> f64 {
    a + (b - a) * w
}

fn rotate(psi: f64, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = psi.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

fn yaw_of(q: [f64; 4]) -> f64 {
    let [w, x, y, z] = q;
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// The fusion, run by the loop after the body's own estimators.
pub struct WorldPositionEstimator {
    config: FusionConfig,
    fixes: ExternalFixEstimator,
    history: Vec<Sample>,
    /// Next slot to write; `len` samples are valid.
    head: usize,
    len: usize,
    last_fix: u64,
    /// ψ and t: source = R(ψ)·estimate + t.
    psi: f64,
    shift: [f64; 2],
    /// The shift's variance, m².
    var: f64,
    last_accepted_t_s: f64,
    /// Where the point was (the estimate's world) at the last accepted fix.
    last_accepted_point: Option<[f64; 2]>,
    rejections_in_row: u32,
    /// Without an orientation: the first fix and where the point was then.
    anchor: Option<([f64; 2], [f64; 2])>,
    out: WorldPosition,
    last_position: Option<(f64, [f64; 2])>,
}

impl WorldPositionEstimator {
    pub fn new(reader: PoseReader, config: FusionConfig) -> Self {
        Self {
            config,
            fixes: ExternalFixEstimator::new(reader),
            history: vec![Sample::default(); HISTORY],
            head: 0,
            len: 0,
            last_fix: 0,
            psi: 0.0,
            shift: [0.0; 2],
            var: 0.0,
            last_accepted_t_s: f64::NEG_INFINITY,
            last_accepted_point: None,
            rejections_in_row: 0,
            anchor: None,
            out: WorldPosition::NONE,
            last_position: None,
        }
    }

    fn sample(&self, b: &BodyEstimate, t_s: f64) -> Sample {
        let chassis = b.odometry_m;
        let (point, yaw) = match self.config.tracked {
            Tracked::Chassis => (chassis, b.heading_rad),
            Tracked::Head => {
                let yaw = yaw_of(b.head_wxyz);
                let head = [chassis[0] - b.position_m[0], chassis[1] - b.position_m[1]];
                let o = rotate(yaw, self.config.marker_offset_m);
                ([head[0] + o[0], head[1] + o[1]], yaw)
            }
        };
        Sample {
            t_s,
            chassis,
            point,
            yaw,
        }
    }

    fn push(&mut self, s: Sample) {
        self.history[self.head] = s;
        self.head = (self.head + 1) % HISTORY;
        self.len = (self.len + 1).min(HISTORY);
    }

    /// The `k`-th oldest sample kept.
    fn at(&self, k: usize) -> Sample {
        self.history[(self.head + HISTORY - self.len + k) % HISTORY]
    }

    /// The body's own estimate at `t_s` (interpolated; `None`: before the history).
    fn back_then(&self, t_s: f64) -> Option<Sample> {
        if self.len == 0 || t_s < self.at(0).t_s {
            return None;
        }
        let newest = self.at(self.len - 1);
        if t_s >= newest.t_s {
            return Some(newest);
        }
        // The last sample at or before t_s, by bisection.
        let (mut lo, mut hi) = (0, self.len - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.at(mid).t_s <= t_s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (self.at(lo), self.at(hi));
        let w = if b.t_s > a.t_s {
            (t_s - a.t_s) / (b.t_s - a.t_s)
        } else {
            0.0
        };
        let mix = |p: [f64; 2], q: [f64; 2]| [lerp(p[0], q[0], w), lerp(p[1], q[1], w)];
        Some(Sample {
            t_s,
            chassis: mix(a.chassis, b.chassis),
            point: mix(a.point, b.point),
            yaw: a.yaw + w * wrap_pi(b.yaw - a.yaw),
        })
    }

    /// Aligns the worlds on `fix` and where the point was then (`false`: not yet).
    fn align(&mut self, fix: &Fix, then: &Sample) -> bool {
        let p = [fix.position_m[0], fix.position_m[1]];
        let psi = match fix.orientation_wxyz {
            Some(q) => wrap_pi(yaw_of(q) - then.yaw),
            None => {
                let Some((p0, e0)) = self.anchor else {
                    self.anchor = Some((p, then.point));
                    return false;
                };
                let ds = [p[0] - p0[0], p[1] - p0[1]];
                let de = [then.point[0] - e0[0], then.point[1] - e0[1]];
                if ds[0].hypot(ds[1]) < ALIGN_TRAVEL_M || de[0].hypot(de[1]) < ALIGN_TRAVEL_M {
                    return false;
                }
                wrap_pi(ds[1].atan2(ds[0]) - de[1].atan2(de[0]))
            }
        };
        let r = rotate(psi, then.point);
        self.psi = psi;
        self.shift = [p[0] - r[0], p[1] - r[1]];
        self.var = self.fix_sd(fix).powi(2);
        self.anchor = None;
        self.out.alignments += 1;
        true
    }

    fn fix_sd(&self, fix: &Fix) -> f64 {
        if fix.position_sd_m.is_finite() {
            fix.position_sd_m
        } else {
            self.config.default_sd_m
        }
    }

    /// A fix while tracking: gated, then t (and ψ) corrected.
    fn correct(&mut self, fix: &Fix, then: &Sample) {
        let c = self.config;
        let sd = self.fix_sd(fix);
        // The shift's variance has grown with odometry's drift since the last fix, in
        // time and with what it read: a jump of the odometry widens the gate, so the
        // next fixes correct it instead of being rejected as outliers.
        let dt = (fix.t_s - self.last_accepted_t_s).max(0.0);
        let read = self
            .last_accepted_point
            .map_or(0.0, |p| (then.point[0] - p[0]).hypot(then.point[1] - p[1]));
        let var = self.var + c.drift_m_per_sqrt_s.powi(2) * dt + (c.drift_per_m * read).powi(2);
        if let Some(q) = fix.orientation_wxyz {
            // Turn about the point as it was then, so ψ's correction moves nothing there.
            let psi = self.psi + c.yaw_gain * wrap_pi(yaw_of(q) - then.yaw - self.psi);
            let before = self.predict(then.point);
            let r = rotate(psi, then.point);
            self.psi = wrap_pi(psi);
            self.shift = [before[0] - r[0], before[1] - r[1]];
        }
        let predicted = self.predict(then.point);
        let innovation = [
            fix.position_m[0] - predicted[0],
            fix.position_m[1] - predicted[1],
        ];
        let gate = c.gate_m.max(c.gate_sigmas * (var + sd * sd).sqrt());
        if innovation[0].hypot(innovation[1]) > gate {
            self.out.rejected += 1;
            self.rejections_in_row += 1;
            if self.rejections_in_row >= c.realign_after {
                // The worlds moved apart: align afresh on this fix.
                self.rejections_in_row = 0;
                if self.align(fix, then) {
                    self.accepted(fix.t_s, then.point);
                }
            }
            return;
        }
        let k = var / (var + sd * sd);
        self.shift[0] += k * innovation[0];
        self.shift[1] += k * innovation[1];
        self.var = (1.0 - k) * var;
        self.accepted(fix.t_s, then.point);
    }

    fn accepted(&mut self, t_s: f64, point: [f64; 2]) {
        self.rejections_in_row = 0;
        self.last_accepted_t_s = t_s;
        self.last_accepted_point = Some(point);
        self.out.accepted += 1;
    }

    fn predict(&self, p: [f64; 2]) -> [f64; 2] {
        let r = rotate(self.psi, p);
        [r[0] + self.shift[0], r[1] + self.shift[1]]
    }

    /// Takes a new fix, if any.
    fn take(&mut self, f: &Fix) {
        let Some(then) = self.back_then(f.t_s) else {
            self.out.late += 1;
            return;
        };
        match self.out.state {
            PositionState::None | PositionState::Aligning => {
                self.out.state = PositionState::Aligning;
                if self.align(f, &then) {
                    self.accepted(f.t_s, then.point);
                    self.out.state = PositionState::Tracking;
                }
            }
            PositionState::Tracking | PositionState::Stale => self.correct(f, &then),
        }
    }
}

impl Estimator for WorldPositionEstimator {
    fn update(&mut self, t_s: f64, obs: &Observation<'_>, out: &mut BodyEstimate) {
        self.fixes.update(t_s, obs, out);
        if !out.valid {
            // Nothing of the body's own to carry a position with: the age runs on.
            self.out.age_s = t_s - self.last_accepted_t_s;
            if self.out.state == PositionState::Tracking && self.out.age_s > self.config.max_age_s {
                self.out.state = PositionState::Stale;
            }
            out.world = self.out;
            return;
        }
        let now = self.sample(out, t_s);
        self.push(now);
        let f = self.fixes.latest();
        if f.number != self.last_fix {
            self.last_fix = f.number;
            self.take(&f);
        }
        let c = self.config;
        let o = &mut self.out;
        o.age_s = t_s - self.last_accepted_t_s;
        if matches!(o.state, PositionState::Tracking | PositionState::Stale) {
            o.state = if o.age_s > c.max_age_s {
                PositionState::Stale
            } else {
                PositionState::Tracking
            };
            let r = rotate(self.psi, now.chassis);
            let p = [r[0] + self.shift[0], r[1] + self.shift[1]];
            if let Some((t0, p0)) = self.last_position {
                let dt = t_s - t0;
                if dt > 0.0 {
                    let a = dt / (c.velocity_tau_s + dt);
                    for i in 0..2 {
                        o.velocity_m_s[i] += a * ((p[i] - p0[i]) / dt - o.velocity_m_s[i]);
                    }
                }
            }
            self.last_position = Some((t_s, p));
            o.position_m = p;
            o.heading_rad = wrap_pi(out.heading_rad + self.psi);
            o.sd_m = (self.var + c.drift_m_per_sqrt_s.powi(2) * o.age_s.max(0.0)).sqrt();
            o.yaw_offset_rad = self.psi;
        }
        out.world = self.out;
    }
}

#[cfg(test)]
#[path = "world_position_tests.rs"]
mod tests;
