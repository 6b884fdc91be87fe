//! The poles of the climbing experiment: a named set and seeded ones, each a foot
//! section and diameter changes (steps, and tapers as fine steps) of up to ±30 % of
//! the foot's diameter along its height; and where the body starts beside one.

use std::f64::consts::TAU;

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use crate::emu::world::{Pole, PoleSection, StartPose, WorldSpec};
use crate::module::MODULE_DIAMETER_M;

/// Modules on the body the starts are laid out for.
const MODULES: usize = 18;
/// Height of every pole, m.
pub const POLE_HEIGHT_M: f64 = 1.5;
/// The top is reached when the body's centre is this high, m: above every change.
pub const TOP_M: f64 = 1.2;
/// Changes happen between these heights, m.
const CHANGES_M: [f64; 2] = [0.4, 1.0];
/// Sections a taper is cut into per 0.1 m.
const TAPER_STEPS_PER_DM: f64 = 4.0;
/// Foot diameters of the seeded poles, m (thinner feet leave the joints no room to
/// tighten by 30 %: docs/lab.md).
const FOOT_M: [f64; 2] = [0.15, 0.18];

/// One change of diameter: from the previous diameter to `factor` × the foot's,
/// starting at `at_m`, over `length_m` (0: a step).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Change {
    pub at_m: f64,
    pub length_m: f64,
    pub factor: f64,
}

/// A pole design: its name, foot diameter and changes (bottom to top).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoleDesign {
    pub name: String,
    pub foot_m: f64,
    pub changes: Vec<Change>,
}

const fn step(at_m: f64, factor: f64) -> Change {
    Change {
        at_m,
        length_m: 0.0,
        factor,
    }
}

const fn taper(at_m: f64, length_m: f64, factor: f64) -> Change {
    Change {
        at_m,
        length_m,
        factor,
    }
}

/// The named set: steps and tapers both ways, a waist and a bulge.
pub fn named_set() -> Vec<PoleDesign> {
    let d = |name: &str, foot_m: f64, changes: &[Change]| PoleDesign {
        name: name.into(),
        foot_m,
        changes: changes.to_vec(),
    };
    vec![
        d("step-up", 0.15, &[step(0.6, 1.28)]),
        d("step-down", 0.18, &[step(0.6, 0.72)]),
        d("taper-up", 0.15, &[taper(0.4, 0.6, 1.3)]),
        d("taper-down", 0.18, &[taper(0.4, 0.6, 0.7)]),
        d("waist", 0.17, &[step(0.5, 0.75), step(0.85, 1.0)]),
        d("bulge", 0.15, &[step(0.5, 1.27), step(0.85, 1.0)]),
    ]
}

/// A seeded pole: foot 0.15–0.18 m, two or three changes between 0.4 and 1.0 m, each a
/// step or a taper to 0.7–1.3 × the foot.
pub fn seeded(seed: u64) -> PoleDesign {
    let mut rng = Pcg64::seed_from_u64(seed);
    let foot_m = rng.random_range(FOOT_M[0]..FOOT_M[1]);
    let count = rng.random_range(2..=3usize);
    let span = (CHANGES_M[1] - CHANGES_M[0]) / count as f64;
    let changes = (0..count)
        .map(|k| {
            let at_m = CHANGES_M[0] + span * (k as f64 + rng.random_range(0.0..0.3));
            let length_m = if rng.random_bool(0.5) {
                0.0
            } else {
                rng.random_range(0.1..0.6 * span)
            };
            // At least 10 % from the previous diameter: every change is a change.
            let mut factor: f64 = rng.random_range(0.7..1.3);
            if (factor - 1.0).abs() < 0.1 {
                factor = 1.0 + 0.1f64.copysign(factor - 1.0);
            }
            Change {
                at_m,
                length_m,
                factor,
            }
        })
        .collect();
    PoleDesign {
        name: format!("seed{seed}"),
        foot_m,
        changes,
    }
}

impl PoleDesign {
    /// The pole's identity: a hash of its description (name, foot, changes), so a
    /// seeded pole's follows from its seed and a named one's from its shape.
    pub fn identity(&self) -> u64 {
        crate::lab::layout::identity_of(format!("{self:?}").as_bytes())
    }

    /// The pole's sections, bottom to top.
    pub fn sections(&self) -> Vec<PoleSection> {
        let mut out = Vec::new();
        let (mut z, mut d) = (0.0, self.foot_m);
        let mut push = |z1: f64, d: f64, z: &mut f64| {
            if z1 > *z + 1e-6 {
                out.push(PoleSection {
                    z0_m: *z,
                    z1_m: z1,
                    diameter_m: d,
                });
                *z = z1;
            }
        };
        for c in &self.changes {
            push(c.at_m, d, &mut z);
            let to = self.foot_m * c.factor;
            let steps = (c.length_m * 10.0 * TAPER_STEPS_PER_DM).ceil() as usize;
            for k in 1..=steps {
                let f = k as f64 / steps as f64;
                let dk = d + (to - d) * (f - 0.5 / steps as f64);
                push(c.at_m + c.length_m * f, dk, &mut z);
            }
            d = to;
        }
        push(POLE_HEIGHT_M, d, &mut z);
        out
    }

    /// The pole's largest change from its foot, as a fraction (±).
    pub fn largest_change(&self) -> f64 {
        self.changes
            .iter()
            .map(|c| c.factor - 1.0)
            .fold(0.0, |a: f64, b| if b.abs() > a.abs() { b } else { a })
    }

    /// The world of start `start`: this pole at the origin (skin–pole friction
    /// `mu`), the body straight on the ground beside it, its middle at the pole and
    /// the pole on its left (looking towards the head), `gap` from its skin, heading
    /// and roll about its own axis drawn from `seed`.
    pub fn world(&self, start_seed: u64, mu: f64) -> WorldSpec {
        let mut rng = Pcg64::seed_from_u64(start_seed);
        let yaw: f64 = rng.random_range(0.0..TAU);
        let roll: f64 = rng.random_range(0.0..TAU);
        let gap: f64 = rng.random_range(0.005..0.02);
        let along: f64 = rng.random_range(-0.05..0.05);
        let modules = MODULES as f64;
        let length = modules * crate::module::MODULE_LENGTH_M;
        // Head → tail along t; towards the head is −t, its left (sin, −cos).
        let t = [yaw.cos(), yaw.sin()];
        let left = [yaw.sin(), -yaw.cos()];
        let off = 0.5 * self.foot_m + 0.5 * MODULE_DIAMETER_M + gap;
        let middle = [-left[0] * off, -left[1] * off];
        let head = [
            middle[0] - t[0] * (0.5 * length + along),
            middle[1] - t[1] * (0.5 * length + along),
        ];
        WorldSpec {
            poles: vec![Pole {
                x_m: 0.0,
                y_m: 0.0,
                sections: self.sections(),
                mu,
            }],
            start: StartPose {
                head_m: [head[0], head[1], 0.0],
                yaw_rad: yaw,
                roll_rad: roll,
                joint_angles_rad: Vec::new(),
            },
            ..WorldSpec::default()
        }
    }
}

/// The pole's diameter at height `z_m` (its top section's above it).
pub fn diameter_at(sections: &[PoleSection], z_m: f64) -> f64 {
    sections
        .iter()
        .find(|s| z_m < s.z1_m)
        .or(sections.last())
        .map_or(0.0, |s| s.diameter_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_follow_the_design() {
        let p = &named_set()[0];
        let s = p.sections();
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].z1_m, s[0].diameter_m), (0.6, 0.15));
        assert!((s[1].diameter_m - 0.15 * 1.28).abs() < 1e-12);
        assert_eq!(s[1].z1_m, POLE_HEIGHT_M);
        let t = named_set()[2].sections();
        assert!(t.len() > 10, "a taper in fine steps");
        assert!(
            t.windows(2)
                .all(|w| w[0].z1_m == w[1].z0_m && w[1].diameter_m > w[0].diameter_m)
        );
        assert!((diameter_at(&t, 1.4) - 0.15 * 1.3).abs() < 1e-12);
        assert_eq!(diameter_at(&t, 0.1), 0.15);
    }

    #[test]
    fn a_poles_identity_is_its_own_not_its_place_in_a_list() {
        let named = named_set();
        let mut reversed = named.clone();
        reversed.reverse();
        let ids = |set: &[PoleDesign]| {
            let climb = crate::lab::pole::PoleClimb {
                designs: set.to_vec(),
                ..Default::default()
            };
            let mut v: Vec<(String, u64)> = climb
                .layouts()
                .unwrap()
                .into_iter()
                .map(|l| (l.name, l.identity))
                .collect();
            v.sort();
            v
        };
        assert_eq!(ids(&named), ids(&reversed));
        assert_eq!(seeded(7).identity(), seeded(7).identity());
        assert_ne!(seeded(7).identity(), seeded(8).identity());
        let mut all: Vec<u64> = named.iter().map(PoleDesign::identity).collect();
        all.dedup();
        assert_eq!(all.len(), named.len());
    }

    #[test]
    fn seeded_poles_change_by_up_to_30_percent_and_differ() {
        for seed in 0..50 {
            let p = seeded(seed);
            assert!((FOOT_M[0]..FOOT_M[1]).contains(&p.foot_m));
            for c in &p.changes {
                assert!((0.7..=1.3).contains(&c.factor), "{p:?}");
                assert!((c.factor - 1.0).abs() >= 0.1 - 1e-12, "{p:?}");
                assert!(c.at_m >= CHANGES_M[0] && c.at_m + c.length_m <= CHANGES_M[1] + 1e-9);
            }
            let s = p.sections();
            assert!(s.windows(2).all(|w| (w[0].z1_m - w[1].z0_m).abs() < 1e-12));
        }
        assert_ne!(seeded(1), seeded(2));
        assert_eq!(seeded(3), seeded(3));
    }

    #[test]
    fn the_body_starts_beside_the_pole_with_it_on_its_left() {
        let p = &named_set()[0];
        for seed in 0..20 {
            let w = p.world(seed, 0.6);
            let (h, yaw) = (w.start.head_m, w.start.yaw_rad);
            let length = MODULES as f64 * crate::module::MODULE_LENGTH_M;
            let mid = [
                h[0] + yaw.cos() * 0.5 * length,
                h[1] + yaw.sin() * 0.5 * length,
            ];
            let d = mid[0].hypot(mid[1]);
            assert!(d > 0.075 + 0.025 && d < 0.075 + 0.025 + 0.08, "{d}");
            // Left of the body looking towards the head: (sin yaw, −cos yaw); the pole
            // (the origin) is on that side of the middle.
            let to_pole = [-mid[0], -mid[1]];
            assert!(to_pole[0] * yaw.sin() - to_pole[1] * yaw.cos() > 0.09);
        }
    }
}
