//! Which way open-loop sidewinding goes among the crossing boards' pegs (issue 28): a
//! measurement, printed (`cargo test --release --lib sidewinding_among_pegs -- --ignored
//! --nocapture`), with the signs it found asserted. Among pegs the body mostly slides
//! along its own axis, in the direction the lateral wave pushes it (head first when the
//! wave runs head to tail, ωT > 0), while the sideways travel follows the chirality
//! (the dorsal wave's phase δ times the sign of ωT): so mirroring δ alone keeps the
//! axial drift and reverses the sideways travel, and mirroring δ and ωT together keeps
//! the sideways travel and reverses the axial drift.

use std::f64::consts::TAU;

use super::starts::StartKind;
use crate::emu::Plant;
use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use crate::emu::world::scenario::WorldScenario;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Plane, Serpenoid};
use crate::module::Command;
use crate::module::MODULE_LENGTH_M;

const N: usize = 18;
const SECONDS: f64 = 40.0;

/// (name, start, mirror δ, ωT sign, alternate δ every 2 cycles)
const MODES: &[(&str, StartKind, bool, f64, bool)] = &[
    ("across, plain", StartKind::AcrossInside, false, 1.0, false),
    (
        "across, δ mirrored",
        StartKind::AcrossInside,
        true,
        1.0,
        false,
    ),
    (
        "across, δ and ωT mirrored",
        StartKind::AcrossInside,
        true,
        -1.0,
        false,
    ),
    ("along, plain", StartKind::AlongInside, false, 1.0, false),
    (
        "along, δ alternating",
        StartKind::AlongInside,
        false,
        1.0,
        true,
    ),
];

fn centre(p: &PhysicsPlant) -> [f64; 2] {
    let n = p.link_count() as f64;
    (0..p.link_count()).fold([0.0, 0.0], |c, k| {
        let q = p.link_pose(k).position_m;
        [c[0] + q[0] / n, c[1] + q[1] / n]
    })
}

/// The centre's displacement over the run: (+x, along the start's head direction,
/// to the left of it), m.
fn run(seed: u64, start: StartKind, mirror: bool, sign: f64, alternate: bool) -> [f64; 3] {
    let mut s = WorldScenario::parse(super::FAMILIES[0].1).unwrap();
    s.seed = seed;
    s.start = start.start_gen(&s.peg_boards[0].region, N);
    let mut world = s.generate_trial(N, 0).unwrap();
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let mut params = GaitParams::default_for(GaitKind::Sidewinding);
    params.temporal_freq_rad_s *= sign;
    let mut mirrored = params;
    mirrored.phase_shift_rad = -params.phase_shift_rad;
    let (plain, mirrored) = (
        Serpenoid::for_layout(GaitKind::Sidewinding, &params, &layout),
        Serpenoid::for_layout(GaitKind::Sidewinding, &mirrored, &layout),
    );
    let first = if mirror { &mirrored } else { &plain };
    let mut angles = vec![0.0; N];
    first.evaluate(&layout, 0.0, &mut angles);
    world.start.joint_angles_rad = angles.clone();
    let config = PhysicsConfig {
        modules: N,
        seed: 1,
        ..PhysicsConfig::default()
    };
    let mut plant = PhysicsPlant::new(&world, config).unwrap();
    let c0 = centre(&plant);
    let (h, t) = (plant.link_pose(0).position_m, plant.link_pose(N).position_m);
    let yaw = (h[1] - t[1]).atan2(h[0] - t[0]);
    let period_s = TAU / params.temporal_freq_rad_s.abs();
    for k in 0..(SECONDS * 1e3) as usize {
        let t = k as f64 * 1e-3;
        let odd_pair = (t / (2.0 * period_s)) as u64 % 2 == 1;
        let gait = if mirror ^ (alternate && odd_pair) {
            &mirrored
        } else {
            &plain
        };
        gait.evaluate(&layout, params.temporal_freq_rad_s * t, &mut angles);
        let cmds: Vec<Command> = angles.iter().map(|&a| Command::position(a)).collect();
        plant.step(1e-3, &cmds);
    }
    let c1 = centre(&plant);
    let d = [c1[0] - c0[0], c1[1] - c0[1]];
    let (s, c) = yaw.sin_cos();
    [d[0], d[0] * c + d[1] * s, -d[0] * s + d[1] * c]
}

#[test]
#[ignore = "a measurement: about 100 s in release"]
fn sidewinding_among_pegs_drifts_along_the_body_with_the_wave() {
    let seeds = 7000..7008u64;
    let mut means = Vec::new();
    for &(name, start, mirror, sign, alternate) in MODES {
        let d: Vec<[f64; 3]> = seeds
            .clone()
            .map(|seed| run(seed, start, mirror, sign, alternate))
            .collect();
        let mean = |i: usize| d.iter().map(|v| v[i]).sum::<f64>() / d.len() as f64;
        let m = [mean(0), mean(1), mean(2)];
        println!(
            "{name}: over {SECONDS} s, mean +x {:.2} m, along the head {:.2} m, to its left {:.2} m",
            m[0], m[1], m[2]
        );
        means.push(m);
    }
    // The axial drift follows ωT's sign; the sideways travel, the chirality.
    assert!(means[0][1] > 0.1 && means[1][1] > 0.1 && means[2][1] < -0.1);
    assert!(means[0][2] < 0.0 && means[1][2] > 0.0 && means[2][2] < 0.0);
}
