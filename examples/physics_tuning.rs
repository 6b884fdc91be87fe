//! Speed of the physics plant's solver settings: for each setting, the real-time factor
//! of 18 modules slithering among 40 pegs (best and median of 1 s windows: the machine
//! is shared). Fidelity is judged by the validation tests
//! (`cargo test --release --lib emu::world::physics -- --nocapture` with the setting as
//! the default); docs/measurements.md has both side by side.
//!     cargo run --release --example physics_tuning
use std::time::Instant;

use snaked::emu::Plant;
use snaked::emu::servo::MODULE_LENGTH_M;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::{Peg, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::protocol::Command;

const N: usize = 18;

fn drive(
    plant: &mut PhysicsPlant,
    gait: GaitKind,
    seconds: f64,
    mut each: impl FnMut(&PhysicsPlant),
) {
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let mut sel = GaitSelector::new(layout, GaitTable::default(), gait, 0.5, 3.46);
    let (mut pos, mut vel) = (vec![0.0; N], vec![0.0; N]);
    let mut cmds = vec![Command::LIMP; N];
    for _ in 0..(seconds * 1000.0) as usize {
        sel.update(plant.time_s(), &mut pos, &mut vel);
        for (c, &p) in cmds.iter_mut().zip(&pos) {
            *c = Command::position(p);
        }
        plant.step(1e-3, &cmds);
        each(plant);
    }
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
    println!("substeps iters pgs friction | RTF best  median");
    for (substeps, iters, pgs, coulomb) in [
        (2, 8, 1, true),
        (1, 4, 1, true),
        (1, 3, 1, true),
        (1, 3, 1, false),
        (1, 2, 2, true),
        (1, 2, 1, true),
    ] {
        let config = PhysicsConfig {
            modules: N,
            substeps,
            solver_iterations: iters,
            pgs_iterations: pgs,
            coulomb_friction: coulomb,
            ..PhysicsConfig::default()
        };
        let mut p = PhysicsPlant::new(&pegs(), config).unwrap();
        // One 5 s run, timed per simulated second.
        let (mut rtf, mut t0, mut steps) = (Vec::new(), Instant::now(), 0);
        drive(&mut p, GaitKind::Slithering, 5.0, |_| {
            steps += 1;
            if steps % 1000 == 0 {
                rtf.push(1.0 / t0.elapsed().as_secs_f64());
                t0 = Instant::now();
            }
        });
        rtf.sort_by(f64::total_cmp);
        println!(
            "{substeps:>8} {iters:>5} {pgs:>3} {:>8} | {:>8.1} {:>7.1}",
            if coulomb { "coulomb" } else { "simple" },
            rtf[4],
            rtf[2]
        );
    }
}
