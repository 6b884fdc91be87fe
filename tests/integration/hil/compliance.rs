//! Hardware in the loop: snaked drives slithering over UDP through a peg board in
//! snake-emu (physics plant, lockstep), open loop and with the full shape-based
//! compliant controller (`a_ws_omega`, set in the daemon's config).
//!
//! What one board shows end to end: the compliant controller engages, the pegs' torques
//! come back over UDP and reshape the wave (window amplitudes leave their nominal value,
//! the phase runs late) and the shape-forces are non-zero. It no longer asserts that the
//! body gets through: that came from the old speed-clamped servo loop's shaking
//! (docs/emulator.md, "The servo loop"); with the stable loop neither controller
//! slithers forward on the thesis board (docs/measurements/slithering.md). Whether one beats the
//! other is a statistic the lab measures over many trials (docs/lab.md). This test
//! prints both runs' figures.
use crate::support::rig;

use std::path::Path;
use std::time::Duration;

use rig::Rig;

const N: usize = 18;
const SIM_S: f64 = 30.0;
/// The peg-board experiment's board with a layout where the contrast is clear.
const BOARD_SEED: u64 = 1002;

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
    /// Largest |A_window − A₀| seen in `status`, rad, and the most negative phase lag.
    amplitude_excursion_rad: f64,
    min_phase_lag_rad: f64,
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
             [gait.controllers.slithering]\ncontroller = \"{controller}\""
        ),
    );
    let mut rig = rig;
    let a0 = std::f64::consts::FRAC_PI_4;
    let (mut excursion, mut min_lag) = (0.0f64, 0.0f64);
    let deadline = std::time::Instant::now() + Duration::from_secs(300);
    loop {
        let s = rig.client.call("status", serde_json::json!({}));
        let c = &s["controller"];
        if c["state"] == "engaged" {
            for w in c["fields"][0]["windows"].as_array().into_iter().flatten() {
                excursion = excursion.max((w["value"].as_f64().unwrap() - a0).abs());
            }
            let lag = c["signals"]["phase_lag_rad"].as_f64().unwrap_or(0.0);
            min_lag = min_lag.min(lag);
        }
        if s["t_s"].as_f64().unwrap() >= SIM_S {
            assert_eq!(c["state"], "engaged", "{s}");
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "timed out; last status {s}"
        );
        std::thread::sleep(Duration::from_millis(20));
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
        amplitude_excursion_rad: excursion,
        min_phase_lag_rad: min_lag,
    };
    println!(
        "{controller}: body centre moved {:.3} m along the board in {SIM_S} s; lateral joints' \
         mean |torque| {:.2} N·m, above 6 N·m {:.1} % of the time; amplitude windows up to \
         {:.3} rad off nominal, phase lag down to {:.3} rad",
        o.progress_m,
        o.mean_abs_torque_nm,
        100.0 * o.saturated,
        o.amplitude_excursion_rad,
        o.min_phase_lag_rad
    );
    o
}

#[test]
fn compliant_slithering_over_udp_reshapes_to_the_pegs() {
    let open = run("open_loop");
    let compliant = run("a_ws_omega");
    println!(
        "progress along the board in {SIM_S} s: open loop {:+.3} m, a_ws_omega {:+.3} m",
        open.progress_m, compliant.progress_m
    );
    assert!(
        compliant.amplitude_excursion_rad > 0.05,
        "the pegs reshaped the wave: {:.3} rad",
        compliant.amplitude_excursion_rad
    );
    assert!(
        compliant.min_phase_lag_rad < -0.01,
        "{:.3}",
        compliant.min_phase_lag_rad
    );
    // Open loop never reports a shape (its wave is fixed).
    assert_eq!(open.amplitude_excursion_rad, 0.0);
}
