//! Getting on the pole (issue 12, point 3), open loop through the physics plant: the
//! body lies straight on the ground beside the pole (`scenarios/pole.toml`), rolls
//! (the rolling gait) for `ROLL` s, then the selector blends into the rolling helix of
//! radius `R` (m; the gait's pitch angle kept) at `WT` rad/s. Every second: the gait,
//! the centre of mass's height, how many links are within a module diameter of the
//! pole's surface and how far round the pole they reach (the angle they sweep, in
//! turns), and where link N/4 is. The data behind the choice of how the body gets on
//! the pole (docs/compliance.md, "Rolling helix").
//!     cargo run --release --example pole_windup -- [SCENARIO.toml]
//! Measured 2026-12-03 (`ROLL=7`): the body rolls toward the pole at about 0.036 m/s
//! and touches it at 6-7 s; the blend into the helix then coils it round its own
//! axis, which lies on the ground, and the coil rolls away from the pole (no link
//! near it from 8 s on, the centre of mass at 0.075 m). A plain blend from the rolling
//! gait does not get on the pole.
//! Environment: SECS (40), ROLL (4), R (0.06), WT (0.5), RWT (the rolling gait's ωT),
//! BLEND (the selector's blend time, s; 2).
use std::f64::consts::{PI, TAU};

use snaked::emu::Plant;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::module::MODULE_LENGTH_M;
use snaked::protocol::Command;

fn env(name: &str, d: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let file = args.get(1).cloned().unwrap_or("scenarios/pole.toml".into());
    let n = 18;
    let sc = WorldScenario::load(std::path::Path::new(&file)).unwrap();
    let spec = sc.generate_trial(n, 0).unwrap();
    let pole = spec
        .poles
        .first()
        .expect("the scenario has no pole")
        .clone();
    let layout = BodyLayout::alternating(n, Plane::Lateral, MODULE_LENGTH_M);
    let mut table = GaitTable::default();
    {
        let r = table.get_mut(GaitKind::Rolling);
        r.temporal_freq_rad_s = env("RWT", r.temporal_freq_rad_s);
    }
    {
        let h = table.get_mut(GaitKind::RollingHelix);
        let radius = env("R", 0.06);
        h.helix_pitch_m *= radius / h.helix_radius_m;
        h.helix_radius_m = radius;
        h.temporal_freq_rad_s = env("WT", 0.5);
    }
    let mut sel = GaitSelector::new(
        layout.clone(),
        table,
        GaitKind::Rolling,
        env("BLEND", 2.0),
        3.46,
    );
    let mut plant = PhysicsPlant::new(
        &spec,
        PhysicsConfig {
            modules: n,
            seed: 7,
            ..PhysicsConfig::default()
        },
    )
    .unwrap();
    let (mut pos, mut vel) = (vec![0.0; n], vec![0.0; n]);
    let mut cmds = vec![Command::LIMP; n];
    let roll_s = env("ROLL", 4.0);
    let steps = (env("SECS", 40.0) * 1e3) as usize;
    for l in [0, n / 2, n] {
        let p = plant.link_pose(l).position_m;
        println!("start: link {l} at ({:.3}, {:.3}, {:.3})", p[0], p[1], p[2]);
    }
    println!(
        "pole at ({:.3}, {:.3}), sections {:?}",
        pole.x_m, pole.y_m, pole.sections
    );
    println!("t s | gait | COM z m | links near the pole | swept round it, turns | mean link z m");
    for k in 1..=steps {
        let t = plant.time_s();
        if (t - roll_s).abs() < 0.5e-3 {
            sel.set_gait(GaitKind::RollingHelix, t);
        }
        sel.update(t, &mut pos, &mut vel);
        for (cmd, &p) in cmds.iter_mut().zip(&pos) {
            *cmd = Command::position(p);
        }
        plant.step(1e-3, &cmds);
        if k % 1000 == 0 {
            let com = plant.centre_of_mass_m();
            let mid = plant.link_pose(n / 4).position_m;
            let (mut near, mut angles, mut zsum) = (0, Vec::new(), 0.0);
            for l in 0..plant.link_count() {
                let p = plant.link_pose(l).position_m;
                let d = (p[0] - pole.x_m).hypot(p[1] - pole.y_m);
                let r = pole
                    .sections
                    .iter()
                    .find(|s| p[2] <= s.z1_m)
                    .map_or(0.0, |s| 0.5 * s.diameter_m);
                if d < r + 0.06 {
                    near += 1;
                    angles.push((p[1] - pole.y_m).atan2(p[0] - pole.x_m));
                }
                zsum += p[2];
            }
            // Unwrapped sweep of the near links in body order.
            let mut swept = 0.0;
            for w in angles.windows(2) {
                let mut d = w[1] - w[0];
                if d > PI {
                    d -= TAU;
                } else if d < -PI {
                    d += TAU;
                }
                swept += d;
            }
            println!(
                "{:.0} | {:?} | {:.3} | {near} | {:+.2} | {:.3} | link {} at ({:.3}, {:.3}, {:.3})",
                plant.time_s(),
                sel.active(),
                com[2],
                swept / TAU,
                zsum / plant.link_count() as f64,
                n / 4,
                mid[0],
                mid[1],
                mid[2]
            );
        }
    }
}
