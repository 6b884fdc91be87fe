//! Open-loop slithering on a peg board, straight through the physics plant (no daemon
//! loop): how far the body's centre goes along its start heading, and what touches it
//! (contact pairs with the ground and the pegs, their normal force, the lateral joints'
//! mean |torque| and the share of them near the 7 N·m limit), every 5 s. The data behind
//! docs/measurements/slithering.md, "Slithering among pegs: the nominal shape".
//!     cargo run --release --example peg_diag -- [SCENARIO.toml] [START]
//! Environment: SECS (60), AMP, WS, WT (the gait's lateral amplitude, spatial and
//! temporal frequency; default the daemon's), MU, PEG_MU (friction).
use snaked::emu::Plant;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::lab::trial::centre;
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
    let file = args
        .get(1)
        .cloned()
        .unwrap_or("scenarios/peg-board-40-inside.toml".into());
    let trial: u64 = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(0);
    let secs = env("SECS", 60.0);
    let n_mod: usize = env("MODULES", 18.0) as usize;
    let sc = WorldScenario::load(std::path::Path::new(&file)).unwrap();
    let mut spec = sc.generate_trial(n_mod, trial).unwrap();
    if let Ok(v) = std::env::var("PEG_MU") {
        spec.friction.peg_mu = Some(v.parse().unwrap());
    }
    spec.friction.mu = env("MU", spec.friction.mu);
    let layout = BodyLayout::alternating(n_mod, Plane::Lateral, MODULE_LENGTH_M);
    let mut table = GaitTable::default();
    {
        let p = table.get_mut(GaitKind::Slithering);
        p.amplitude_lat_rad = env("AMP", p.amplitude_lat_rad);
        p.spatial_freq_rad = env("WS", p.spatial_freq_rad);
        p.temporal_freq_rad_s = env("WT", p.temporal_freq_rad_s);
    }
    let mut sel = GaitSelector::new(layout.clone(), table, GaitKind::Slithering, 0.5, 3.46);
    let mut plant = PhysicsPlant::new(
        &spec,
        PhysicsConfig {
            modules: n_mod,
            seed: 7,
            ..PhysicsConfig::default()
        },
    )
    .unwrap();
    let (mut pos, mut vel) = (vec![0.0; n_mod], vec![0.0; n_mod]);
    let mut cmds = vec![Command::LIMP; n_mod];
    let c0 = centre(&plant);
    let h0 = {
        let (h, t) = (
            plant.link_pose(0).position_m,
            plant.link_pose(n_mod).position_m,
        );
        let d = [h[0] - t[0], h[1] - t[1]];
        let l = d[0].hypot(d[1]);
        [d[0] / l, d[1] / l]
    };
    let steps = (secs * 1e3) as usize;
    let (mut sat, mut contacts, mut force, mut tau) = (0.0, 0.0, 0.0, 0.0);
    let mut last = c0;
    for k in 1..=steps {
        sel.update(plant.time_s(), &mut pos, &mut vel);
        for (cmd, &p) in cmds.iter_mut().zip(&pos) {
            *cmd = Command::position(p);
        }
        plant.step(1e-3, &cmds);
        let c = plant.contacts();
        contacts += c.pairs as f64;
        force += c.normal_force_n;
        for i in (0..n_mod).step_by(2) {
            let t = f64::from(plant.feedback(i).torque_nm.abs());
            tau += t / (n_mod / 2) as f64;
            if t > 6.0 {
                sat += 1.0 / (n_mod / 2) as f64;
            }
        }
        if k % 5000 == 0 {
            let n = 5000.0;
            let cc = centre(&plant);
            let fwd = (cc[0] - last[0]) * h0[0] + (cc[1] - last[1]) * h0[1];
            println!(
                "t {:5.1} fwd {:+.3} m/5s  peg pairs {:.2} n_mod {:.1} |tau| {:.2} sat {:.2}",
                k as f64 * 1e-3,
                fwd,
                contacts / n,
                force / n,
                tau / n,
                sat / n
            );
            last = cc;
            (sat, contacts, force, tau) = (0.0, 0.0, 0.0, 0.0);
        }
    }
    let c1 = centre(&plant);
    println!(
        "progress along start heading {:+.3} m",
        (c1[0] - c0[0]) * h0[0] + (c1[1] - c0[1]) * h0[1]
    );
}
