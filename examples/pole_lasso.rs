//! Getting on the pole by lapping its foot (issue 12, point 3), open loop in the
//! physics plant: the body lies straight on the ground with its middle against a pole;
//! a helix of lap radius (the pole's radius plus a module's plus 5 mm) and a flat pitch
//! `FLAT` is commanded to every joint at once over 2 s, its phase chosen so the
//! middle bends in the ground plane, so both halves lap the pole's foot; then over 3 s
//! the coil tightens by `SQUEEZE` and its pitch opens to `PITCH`, and it rolls at `WT`.
//! Every 2 s: the centre of mass's height, how many links touch the pole (within 1 cm
//! of its surface) and the highest link. Tries both senses of the lap (ψ 0: away from
//! the pole; π: round it) and of the twist (±pitch).
//!     cargo run --release --example pole_lasso
//! Environment: POLE_D (pole diameter, m; 0.2; with STEPPED set, the foot's, then
//! 0.8× from 0.4 m and 1.2× from 0.8 m, as `scenarios/pole.toml`), ROLL_DEG (the body
//! rolled about its axis at the start, °; 0), PSI_SWEEP (set: ψ0 in steps of π/4), PITCH (0.03), FLAT (0.008), SQUEEZE
//! (0.02), WT (−1), SECS (40), HEAD_X (−0.58: the middle at the pole), LAP_S (0: a
//! delay per joint, s, to lap from the head instead).
//! Measured 2026-12-03: on a 0.20 m pole the lap round it (ψ π) touches with all 19
//! links, and rolled at ωT −1 the coil climbs from 0.12 m to 1.03 m (centre of mass)
//! in 36 s, 16 links still touching, either twist; at ωT +1 it stays at the foot. On
//! 0.14 m and 0.10 m poles the lap does not hold (0-4 links touch): a flat lap that
//! tight needs more than the ±π/2 a joint can bend when one joint family carries it
//! (docs/compliance.md, "Rolling helix"). With the body rolled 45° (`ROLL_DEG=45
//! POLE_D=0.1 PITCH=0.015 SQUEEZE=0.015`) the 0.10 m pole is lapped (16 links) and
//! climbed to 1.24 m in 40 s; on the stepped pole (`STEPPED=1`, 0.10 / 0.08 / 0.12 m)
//! the same open-loop coil loosens on the thin section and falls from 0.8 m at the
//! thick one (twist +1), or climbs off the top (−1).
use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};
use snaked::emu::Plant;
use snaked::emu::world::physics::kinematics::head_pose;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::{Pole, PoleSection, StartPose, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitParams, Plane, Serpenoid};
use snaked::module::{MODULE_LENGTH_M, MODULE_RADIUS_M};
use snaked::protocol::Command;

fn env(name: &str, d: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

const N: usize = 18;

fn helix(layout: &BodyLayout, radius_m: f64, pitch_m: f64) -> Serpenoid {
    let p = GaitParams {
        helix_radius_m: radius_m,
        helix_pitch_m: pitch_m,
        ..GaitParams::default_for(GaitKind::RollingHelix)
    };
    Serpenoid::for_layout(GaitKind::RollingHelix, &p, layout)
}

fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

fn run(psi0: f64, twist: f64) {
    let pole_r = 0.5 * env("POLE_D", 0.2);
    let lap = pole_r + MODULE_RADIUS_M + 0.005;
    let (flat, pitch) = (twist * env("FLAT", 0.008), twist * env("PITCH", 0.03));
    let wt = env("WT", -1.0);
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    // Head beside the pole, the body along +x, its side a few mm off the pole.
    let spec = WorldSpec {
        poles: vec![Pole {
            x_m: 0.0,
            y_m: 0.0,
            sections: if std::env::var("STEPPED").is_ok() {
                // scenarios/pole.toml's: the foot's diameter, then 0.8× and 1.2× it.
                [(0.0, 0.4, 1.0), (0.4, 0.8, 0.8), (0.8, 1.5, 1.2)]
                    .map(|(z0_m, z1_m, f)| PoleSection {
                        z0_m,
                        z1_m,
                        diameter_m: 2.0 * pole_r * f,
                    })
                    .to_vec()
            } else {
                vec![PoleSection {
                    z0_m: 0.0,
                    z1_m: 1.5,
                    diameter_m: 2.0 * pole_r,
                }]
            },
            mu: 0.6,
        }],
        start: StartPose {
            head_m: [env("HEAD_X", -0.58), pole_r + MODULE_RADIUS_M + 0.005, 0.0],
            yaw_rad: 0.0,
            ..StartPose::default()
        },
        ..WorldSpec::default()
    };
    // The body rolled `ROLL_DEG` about its own axis (both joint families then bend
    // across the ground plane).
    let mut h = spec.start.head_m;
    h[2] += MODULE_RADIUS_M;
    let head = head_pose(h, spec.start.yaw_rad, MODULE_LENGTH_M)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), env("ROLL_DEG", 0.0).to_radians());
    let mut plant = PhysicsPlant::with_head_pose(
        &spec,
        PhysicsConfig {
            modules: N,
            seed: 7,
            ..PhysicsConfig::default()
        },
        Some(head),
    )
    .unwrap();
    let (mut a, mut b) = (vec![0.0; N], vec![0.0; N]);
    let mut cmds = vec![Command::LIMP; N];
    let lap_s = env("LAP_S", 0.0); // per joint
    let formed = N as f64 * lap_s + 1.5;
    let opened = formed + 3.0;
    let mut line = Vec::new();
    let h = plant.link_pose(0).position_m;
    let m = plant.link_pose(N / 2).position_m;
    line.push(format!(
        "start head ({:.2}, {:.2}, {:.2}) mid ({:.2}, {:.2})",
        h[0], h[1], h[2], m[0], m[1]
    ));
    for k in 1..=(env("SECS", 40.0) * 1e3) as usize {
        let t = k as f64 * 1e-3;
        let open = smooth((t - formed) / 3.0);
        let psi = psi0 + if t > opened { wt * (t - opened) } else { 0.0 };
        let mid = helix(&layout, lap, flat)
            .wave(Plane::Lateral)
            .spatial_freq_rad
            * 0.5;
        let psi = psi + mid;
        helix(&layout, lap, flat).evaluate(&layout, psi, &mut a);
        helix(&layout, lap - env("SQUEEZE", 0.02), pitch).evaluate(&layout, psi, &mut b);
        for (i, cmd) in cmds.iter_mut().enumerate() {
            let reach = smooth((t - i as f64 * lap_s) / 2.0);
            *cmd = Command::position(reach * ((1.0 - open) * a[i] + open * b[i]));
        }
        plant.step(1e-3, &cmds);
        if k % 2000 == 0 {
            let (mut touching, mut top) = (0, 0.0f64);
            for l in 0..plant.link_count() {
                let p = plant.link_pose(l).position_m;
                if p[0].hypot(p[1]) < pole_r + MODULE_RADIUS_M + 0.01 {
                    touching += 1;
                }
                top = top.max(p[2]);
            }
            let h = plant.link_pose(0).position_m;
            line.push(format!(
                "{:.0}s z {:.2} touch {touching} top {:.2} head ({:.2}, {:.2}, {:.2})",
                t,
                plant.centre_of_mass_m()[2],
                top,
                h[0],
                h[1],
                h[2]
            ));
        }
    }
    println!("ψ0 {psi0:.2} twist {twist:+}: {}", line.join(" | "));
}

fn main() {
    if std::env::var("PSI_SWEEP").is_ok() {
        for k in 0..8 {
            run(k as f64 * PI / 4.0, 1.0);
        }
        return;
    }
    for psi0 in [0.0, PI] {
        for twist in [1.0, -1.0] {
            run(psi0, twist);
        }
    }
}
