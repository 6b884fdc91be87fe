//! Speed against fidelity of the physics plant's solver settings: for each setting,
//! the real-time factor of 18 modules slithering among 40 pegs, and how well the
//! rolling gait rolls on flat ground (revolutions per cycle, and distance across the
//! body axis as a fraction of rolling without slip).
//!     cargo run --release --example physics_tuning
use std::f64::consts::PI;
use std::time::Instant;

use snaked::emu::Plant;
use snaked::emu::servo::MODULE_LENGTH_M;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::{Peg, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitParams, GaitSelector, GaitTable, Plane};
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
    let omega = GaitParams::default_for(GaitKind::Rolling).temporal_freq_rad_s;
    let cycle = 2.0 * PI / omega;
    println!("substeps iters pgs friction | RTF pegs | roll rev/cycle  across/ideal");
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
        let mut p = PhysicsPlant::new(&pegs(), config.clone()).unwrap();
        let t0 = Instant::now();
        drive(&mut p, GaitKind::Slithering, 3.0, |_| {});
        let rtf = 3.0 / t0.elapsed().as_secs_f64();
        let mut p = PhysicsPlant::new(&WorldSpec::default(), config).unwrap();
        let mid = N / 2 + 1;
        let (mut roll, mut across, mut last) = (0.0, 0.0, None::<[f64; 3]>);
        drive(&mut p, GaitKind::Rolling, 1.0 + 2.0 * cycle, |pl| {
            let pose = pl.link_pose(mid);
            let [w, x, y, z] = pose.quat_wxyz;
            let q =
                nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
            let axis = q * nalgebra::Vector3::x();
            let flat = nalgebra::Vector3::new(axis.x, axis.y, 0.0).normalize();
            let side = nalgebra::Vector3::z().cross(&flat);
            if pl.time_s() > 1.0 {
                if let Some(l) = last {
                    let d = nalgebra::Vector3::new(
                        pose.position_m[0] - l[0],
                        pose.position_m[1] - l[1],
                        0.0,
                    );
                    across += d.dot(&side);
                }
                roll += pl.link_angvel_rad_s(mid).dot(&axis) * 1e-3;
            }
            last = Some(pose.position_m);
        });
        let ideal = PI * 0.051;
        println!(
            "{substeps:>8} {iters:>5} {pgs:>3} {:>8} | {rtf:>8.1} | {:>14.2} {:>13.2}",
            if coulomb { "coulomb" } else { "simple" },
            roll / (2.0 * PI) / 2.0,
            (across / 2.0).abs() / ideal
        );
    }
}
