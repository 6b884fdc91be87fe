//! The peg array of the sidewinding experiment as the metrics see it: a line of pegs
//! (the scenario's `[[peg_fence]]`), the openings between neighbours, which side the
//! snake starts on, and when a trial is over.

use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::PegFence;
use crate::lab::experiment::Goal;
use crate::module::{MODULE_LENGTH_M, MODULE_RADIUS_M};

/// Beyond either end of the array by this much, the body has gone round it, m.
pub const OFF_END_M: f64 = 0.3;
/// Back from the array by this much on the start side, the body has left the board, m.
pub const RETREAT_M: f64 = 1.0;

/// One opening: the free gap between two neighbouring pegs, as arc length along the
/// array's line, m.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Opening {
    pub from_m: f64,
    pub to_m: f64,
}

impl Opening {
    pub fn width_m(&self) -> f64 {
        self.to_m - self.from_m
    }
}

/// The array's line and openings, and the side the trial must get to.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fence {
    origin_m: [f64; 2],
    /// Unit vector along the line.
    along: [f64; 2],
    /// Unit normal pointing to the far side (away from the start).
    normal: [f64; 2],
    pub length_m: f64,
    pub openings: Vec<Opening>,
    /// A link whose centre is this far beyond the line has passed the pegs, m (peg
    /// radius, the pegs' jitter off the line and the module's radius).
    pub clear_m: f64,
}

impl Fence {
    /// The array of `fence` in `world` (whose pegs it generated, among others: only the
    /// pegs within its jitter of the line count), the far side the one the middle of
    /// the start's straight body of `modules` is not on.
    pub fn new(fence: &PegFence, world: &WorldSpec, modules: usize) -> Self {
        let (sin, cos) = fence.direction_rad.sin_cos();
        let along = [cos, sin];
        let mut normal = [-sin, cos];
        let origin_m = fence.start_m;
        let rel = |p: [f64; 2]| [p[0] - origin_m[0], p[1] - origin_m[1]];
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let r = fence.diameter_m / 2.0;
        let mut us: Vec<f64> = world
            .pegs
            .iter()
            .map(|p| rel([p.x_m, p.y_m]))
            .filter(|q| dot(*q, normal).abs() <= fence.jitter_m + 1e-9)
            .map(|q| dot(q, along))
            .collect();
        us.sort_by(f64::total_cmp);
        let openings = us
            .windows(2)
            .map(|w| Opening {
                from_m: w[0] + r,
                to_m: w[1] - r,
            })
            .collect();
        let s = &world.start;
        let (ys, yc) = s.yaw_rad.sin_cos();
        let half = modules as f64 * MODULE_LENGTH_M / 2.0;
        let mid = [s.head_m[0] + yc * half, s.head_m[1] + ys * half];
        if dot(rel(mid), normal) > 0.0 {
            normal = [-normal[0], -normal[1]];
        }
        Self {
            origin_m,
            along,
            normal,
            length_m: fence.length_m,
            openings,
            clear_m: r + fence.jitter_m + MODULE_RADIUS_M,
        }
    }

    /// `p` as (arc length along the line, signed distance beyond it towards the far
    /// side), m.
    pub fn coords(&self, p: [f64; 2]) -> (f64, f64) {
        let q = [p[0] - self.origin_m[0], p[1] - self.origin_m[1]];
        (
            q[0] * self.along[0] + q[1] * self.along[1],
            q[0] * self.normal[0] + q[1] * self.normal[1],
        )
    }

    /// The far side's direction (the travel the trial asks for), unit.
    pub fn forward(&self) -> [f64; 2] {
        self.normal
    }

    /// The opening at arc length `u`: the one containing it, or the nearest.
    pub fn opening_at(&self, u: f64) -> Option<usize> {
        let gap = |o: &Opening| {
            if u < o.from_m {
                o.from_m - u
            } else if u > o.to_m {
                u - o.to_m
            } else {
                0.0
            }
        };
        (0..self.openings.len())
            .min_by(|&a, &b| gap(&self.openings[a]).total_cmp(&gap(&self.openings[b])))
    }

    /// Every link beyond the pegs.
    pub fn through(&self, links: impl IntoIterator<Item = [f64; 2]>) -> bool {
        links.into_iter().all(|p| self.coords(p).1 > self.clear_m)
    }

    /// The body (its centre `c`) went round an end of the array or back from it.
    pub fn off_board(&self, c: [f64; 2]) -> bool {
        let (u, d) = self.coords(c);
        u < -OFF_END_M || u > self.length_m + OFF_END_M || d < -RETREAT_M
    }
}

/// A trial is over when the body has passed the array or left the board.
impl Goal for Fence {
    fn reached(&self, plant: &dyn Plant) -> bool {
        let n = plant.link_count();
        let link = |k: usize| {
            let p = plant.link_pose(k).position_m;
            [p[0], p[1]]
        };
        if self.through((0..n).map(link)) {
            return true;
        }
        let c = (0..n).map(link).fold([0.0, 0.0], |a, p| {
            [a[0] + p[0] / n as f64, a[1] + p[1] / n as f64]
        });
        self.off_board(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::scenario::WorldScenario;

    const FENCE: &str = "seed = 5\n[[peg_fence]]\nstart_m = [-2.0, -0.5]\nlength_m = 4.0\n\
        diameter_m = 0.05\ngap_m = [0.1, 0.3]\njitter_m = 0.02\n\
        [start]\nhead_m = [0.5, 0.0]\nyaw_rad = 3.14159\n";

    fn fence() -> Fence {
        let s = WorldScenario::parse(FENCE).unwrap();
        let w = s.generate(18).unwrap();
        Fence::new(&s.peg_fences[0], &w, 18)
    }

    #[test]
    fn the_far_side_is_away_from_the_start_and_openings_are_the_gaps() {
        let f = fence();
        assert_eq!(f.forward().map(|v| v.round()), [0.0, -1.0]);
        assert!(f.openings.len() > 8);
        for o in &f.openings {
            assert!((0.1..0.3).contains(&o.width_m()), "{o:?}");
        }
        let (u, d) = f.coords([0.0, -0.8]);
        assert!((u - 2.0).abs() < 1e-12 && (d - 0.3).abs() < 1e-12);
        let mid = (f.openings[3].from_m + f.openings[3].to_m) / 2.0;
        assert_eq!(f.opening_at(mid), Some(3));
        assert_eq!(f.opening_at(-5.0), Some(0));
        assert!(f.through([[0.0, -0.7], [0.3, -0.9]]));
        assert!(!f.through([[0.0, -0.7], [0.3, -0.5]]));
        assert!(f.off_board([-2.5, 0.0]) && f.off_board([0.0, 0.6]));
        assert!(!f.off_board([0.0, 0.0]));
    }
}
