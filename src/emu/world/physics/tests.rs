//! Unit tests of the physics plant: rest, tracking, determinism, torque sign.

use super::*;
use crate::emu::Plant;
use crate::emu::world::{Peg, StartPose};
use crate::module::Command;

pub(super) fn quiet(modules: usize) -> PhysicsConfig {
    PhysicsConfig {
        modules,
        noise: NoiseConfig::NONE,
        ..PhysicsConfig::default()
    }
}

pub(super) fn hold(angles: &[f64]) -> Vec<Command> {
    angles.iter().map(|&a| Command::position(a)).collect()
}

#[test]
fn a_shaped_start_is_lifted_to_rest_on_the_ground() {
    // Dorsal joints (odd ones with a lateral first plane) bent to curl the body down:
    // built from the head at z = radius, the tail would be deep inside the ground.
    let angles: Vec<f64> = (0..8).map(|i| if i % 2 == 1 { 0.6 } else { 0.0 }).collect();
    for sign in [1.0, -1.0] {
        let spec = WorldSpec {
            start: StartPose {
                joint_angles_rad: angles.iter().map(|a| sign * a).collect(),
                ..StartPose::default()
            },
            ..WorldSpec::default()
        };
        let poses = build::start_poses(&spec, &quiet(8), None);
        let lowest = poses
            .iter()
            .map(|p| {
                let axis = p.rotation * nalgebra::Vector3::x();
                p.translation.z - (0.032 - 0.0255) * axis.z.abs() - 0.0255
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            lowest.abs() < 1e-9,
            "sign {sign}: lowest point at {lowest} m"
        );
    }
}

#[test]
fn straight_snake_rests_on_the_ground() {
    let spec = WorldSpec::default();
    let mut plant = PhysicsPlant::new(&spec, quiet(6)).unwrap();
    let cmds = hold(&[0.0; 6]);
    for _ in 0..300 {
        plant.step(1e-3, &cmds);
    }
    for k in 0..plant.link_count() {
        let z = plant.link_pose(k).position_m[2];
        assert!((z - 0.0255).abs() < 2e-3, "link {k} at z {z}");
    }
    for i in 0..6 {
        let f = plant.feedback(i);
        assert!(f.position_rad.abs() < 1e-2, "joint {i}: {f:?}");
        assert!((f.accel_m_s2[2] - 9.81).abs() < 0.2, "accel {f:?}");
        assert!(f.accel_m_s2[0].abs() < 0.2 && f.gyro_rad_s[2].abs() < 0.05);
    }
    let c = plant.contacts();
    assert!(c.pairs >= 7, "{c:?}");
    // The whole weight rests on the ground.
    let weight = 7.0 * 0.205 * 9.81;
    assert!((c.normal_force_n - weight).abs() < 0.1 * weight, "{c:?}");
}

#[test]
fn joints_follow_position_commands() {
    let spec = WorldSpec::default();
    let mut plant = PhysicsPlant::new(&spec, quiet(4)).unwrap();
    let target = [0.5, -0.3, 0.4, 0.2];
    let cmds = hold(&target);
    for _ in 0..1500 {
        plant.step(1e-3, &cmds);
    }
    for (i, t) in target.iter().enumerate() {
        let x = plant.ground_truth(i).position_rad;
        assert!((x - t).abs() < 0.03, "joint {i}: {x} vs {t}");
    }
}

#[test]
fn same_seed_same_trajectory() {
    let spec = WorldSpec {
        pegs: vec![Peg {
            x_m: 0.3,
            y_m: 0.06,
            diameter_m: 0.05,
            height_m: 0.2,
        }],
        ..WorldSpec::default()
    };
    let run = || {
        let mut plant = PhysicsPlant::new(
            &spec,
            PhysicsConfig {
                modules: 6,
                seed: 7,
                ..PhysicsConfig::default()
            },
        )
        .unwrap();
        let mut log = Vec::new();
        for k in 0..400 {
            let t = k as f64 * 1e-3;
            let a: Vec<f64> = (0..6).map(|i| 0.8 * (3.0 * t - i as f64).sin()).collect();
            plant.step(1e-3, &hold(&a));
            let f = plant.feedback(5);
            log.push((plant.link_pose(3), f.torque_nm, f.accel_m_s2));
        }
        log
    };
    assert_eq!(run(), run());
}

#[test]
fn anisotropic_friction_builds_and_steps() {
    let spec = WorldSpec {
        friction: crate::emu::world::Friction {
            mu: 0.5,
            anisotropic: Some(crate::emu::world::Anisotropic {
                mu_axial: 0.2,
                mu_lateral: 0.8,
            }),
            peg_mu: None,
        },
        ..WorldSpec::default()
    };
    let mut plant = PhysicsPlant::new(&spec, quiet(4)).unwrap();
    for _ in 0..100 {
        plant.step(1e-3, &hold(&[0.3; 4]));
    }
    assert!(plant.joint_rad(0) > 0.1);
}

#[test]
fn invalid_configs_are_refused() {
    let spec = WorldSpec::default();
    assert!(matches!(
        PhysicsPlant::new(&spec, quiet(0)),
        Err(PhysicsError::NoModules)
    ));
    let bad = PhysicsConfig {
        substeps: 0,
        ..quiet(3)
    };
    assert!(PhysicsPlant::new(&spec, bad).is_err());
}

/// Three-point bending: a lateral joint commanded to bend, blocked by one peg on the
/// convex side at the joint and two on the concave side near the ends, reports the
/// push of the pegs with the servo's sign (commanded positive, pushed back negative:
/// positive torque).
#[test]
fn joint_pressed_by_pegs_reports_torque_of_the_right_sign() {
    use crate::module::MODULE_LENGTH_M;
    let l = MODULE_LENGTH_M;
    let gap = 0.5 * crate::module::MODULE_DIAMETER_M + 0.025 + 0.001;
    for sign in [1.0, -1.0] {
        // Head at the origin, body along −x; joint 4 (lateral) at x = −5 l. A positive
        // lateral angle swings the tail side right (−y): the body's ends move to −y
        // and the joint to +y.
        let peg = |x: f64, y: f64| Peg {
            x_m: x,
            y_m: y,
            diameter_m: 0.05,
            height_m: 0.1,
        };
        let spec = WorldSpec {
            pegs: vec![
                peg(-5.0 * l, sign * gap),
                peg(-l, -sign * gap),
                peg(-9.0 * l, -sign * gap),
            ],
            ..WorldSpec::default()
        };
        let mut plant = PhysicsPlant::new(&spec, quiet(9)).unwrap();
        let mut cmd = [0.0; 9];
        cmd[4] = sign * 0.8;
        for _ in 0..800 {
            plant.step(1e-3, &hold(&cmd));
        }
        let x = plant.joint_rad(4);
        let tau = plant.feedback(4).torque_nm;
        println!(
            "peg torque: commanded {:.1} rad, joint at {x:.3} rad, torque {tau:.2} N·m",
            cmd[4]
        );
        assert!(x.abs() < 0.4, "the pegs did not block the bend: {x}");
        assert!(f64::from(tau) * sign > 1.0, "torque {tau} for sign {sign}");
    }
}
