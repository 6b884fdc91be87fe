//! Speed of the physics plant's solver settings, side by side in one run: for each
//! setting, the plant's time per 1 ms step (this thread's CPU time, so other work on a
//! shared machine counts less than in wall time) and the real-time factor, in three
//! worlds: 18 modules slithering among 40 pegs, sidewinding on the rock pile
//! (`scenarios/rock-pile-3d.toml`), rolling on flat ground. The settings alternate
//! within each round and the fastest of `ROUNDS` rounds counts (the least disturbed),
//! so a busy hour slows them alike. Fidelity is
//! judged by the validation tests (`cargo test --release --lib emu::world::physics --
//! --nocapture` with the setting as the default) and the joint-speed diagnostic
//! (`cargo run --release --example joint_speed_diag`); docs/measurements/physics.md has them
//! side by side.
//!     cargo run --release --example physics_tuning
use snaked::emu::Plant;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::scenario::WorldScenario;
use snaked::emu::world::{Peg, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::module::MODULE_LENGTH_M;
use snaked::protocol::Command;

const N: usize = 18;
const ROUNDS: usize = 5;
const SECONDS: f64 = 3.0;

/// A setting: name, substeps, solver iterations, PGS sweeps, stabilisation sweeps.
type Setting = (&'static str, usize, usize, usize, usize);

const SETTINGS: [Setting; 8] = [
    ("1 × 3 × 1, 1 stabilisation (until 2026-12-04)", 1, 3, 1, 1),
    ("1 × 3 × 1, 2 stabilisation", 1, 3, 1, 2),
    ("1 × 3 × 1, 3 stabilisation", 1, 3, 1, 3),
    ("1 × 3 × 2, 2 stabilisation", 1, 3, 2, 2),
    ("1 × 3 × 4, 1 stabilisation", 1, 3, 4, 1),
    ("1 × 4 × 1, 2 stabilisation", 1, 4, 1, 2),
    ("1 × 5 × 1, 1 stabilisation", 1, 5, 1, 1),
    ("2 × 3 × 1, 1 stabilisation", 2, 3, 1, 1),
];

/// This thread's CPU time, s.
fn cpu_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// CPU seconds the plant took for `seconds` of `gait` (the set-points are not timed).
fn drive(plant: &mut PhysicsPlant, gait: GaitKind, seconds: f64) -> f64 {
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let mut sel = GaitSelector::new(layout, GaitTable::default(), gait, 0.5, 3.46);
    let (mut pos, mut vel) = (vec![0.0; N], vec![0.0; N]);
    let mut cmds = vec![Command::LIMP; N];
    let mut busy = 0.0;
    for _ in 0..(seconds * 1000.0) as usize {
        sel.update(plant.time_s(), &mut pos, &mut vel);
        for (c, &p) in cmds.iter_mut().zip(&pos) {
            *c = Command::position(p);
        }
        let t0 = cpu_s();
        plant.step(1e-3, &cmds);
        busy += cpu_s() - t0;
    }
    busy
}

fn pegs() -> WorldSpec {
    let pegs = (0..40)
        .map(|k| Peg {
            x_m: -1.2 + 0.3 * (k / 5) as f64 + 0.03 * ((k * 7) % 5) as f64,
            y_m: -0.45 + 0.3 * (k % 5) as f64,
            diameter_m: 0.05,
            height_m: 0.15,
        })
        .collect();
    WorldSpec {
        pegs,
        ..WorldSpec::default()
    }
}

fn main() {
    let rocks = WorldScenario::load(std::path::Path::new("scenarios/rock-pile-3d.toml"))
        .and_then(|s| s.generate_trial(N, 0))
        .expect("the rock pile scenario");
    let worlds = [
        ("40 pegs, slithering", pegs(), GaitKind::Slithering),
        ("rock pile, sidewinding", rocks, GaitKind::Sidewinding),
        ("flat, rolling", WorldSpec::default(), GaitKind::Rolling),
    ];
    // cpu[world][setting][round], s.
    let mut cpu = vec![vec![Vec::new(); SETTINGS.len()]; worlds.len()];
    for _ in 0..ROUNDS {
        for (w, (_, spec, gait)) in worlds.iter().enumerate() {
            for (s, &(_, substeps, iters, pgs, stab)) in SETTINGS.iter().enumerate() {
                let config = PhysicsConfig {
                    modules: N,
                    substeps,
                    solver_iterations: iters,
                    pgs_iterations: pgs,
                    stabilization_iterations: stab,
                    ..PhysicsConfig::default()
                };
                let mut p = PhysicsPlant::new(spec, config).unwrap();
                cpu[w][s].push(drive(&mut p, *gait, SECONDS));
            }
        }
    }
    print!("{:<48}", "substeps × iterations × PGS, stabilisation");
    for (name, _, _) in &worlds {
        print!(" | {name:>28}");
    }
    println!(
        "\n{:<48}{}",
        "",
        " | µs per step, RTF, vs first".repeat(worlds.len())
    );
    let best = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    for (s, (name, ..)) in SETTINGS.iter().enumerate() {
        print!("{name:<48}");
        for row in &cpu {
            let us = best(&row[s]) / SECONDS * 1e3;
            let base = best(&row[0]) / SECONDS * 1e3;
            print!(
                " | {us:>7.1} µs {:>5.1}× {:>+5.0} %",
                1e3 / us,
                100.0 * (us / base - 1.0)
            );
        }
        println!();
    }
}
