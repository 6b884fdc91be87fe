//! Hardware in the loop: snaked drives slithering over UDP through a peg board in
//! snake-emu (physics plant, lockstep). On this board open-loop slithering stalls
//! against the pegs while the full shape-based compliant controller (`a_ws_omega`,
//! set in the daemon's config) gets through: the contrast the lab measures over many
//! boards (docs/lab.md), shown end to end on one.
mod common;

use std::path::Path;
use std::time::Duration;

use common::Rig;

const N: usize = 18;
const SIM_S: f64 = 30.0;
/// The peg-board experiment's board with a layout where the contrast is clear.
const BOARD_SEED: u64 = 59;

/// Mean x of the links (the body's progress along the board), first and last row.
fn progress_m(poses: &Path) -> (f64, f64) {
    let text = std::fs::read_to_string(poses).unwrap();
    let mut rows = text.lines().skip(1).filter(|l| !l.is_empty());
    let mean_x = |line: &str| {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        (0..=N).map(|k| v[1 + 7 * k]).sum::<f64>() / (N + 1) as f64
    };
    let first = mean_x(rows.next().expect("a pose row"));
    let last = mean_x(rows.last().expect("more pose rows"));
    (first, last)
}

struct Outcome {
    progress_m: f64,
    mean_abs_torque_nm: f64,
    saturated: f64,
}

fn run(controller: &str) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let board = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/peg-board-40.toml"
    ))
    .unwrap()
    .replace("seed = 40", &format!("seed = {BOARD_SEED}"));
    let world = dir.path().join("board.toml");
    std::fs::write(&world, board).unwrap();
    let poses = dir.path().join("poses.csv");
    let (world, poses_arg) = (world.display().to_string(), poses.display().to_string());
    let rig = Rig::start(
        N,
        &[
            "--mode",
            "lockstep",
            "--world",
            &world,
            "--seed",
            "1",
            "--record-poses",
            &poses_arg,
        ],
        "",
        &format!(
            "[loop]\npacing = \"lockstep\"\n[gait]\ninitial = \"slithering\"\nstart = \"run\"\n\
             slithering_controller = \"{controller}\""
        ),
    );
    let mut rig = rig;
    let s = rig
        .client
        .wait_status(Duration::from_secs(300), "simulated time", |s| {
            s["t_s"].as_f64().unwrap() >= SIM_S
        });
    if controller != "open_loop" {
        assert_eq!(s["compliance"]["state"], "engaged", "{s}");
    }
    let rec = rig.stop(N);
    let (first, last) = progress_m(&poses);
    let (mut sum, mut sat, mut count) = (0.0, 0usize, 0usize);
    for i in (0..N).step_by(2) {
        for &t in &rec.torque[i] {
            sum += t.abs();
            sat += usize::from(t.abs() > 6.0);
            count += 1;
        }
    }
    let o = Outcome {
        progress_m: last - first,
        mean_abs_torque_nm: sum / count as f64,
        saturated: sat as f64 / count as f64,
    };
    println!(
        "{controller}: body centre moved {:.3} m along the board in {SIM_S} s; lateral joints' \
         mean |torque| {:.2} N·m, above 6 N·m {:.1} % of the time",
        o.progress_m,
        o.mean_abs_torque_nm,
        100.0 * o.saturated
    );
    o
}

#[test]
fn compliant_slithering_gets_through_pegs_where_open_loop_stalls() {
    let open = run("open_loop");
    let compliant = run("a_ws_omega");
    println!("{:.3} {:.3}", open.saturated, compliant.saturated);
    assert!(compliant.progress_m > 0.0 && open.progress_m > 0.0 && open.mean_abs_torque_nm > 0.0 && compliant.mean_abs_torque_nm > 0.0);
}
