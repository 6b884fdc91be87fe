//! Diagnostic (issue 28, point 2): does a jam show in what the daemon senses? A body
//! jammed among pegs settles into an exact limit cycle (its centre repeats each gait
//! cycle to the millimetre), one making way among irregular pegs does not. Per gait
//! cycle: the true displacement and how far the joint torques are from repeating
//! (RMS of τ(t) − τ(t − T) over the cycle, over the RMS of τ).

use std::f64::consts::TAU;

use crate::emu::world::physics::PhysicsPlant;
use crate::emu::world::scenario::WorldScenario;
use crate::gait::{GaitKind, GaitParams};
use crate::lab::compared::LabController;
use crate::lab::trial::{TrialConfig, centre, plant_of, trial_loop};

#[test]
#[ignore = "diagnostic: prints per gait cycle the true displacement and the torques' repeat error"]
fn jams_repeat_and_progress_does_not() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let p = GaitParams::default_for(GaitKind::Slithering);
    let sleeve = GaitParams {
        amplitude_lat_rad: 1.1,
        spatial_freq_rad: TAU,
        ..p
    };
    let toml = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/peg-board-40-sleeve.toml"
    ))
    .unwrap();
    let mut scenario = WorldScenario::parse(&toml).unwrap();
    for seed in env("SEED", 1000)..env("SEED", 1000) + env("WORLDS", 3) {
        scenario.seed = seed;
        let world = scenario.generate(18).unwrap();
        let controller = LabController::named(GaitKind::Slithering, "a_ws_omega").unwrap();
        let mut config = TrialConfig::default();
        *config.gaits.get_mut(GaitKind::Slithering) = sleeve;
        config.limit_s = 1000.0;
        let plant = PhysicsPlant::new(&world, config.physics(seed)).unwrap();
        let (mut lp, _, _, _, _) = trial_loop(&controller, plant, &config, None, &[]).unwrap();
        let steps = (TAU / sleeve.temporal_freq_rad_s * 1000.0).round() as usize;
        let n = plant_of(&lp).link_count() - 1;
        let mut last: Vec<f64> = vec![f64::NAN; steps * n];
        println!("seed {seed}:");
        for cycle in 0..15 {
            let p0 = centre(plant_of(&lp));
            let (mut diff, mut norm) = (0.0, 0.0);
            for k in 0..steps {
                lp.step();
                for j in 0..n {
                    let tau = f64::from(plant_of(&lp).feedback(j).torque_nm);
                    let before = last[k * n + j];
                    if before.is_finite() {
                        diff += (tau - before).powi(2);
                    }
                    norm += tau * tau;
                    last[k * n + j] = tau;
                }
            }
            let p1 = centre(plant_of(&lp));
            let d = (p1[0] - p0[0]).hypot(p1[1] - p0[1]);
            println!(
                "  cycle {cycle:2}: moved {d:.3} m, torque repeat error {:.2}",
                if cycle == 0 {
                    f64::NAN
                } else {
                    (diff / norm).sqrt()
                }
            );
        }
    }
}
