//! The estimator against the emulator's ground truth, which the daemon never sees:
//! the physics plant's IMUs and encoders in, its true link poses to compare with.
//! Figures are printed (`cargo test --lib estimation -- --nocapture`).

use std::f64::consts::{PI, TAU};

use nalgebra::{UnitQuaternion, Vector3};

use super::VirtualChassisEstimator;
use super::chassis::{Chassis, chassis};
use crate::controller_interface::{BodyEstimate, Estimator, Imu, Observation};
use crate::emu::Plant;
use crate::emu::servo::PositionLoop;
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::{ImuBias, PhysicsConfig, PhysicsPlant};
use crate::emu::world::scenario::WorldScenario;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Plane, Serpenoid};
use crate::module::Command;
use crate::module::MODULE_LENGTH_M;

const N: usize = 18;

/// Errors over a run, degrees: heading (after the start's yaw offset is removed) and
/// the head's tilt.
#[derive(Debug, Default)]
struct Errors {
    heading: Vec<f64>,
    tilt: Vec<f64>,
    round: usize,
    /// The chassis origin's ground-plane travel over the run: true, and the contact
    /// odometry's turned into the truth's frame by the heading offset.
    travel_true: [f64; 2],
    travel_odometry: [f64; 2],
    lifted: usize,
}

impl Errors {
    /// The odometry's direction error, degrees, and its length over the truth's.
    fn odometry(&self) -> (f64, f64) {
        let [tx, ty] = self.travel_true;
        let [ex, ey] = self.travel_odometry;
        (
            wrap(ey.atan2(ex) - ty.atan2(tx)).to_degrees(),
            ex.hypot(ey) / tx.hypot(ty),
        )
    }
}

fn stats(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let mean = s.iter().sum::<f64>() / s.len() as f64;
    (
        mean,
        s[(0.95 * (s.len() - 1) as f64) as usize],
        s[s.len() - 1],
    )
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

fn rotation(q: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// Runs `kind` open loop in `world` for `cycles` after one settling cycle, the
/// estimator fed from the plant's noisy feedback.
fn run(world: &WorldSpec, kind: GaitKind, cycles: f64) -> Errors {
    let params = GaitParams::default_for(kind);
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let gait = Serpenoid::for_layout(kind, &params, &layout);
    let mut angles = vec![0.0; N];
    gait.evaluate(&layout, 0.0, &mut angles);
    let world = WorldSpec {
        start: crate::emu::world::StartPose {
            joint_angles_rad: angles.clone(),
            ..world.start.clone()
        },
        ..world.clone()
    };
    // The default sensor noise, and biases like a MEMS IMU's (about 0.6°/s of gyro
    // bias per module): the heading, which gravity cannot correct, drifts with them.
    let mut config = PhysicsConfig {
        modules: N,
        seed: 7,
        imu_bias: ImuBias {
            accel_m_s2: 0.05,
            gyro_rad_s: 0.01,
        },
        ..PhysicsConfig::default()
    };
    config.servo.position_loop = PositionLoop::Profiled;
    let mut plant = PhysicsPlant::new(&world, config).unwrap();
    let mut estimator =
        VirtualChassisEstimator::new(layout.clone(), super::DEFAULT_TIME_CONSTANT_S);
    let (mut pos, mut vel, mut tau) = (vec![0.0; N], vec![0.0; N], vec![0.0; N]);
    let mut imu = vec![Imu::default(); N];
    let mut body = BodyEstimate::default();
    let mut truth: Option<Chassis> = None;
    let mut offset = None;
    let mut first: Option<([f64; 2], [f64; 2])> = None;
    let mut errors = Errors::default();
    let cycle_s = TAU / params.temporal_freq_rad_s;
    let steps = ((1.0 + cycles) * cycle_s * 1e3) as usize;
    for k in 0..steps {
        let t = k as f64 * 1e-3;
        gait.evaluate(&layout, params.temporal_freq_rad_s * t, &mut angles);
        let cmds: Vec<Command> = angles.iter().map(|&a| Command::position(a)).collect();
        plant.step(1e-3, &cmds);
        for i in 0..N {
            let f = plant.feedback(i);
            pos[i] = f64::from(f.position_rad);
            vel[i] = f64::from(f.velocity_rad_s);
            tau[i] = f64::from(f.torque_nm);
            imu[i] = Imu {
                accel_m_s2: f.accel_m_s2.map(f64::from),
                gyro_rad_s: f.gyro_rad_s.map(f64::from),
            };
        }
        let previous = body;
        let obs = Observation {
            position_rad: &pos,
            velocity_rad_s: &vel,
            torque_nm: &tau,
            imu: &imu,
            body: &previous,
        };
        estimator.update(t + 1e-3, &obs, &mut body);
        // The truth: the same chassis of the true link centres.
        let points: Vec<Vector3<f64>> = (0..=N)
            .map(|l| Vector3::from(plant.link_pose(l).position_m))
            .collect();
        let c = chassis(&points, truth.as_ref());
        truth = Some(c);
        if !body.valid || t < cycle_s {
            continue;
        }
        let d = wrap(body.heading_rad - c.heading_rad());
        let offset = *offset.get_or_insert(d);
        errors.heading.push(wrap(d - offset).abs().to_degrees());
        let true_head = rotation(plant.link_pose(0).quat_wxyz);
        let up_true = true_head.inverse() * Vector3::z();
        let up_est = estimator.head_attitude().inverse() * Vector3::z();
        errors.tilt.push(up_true.angle(&up_est).to_degrees());
        errors.round += usize::from(body.round);
        errors.lifted += usize::from(body.odometry_lifted);
        let truth_xy = [c.origin.x, c.origin.y];
        let (t0, o0) = *first.get_or_insert((truth_xy, body.odometry_m));
        let (s, co) = offset.sin_cos();
        let (dx, dy) = (body.odometry_m[0] - o0[0], body.odometry_m[1] - o0[1]);
        // Estimate's world → truth's: turn by minus the heading offset.
        errors.travel_odometry = [co * dx + s * dy, -s * dx + co * dy];
        errors.travel_true = [truth_xy[0] - t0[0], truth_xy[1] - t0[1]];
    }
    errors
}

#[test]
fn the_virtual_chassis_follows_the_true_body_on_flat_ground_and_among_pegs() {
    let board = WorldScenario::parse(crate::lab::pegboard::board::PEG_BOARD_TOML)
        .unwrap()
        .generate(N)
        .unwrap();
    let flat = WorldSpec::default();
    for (name, world, kind, cycles, heading_p95, tilt_p95) in [
        ("sidewinding", &flat, GaitKind::Sidewinding, 2.0, 3.0, 3.0),
        ("rolling", &flat, GaitKind::Rolling, 3.0, 3.0, 3.0),
        ("slithering", &flat, GaitKind::Slithering, 2.0, 3.0, 3.0),
        (
            "slithering among pegs",
            &board,
            GaitKind::Slithering,
            2.0,
            3.0,
            3.0,
        ),
    ] {
        let e = run(world, kind, cycles);
        let (hm, hp, hx) = stats(&e.heading);
        let (tm, tp, tx) = stats(&e.tilt);
        println!(
            "{name}: heading error mean {hm:.2}°, p95 {hp:.2}°, max {hx:.2}°; head tilt \
             error mean {tm:.2}°, p95 {tp:.2}°, max {tx:.2}°; no clear axis in {} of {} steps",
            e.round,
            e.heading.len()
        );
        assert!(hp < heading_p95 && tp < tilt_p95, "{name}");
    }
}

#[test]
fn contact_odometry_follows_a_lifted_gait_on_flat_ground_and_among_pegs() {
    let board = WorldScenario::parse(crate::lab::pegboard::board::PEG_BOARD_TOML)
        .unwrap()
        .generate(N)
        .unwrap();
    let flat = WorldSpec::default();
    let mut checks = Vec::new();
    for (name, world, kind, cycles) in [
        ("sidewinding", &flat, GaitKind::Sidewinding, 3.0),
        ("rolling", &flat, GaitKind::Rolling, 3.0),
        ("sidewinding among pegs", &board, GaitKind::Sidewinding, 3.0),
        ("slithering", &flat, GaitKind::Slithering, 2.0),
    ] {
        let e = run(world, kind, cycles);
        let (dir, ratio) = e.odometry();
        checks.push((name, dir, ratio, e.lifted));
        let [tx, ty] = e.travel_true;
        let [ex, ey] = e.travel_odometry;
        println!(
            "{name}: travelled ({tx:.3}, {ty:.3}) m, odometry ({ex:.3}, {ey:.3}) m: direction \
             error {dir:.1}°, length ratio {ratio:.2}; lifted in {} of {} steps",
            e.lifted,
            e.heading.len()
        );
    }
    // On open ground a lifted gait's contacts stay put: the odometry follows it. Among
    // pegs they slide (printed, not bounded: docs/estimation.md); the planar gaits have
    // no lift to stand on and say so.
    let (_, dir, ratio, lifted) = checks[0];
    assert!(
        dir.abs() < 10.0 && (0.6..1.2).contains(&ratio) && lifted > 0,
        "sidewinding"
    );
    for (name, _, _, lifted) in checks.iter().filter(|c| !c.0.starts_with("sidewinding")) {
        assert_eq!(*lifted, 0, "{name}");
    }
}
