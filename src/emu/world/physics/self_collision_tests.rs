//! Self-collision: a body folded onto itself does not pass through itself, joined links
//! never touch, skin on skin has the world's `mu`, and the ordinary gaits make no
//! self-contacts.

use super::tests::{hold, quiet};
use super::*;
use crate::emu::Plant;
use crate::gait::{GaitKind, GaitParams};

/// Distance between the centres of two links not joined by a joint: never below this
/// (× the module diameter) when they collide.
const MIN_GAP_DIAMETERS: f64 = 0.9;

fn config(modules: usize, self_collision: bool) -> PhysicsConfig {
    PhysicsConfig {
        self_collision,
        ..quiet(modules)
    }
}

/// Smallest distance between the centres of links at least 2 apart, m.
fn closest_non_adjacent_m(plant: &PhysicsPlant) -> f64 {
    let n = plant.link_count();
    let centre = |k| nalgebra::Vector3::from(plant.link_pose(k).position_m);
    let mut d = f64::INFINITY;
    for a in 0..n {
        for b in a + 2..n {
            d = d.min((centre(a) - centre(b)).norm());
        }
    }
    d
}

/// Every lateral joint of 12 modules bent to 1.2 rad: a flat coil of 0.67 m
/// circumference for a 0.83 m body, so the head runs into the tail section. Returns
/// the plant and the closest approach over the run.
fn fold(self_collision: bool) -> (PhysicsPlant, f64) {
    let n = 12;
    let mut plant = PhysicsPlant::new(&WorldSpec::default(), config(n, self_collision)).unwrap();
    let angles: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 1.2 } else { 0.0 }).collect();
    let cmds = hold(&angles);
    let mut closest = f64::INFINITY;
    for _ in 0..1200 {
        plant.step(1e-3, &cmds);
        closest = closest.min(closest_non_adjacent_m(&plant));
    }
    (plant, closest)
}

#[test]
fn a_body_folded_onto_itself_does_not_pass_through_itself() {
    let d = crate::module::MODULE_DIAMETER_M;
    let (plant, closest) = fold(true);
    let (ghost, ghost_closest) = fold(false);
    println!(
        "fold: closest centres {:.3} diameters with self-collision ({} onsets, {} pairs \
         touching at the end), {:.3} without",
        closest / d,
        plant.self_contacts(),
        plant.self_contact_pairs_now(),
        ghost_closest / d
    );
    assert!(closest > MIN_GAP_DIAMETERS * d, "{closest} m");
    assert!(plant.self_contacts() >= 1 && plant.self_contact_pairs_now() >= 1);
    // Without it the head sinks into the tail section (so this test can fail).
    assert!(ghost_closest < 0.5 * d, "{ghost_closest} m");
    assert_eq!(ghost.self_contacts(), 0);
    // Skin on skin: the world's `mu` (not 0 from the links' own coefficient), and the
    // link–world contact summary leaves the self-contacts out.
    let mu = WorldSpec::default().friction.mu as f32;
    let (mut self_manifolds, mut world_pairs) = (0, 0);
    let is_link = |h: ColliderHandle| plant.world().colliders[h].user_data >= build::TAG_LINK_BASE;
    for pair in plant.world().narrow_phase.contact_pairs() {
        if is_link(pair.collider1) && is_link(pair.collider2) {
            for m in pair.manifolds() {
                assert_eq!(m.data.friction, mu);
                self_manifolds += 1;
            }
        } else if pair.has_any_active_contact() {
            world_pairs += 1;
        }
    }
    assert!(self_manifolds >= 1);
    assert_eq!(plant.contacts().pairs, world_pairs);
}

/// Each surface keeps its own coefficient against the skin (poles above and below the
/// skin's), and skin on skin is the skin's.
#[test]
fn friction_combines_to_each_surface_s_own_coefficient() {
    use crate::emu::world::{Peg, Pole, PoleSection};
    let pole = |x_m: f64, mu: f64| Pole {
        x_m,
        y_m: 1.0,
        sections: vec![PoleSection {
            z0_m: 0.0,
            z1_m: 0.5,
            diameter_m: 0.1,
        }],
        mu,
    };
    let spec = WorldSpec {
        pegs: vec![Peg {
            x_m: 0.0,
            y_m: -1.0,
            diameter_m: 0.05,
            height_m: 0.1,
        }],
        poles: vec![pole(0.0, 0.2), pole(0.5, 0.9)],
        ..WorldSpec::default()
    };
    let plant = PhysicsPlant::new(&spec, quiet(3)).unwrap();
    let colliders = &plant.world().colliders;
    let link = &colliders[plant.chain.colliders[0]];
    let combine = |a: &Collider, b: &Collider| {
        CoefficientCombineRule::combine(
            a.friction(),
            b.friction(),
            a.friction_combine_rule(),
            b.friction_combine_rule(),
        )
    };
    let mut seen = 0;
    for (_, c) in colliders.iter() {
        let want = match c.user_data {
            build::TAG_POLE | build::TAG_SKIN_SURFACE => c.friction(),
            _ => spec.friction.mu as f32,
        };
        assert_eq!(combine(link, c), want, "{:?}", c.user_data);
        assert_eq!(combine(c, link), want);
        seen += 1;
    }
    assert_eq!(seen, 4 + 4); // ground, peg, 2 poles; 4 links
}

/// Joined links overlap at the joint when bent: neither they nor links 2 apart may
/// make a contact pair, at any bend, with 19 links (one collision group each) and
/// with 41 (where the joints alone keep joined links apart).
#[test]
fn joined_links_never_touch() {
    for modules in [18, 40] {
        let mut plant = PhysicsPlant::new(&WorldSpec::default(), config(modules, true)).unwrap();
        // A zigzag at the limits: every joint folded, alternating sign per pair.
        let angles: Vec<f64> = (0..modules)
            .map(|i| if (i / 2) % 2 == 0 { 1.5 } else { -1.5 })
            .collect();
        let cmds = hold(&angles);
        let mut joined_pairs_seen = 0;
        let world_links = |p: &PhysicsPlant, h: ColliderHandle| {
            p.world().colliders[h]
                .user_data
                .checked_sub(build::TAG_LINK_BASE)
        };
        for step in 0..400 {
            plant.step(1e-3, &cmds);
            if step % 20 != 0 {
                continue;
            }
            for pair in plant.world().narrow_phase.contact_pairs() {
                let (Some(a), Some(b)) = (
                    world_links(&plant, pair.collider1),
                    world_links(&plant, pair.collider2),
                ) else {
                    continue;
                };
                let gap = a.abs_diff(b);
                if plant.link_count() <= 31 {
                    assert!(gap >= 3, "pair {a}-{b} made at step {step}");
                } else if gap == 1 {
                    assert!(!pair.has_any_active_contact(), "{a}-{b} at step {step}");
                    assert!(pair.manifolds().iter().all(|m| m.points.is_empty()));
                    joined_pairs_seen += 1;
                }
            }
        }
        assert!(plant.joint_rad(0).abs() > 1.2, "{}", plant.joint_rad(0));
        // Past 31 links the joined pairs reach the narrow phase (so the check above
        // ran) and are dropped there.
        assert_eq!(joined_pairs_seen > 0, plant.link_count() > 31);
        println!(
            "zigzag, {modules} modules: {} self-contact onsets, {joined_pairs_seen} joined \
             pairs seen in the narrow phase",
            plant.self_contacts()
        );
    }
}

/// The gaits at their default parameters on flat ground never bring two links
/// together (their closest centres stay about 2 diameters apart).
#[test]
fn ordinary_gaits_make_no_self_contacts() {
    for kind in [
        GaitKind::Slithering,
        GaitKind::Sidewinding,
        GaitKind::Rolling,
    ] {
        let mut closest = f64::INFINITY;
        let plant = super::validation_tests::run_gait(
            &WorldSpec::default(),
            kind,
            GaitParams::default_for(kind),
            3.0,
            |_, p| closest = closest.min(closest_non_adjacent_m(p)),
        );
        println!(
            "{kind:?} 3 s: {} self-contact onsets, closest centres {:.2} diameters",
            plant.self_contacts(),
            closest / crate::module::MODULE_DIAMETER_M
        );
        assert_eq!(plant.self_contacts(), 0, "{kind:?}");
    }
}

#[test]
fn self_collision_defaults_on_and_reads_from_toml() {
    let read = |s: &str| toml::from_str::<PhysicsConfig>(s).unwrap().self_collision;
    assert!(read(""));
    assert!(!read("self_collision = false"));
}
