//! How sidewinding's heading turns under different amplitude profiles along the body,
//! in the physics plant on flat ground, open loop: the data behind the heading
//! adjustment's choice of turning cone (docs/compliance.md, "Sidewinding").
//! Each row: the true heading's turn per 16 s (mean of the last cycle minus mean of
//! the cycle from 4 s, over 26 s), for β = 0 and β = π; then the gradient's turn and
//! the speed for β across the wells, for δ = π/2 and the thesis's 3π/4.
//!     cargo run --release --example sidewinding_turns
use std::f64::consts::{PI, TAU};

use snaked::emu::Plant;
use snaked::emu::world::WorldSpec;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::lab::trial::centre;
use snaked::module::MODULE_LENGTH_M;
use snaked::protocol::Command;

const N: usize = 18;

type Profile = fn(Plane, f64, f64) -> f64;

/// Heading (tail to head) of the true body.
fn heading(p: &PhysicsPlant) -> f64 {
    let n = p.link_count();
    let (h, t) = (p.link_pose(0).position_m, p.link_pose(n - 1).position_m);
    (h[1] - t[1]).atan2(h[0] - t[0])
}

fn mean_angle(a: &[f64]) -> f64 {
    let (c, s) = a
        .iter()
        .fold((0.0, 0.0), |(c, s), x| (c + x.cos(), s + x.sin()));
    s.atan2(c)
}

fn wrap(x: f64) -> f64 {
    let y = x.rem_euclid(TAU);
    if y > PI { y - TAU } else { y }
}

/// Turn per 16 s and mean speed (m/s) with `profile(plane, s, c)` scaling each joint,
/// the default gait with its phase shift δ + `beta`.
fn turn(profile: Profile, c: f64, beta: f64, scale: f64) -> (f64, f64) {
    turn_at(None, profile, c, beta, scale)
}

/// As [`turn`], with the phase shift `delta` instead of the default's (`None`).
fn turn_at(delta: Option<f64>, profile: Profile, c: f64, beta: f64, scale: f64) -> (f64, f64) {
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let mut table = GaitTable::default();
    let sw = table.get_mut(GaitKind::Sidewinding);
    if let Some(d) = delta {
        sw.phase_shift_rad = d;
    }
    sw.phase_shift_rad += beta;
    let mut sel = GaitSelector::new(layout.clone(), table, GaitKind::Sidewinding, 0.5, 3.46);
    let mut plant = PhysicsPlant::new(
        &WorldSpec::default(),
        PhysicsConfig {
            modules: N,
            seed: 7,
            ..PhysicsConfig::default()
        },
    )
    .unwrap();
    let (mut pos, mut vel) = (vec![0.0; N], vec![0.0; N]);
    let mut cmds = vec![Command::LIMP; N];
    let mut headings = Vec::new();
    let mut c0 = [0.0, 0.0];
    for k in 1..=26_000 {
        sel.update(plant.time_s(), &mut pos, &mut vel);
        for (i, (cmd, &p)) in cmds.iter_mut().zip(&pos).enumerate() {
            *cmd = Command::position(p * scale * profile(layout.planes[i], layout.s[i], c));
        }
        plant.step(1e-3, &cmds);
        if k % 100 == 0 {
            headings.push(heading(&plant));
        }
        if k == 4000 {
            c0 = centre(&plant);
        }
    }
    let cycle = (TAU / 0.1).round() as usize;
    let n = headings.len();
    let c1 = centre(&plant);
    (
        wrap(mean_angle(&headings[n - cycle..]) - mean_angle(&headings[40..40 + cycle])),
        (c1[0] - c0[0]).hypot(c1[1] - c0[1]) / 22.0,
    )
}

fn main() {
    let rows: &[(&str, Profile, &[f64])] = &[
        ("straight", |_, _, _| 1.0, &[0.0]),
        (
            "grow head 1+c(1-s), both",
            |_, s, c| 1.0 + c * (1.0 - s),
            &[0.4, 0.8],
        ),
        ("grow tail 1+cs, both", |_, s, c| 1.0 + c * s, &[0.4, 0.8]),
        (
            "gradient 1+c(1-2s), both",
            |_, s, c| 1.0 + c * (1.0 - 2.0 * s),
            &[-0.4, 0.4],
        ),
        (
            "gradient, lateral only",
            |p, s, c| {
                if p == Plane::Lateral {
                    1.0 + c * (1.0 - 2.0 * s)
                } else {
                    1.0
                }
            },
            &[-0.4, 0.4],
        ),
        (
            "gradient, dorsal only",
            |p, s, c| {
                if p == Plane::Dorsal {
                    1.0 + c * (1.0 - 2.0 * s)
                } else {
                    1.0
                }
            },
            &[-0.6, 0.6],
        ),
        (
            "dorsal x(1+c) on the head half",
            |p, s, c| {
                if p == Plane::Dorsal && s < 0.5 {
                    1.0 + c
                } else {
                    1.0
                }
            },
            &[-0.5, 0.5],
        ),
        (
            "dorsal x(1+c) on the tail half",
            |p, s, c| {
                if p == Plane::Dorsal && s >= 0.5 {
                    1.0 + c
                } else {
                    1.0
                }
            },
            &[-0.5, 0.5],
        ),
    ];
    println!("profile | c | β 0: turn rad/16 s, speed m/s | β π: turn, speed");
    for &(name, f, cs) in rows {
        for &c in cs {
            let (a, va) = turn(f, c, 0.0, 1.0);
            let (b, vb) = turn(f, c, PI, 1.0);
            println!("{name} | {c:+.1} | {a:+.3} {va:.3} | {b:+.3} {vb:.3}");
        }
    }
    // Between the wells (β follows the heading with the presets' K_h 6): how much turn
    // the gradient still has, which way, and where the travel stalls (δ + β ≡ 0 mod π:
    // on the reversal's hill π/2 for the default δ = π/2, at β = π/4, inside the 0
    // well, for the thesis's δ = 3π/4).
    for delta in [0.5 * PI, 0.75 * PI] {
        println!("δ {delta:.3}: β | turn at c −0.4, speed | turn at c +0.4, speed | straight");
        for k in 0..=8 {
            let beta = k as f64 * PI / 8.0;
            let g = |_: Plane, s: f64, c: f64| 1.0 + c * (1.0 - 2.0 * s);
            let (a, va) = turn_at(Some(delta), g, -0.4, beta, 1.0);
            let (b, vb) = turn_at(Some(delta), g, 0.4, beta, 1.0);
            let (z, vz) = turn_at(Some(delta), g, 0.0, beta, 1.0);
            println!("| {beta:.3} | {a:+.3} {va:.3} | {b:+.3} {vb:.3} | {z:+.3} {vz:.3}");
        }
    }
    for scale in [0.7, 1.3] {
        let (a, va) = turn(|_, _, _| 1.0, 0.0, 0.0, scale);
        println!("straight, both amplitudes x{scale} | | {a:+.3} {va:.3} |");
    }
}
