//! What ends a displacement trial early: the body's centre has left the obstacle field.
//! Past the field's edge the snake travels on open ground, and a trial that ran on
//! would score open-ground speed as speed through the obstacles (on the rock pile such
//! trials made most of the spread: the measurements' history, `git show
//! fcea847:docs/measurements.md`, "Directional compliance per body section").

use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::lab::experiment::Goal;

/// The obstacles' bounding box in the ground plane; the trial ends when the body's
/// centre (mean of the links, as the metric measures it) is outside it. No box (a
/// world without pegs or rocks): the trial runs its whole time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FieldEdge {
    pub bounds_m: Option<([f64; 2], [f64; 2])>,
}

impl FieldEdge {
    /// A goal never reached: the trial runs its whole time.
    pub const FULL_TIME: FieldEdge = FieldEdge { bounds_m: None };

    /// The box around every peg (its full diameter) and every rock point of `world`.
    pub fn of(world: &WorldSpec) -> Self {
        let mut pts: Vec<[f64; 2]> = Vec::new();
        for p in &world.pegs {
            let r = p.diameter_m / 2.0;
            pts.push([p.x_m - r, p.y_m - r]);
            pts.push([p.x_m + r, p.y_m + r]);
        }
        for rock in &world.rocks {
            pts.extend(
                rock.points_m
                    .iter()
                    .map(|q| [rock.center_m[0] + q[0], rock.center_m[1] + q[1]]),
            );
        }
        let bounds_m = pts.first().map(|&first| {
            pts.iter().fold((first, first), |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            })
        });
        FieldEdge { bounds_m }
    }

    /// Whether the point `c` lies outside the box.
    pub fn outside(&self, c: [f64; 2]) -> bool {
        self.bounds_m
            .is_some_and(|(lo, hi)| c[0] < lo[0] || c[0] > hi[0] || c[1] < lo[1] || c[1] > hi[1])
    }
}

impl Goal for FieldEdge {
    fn reached(&self, plant: &dyn Plant) -> bool {
        let n = plant.link_count();
        if n == 0 {
            return false;
        }
        let mut c = [0.0, 0.0];
        for k in 0..n {
            let p = plant.link_pose(k).position_m;
            c = [c[0] + p[0], c[1] + p[1]];
        }
        self.outside([c[0] / n as f64, c[1] / n as f64])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::spec::Peg;

    #[test]
    fn the_box_spans_the_pegs_and_a_point_past_it_is_outside() {
        let peg = |x_m, y_m| Peg {
            x_m,
            y_m,
            diameter_m: 0.04,
            height_m: 0.1,
        };
        let world = WorldSpec {
            pegs: vec![peg(-1.0, 0.5), peg(1.0, -0.5)],
            ..WorldSpec::default()
        };
        let edge = FieldEdge::of(&world);
        assert_eq!(edge.bounds_m, Some(([-1.02, -0.52], [1.02, 0.52])));
        assert!(!edge.outside([0.0, 0.0]));
        assert!(!edge.outside([1.0, 0.5]));
        assert!(edge.outside([1.1, 0.0]));
        assert!(edge.outside([0.0, -0.6]));
        assert!(!FieldEdge::of(&WorldSpec::default()).outside([9.0, 9.0]));
        assert!(!FieldEdge::FULL_TIME.outside([9.0, 9.0]));
    }
}
