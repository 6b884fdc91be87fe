//! Determinism in lockstep, end to end: snake-emu on the physics plant and snaked,
//! both in lockstep over UDP, run twice with the same world and seed: the emulator's
//! recorded trajectories are identical, value for value.
use crate::support::rig;

use std::time::Duration;

use rig::{Recording, Rig};

const N: usize = 18;
const SIM_S: f64 = 2.0;

fn run() -> Recording {
    let world = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/peg-board-40.toml");
    let mut rig = Rig::start(
        N,
        &["--mode", "lockstep", "--world", world, "--seed", "3"],
        "",
        "[loop]\npacing = \"lockstep\"\n[gait]\ninitial = \"sidewinding\"\nstart = \"run\"",
    );
    rig.client
        .wait_status(Duration::from_secs(120), "simulated time", |s| {
            s["t_s"].as_f64().unwrap() >= SIM_S
        });
    rig.stop(N)
}

#[test]
fn same_world_and_seed_give_the_same_trajectory_in_lockstep() {
    let (a, b) = (run(), run());
    let rows = a.span(0.0, SIM_S).end.min(b.span(0.0, SIM_S).end);
    assert!(rows > 1500, "both runs recorded {rows} rows");
    let mut moved = 0.0f64;
    for k in 0..rows {
        assert_eq!(a.t[k], b.t[k]);
        for i in 0..N {
            for (x, y, what) in [
                (a.cmd[i][k], b.cmd[i][k], "set-point"),
                (a.pos[i][k], b.pos[i][k], "position"),
                (a.torque[i][k], b.torque[i][k], "torque"),
            ] {
                assert!(
                    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                    "joint {i} {what} differs at t = {}: {x} vs {y}",
                    a.t[k]
                );
            }
            moved = moved.max(a.pos[i][k].abs());
        }
    }
    assert!(moved > 0.3, "the snake really moved ({moved} rad)");
}
