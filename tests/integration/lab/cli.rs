//! `snake-lab` end to end with tiny settings: outputs, determinism, bad input.

use std::path::Path;
use std::process::Output;

use super::{lab, lab_ok, read};

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// A tiny peg-board run (1 start, 2 s) into `out`; panics with stderr unless it succeeds.
fn pegboard(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![out.to_str().unwrap()];
    args.extend_from_slice(extra);
    lab_ok(
        "pegboard --controllers open_loop --starts 1 --seconds 2 --quiet --out",
        &args,
    )
}

#[test]
fn pegboard_writes_csv_summary_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let o = pegboard(dir.path(), &["--layouts", "2", "--threads", "2"]);
    let csv = read(&dir.path().join("results.csv"));
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        rows[0],
        [
            "controller",
            "layout",
            "start",
            "repeat",
            "success",
            "seconds",
            "cycles",
            "path_m",
            "distance_m",
            "cycles_per_m",
            "stuck_s",
            "self_contacts",
            "side_exit",
            "progress_m",
            "guard_limited_pct",
            "peak_joint_speed_rad_s",
            "mean_joint_speed_rad_s",
            "fast_joint_pct",
            "torque_limit_pct",
            "moving_s",
            "stuck_while_moving_pct",
            "jammed_s",
            "stuck_while_jammed_pct",
            "jam_episodes",
            "jams_reported",
            "jam_report_delay_s",
            "odometry_direction_err_deg",
            "odometry_right_pct",
            "odometry_length_ratio",
            "odometry_false_motion_pct",
            "position_tracked_pct",
            "position_err_mean_m",
            "position_err_max_m",
            "position_far_pct"
        ]
    );
    assert_eq!(rows.len(), 3, "header + 2 layouts x 1 start:\n{csv}");
    for (row, layout) in rows[1..].iter().zip(["seed1000", "seed1001"]) {
        assert_eq!(row.len(), 34);
        // No position source: its columns are empty (NaN).
        assert_eq!(&row[30..], ["NaN", "NaN", "NaN", "NaN"], "{row:?}");
        // 2 s of open loop from rest: the blend and the wave stay within the motors.
        let guarded: f64 = row[14].parse().unwrap();
        assert_eq!(guarded, 0.0, "{row:?}");
        let peak: f64 = row[15].parse().unwrap();
        assert!(peak.is_finite() && peak > 0.0, "{row:?}");
        assert_eq!(row[11], "0", "no self-contact in 2 s of open loop");
        assert_eq!(row[12], "false", "no side exit in 2 s");
        let progress_m: f64 = row[13].parse().unwrap();
        let distance_m: f64 = row[8].parse().unwrap();
        assert!(progress_m.abs() <= distance_m + 1e-4, "{row:?}");
        assert_eq!(&row[..4], ["open_loop", layout, "0", "0"]);
        assert_eq!(row[4], "false", "2 s cannot cross a 2 m board");
        assert_eq!(row[5], "2.000");
        let cycles_per_m: f64 = row[9].parse().unwrap();
        assert!(cycles_per_m.is_finite() && cycles_per_m > 0.0);
    }
    let summary = read(&dir.path().join("summary.md"));
    assert!(
        summary.contains("| controller | trials | success | side exits |"),
        "{summary}"
    );
    assert!(
        summary.contains("| controller | guard-limited % (median / max) |"),
        "the strain table: {summary}"
    );
    assert!(
        summary.contains("| open_loop | 2 | 0/2 (0 %) |"),
        "{summary}"
    );
    assert!(summary.contains("snake-lab pegboard --controllers open_loop"));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        summary,
        "stdout = summary"
    );
    for png in [
        "path-open_loop.png",
        "signals-open_loop.png",
        "cycles_per_m.png",
    ] {
        let bytes = std::fs::read(dir.path().join(png)).unwrap();
        assert!(bytes.starts_with(&PNG_SIGNATURE), "{png} is not a PNG");
        assert!(summary.contains(png), "summary lists {png}");
    }
}

#[test]
fn results_are_deterministic_for_any_thread_count() {
    let dirs: Vec<_> = (0..3).map(|_| tempfile::tempdir().unwrap()).collect();
    pegboard(dirs[0].path(), &["--layouts", "2", "--threads", "1"]);
    pegboard(dirs[1].path(), &["--layouts", "2", "--threads", "2"]);
    pegboard(dirs[2].path(), &["--layouts", "2", "--threads", "2"]);
    let csv: Vec<String> = dirs
        .iter()
        .map(|d| read(&d.path().join("results.csv")))
        .collect();
    assert_eq!(csv[1], csv[2], "same run twice");
    assert_eq!(csv[0], csv[1], "--threads 1 vs 2");
    let other_seeds = tempfile::tempdir().unwrap();
    pegboard(other_seeds.path(), &["--layouts", "2", "--seed-base", "7"]);
    assert_ne!(read(&other_seeds.path().join("results.csv")), csv[0]);
}

#[test]
fn explicit_layouts_come_from_scenario_files() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("two-pegs.toml");
    std::fs::write(
        &file,
        "[[peg]]\nx_m = 0.5\ny_m = 0.15\ndiameter_m = 0.04\n\
         [[peg]]\nx_m = 0.8\ny_m = -0.15\ndiameter_m = 0.04\n\
         [start]\nhead_m = [0.2, 0.0]\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    pegboard(
        &out,
        &["--layouts", "0", "--scenario", file.to_str().unwrap()],
    );
    let csv = read(&out.join("results.csv"));
    let rows: Vec<_> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 1, "{csv}");
    assert!(rows[0].starts_with("open_loop,two-pegs,0,"), "{csv}");
}

#[test]
fn variants_run_beside_the_named_controllers() {
    let dir = tempfile::tempdir().unwrap();
    pegboard(
        dir.path(),
        &[
            "--layouts",
            "1",
            "--variant",
            r#"soft_a={"controller":"a","amplitude":{"gains":{"stiffness":1}}}"#,
        ],
    );
    let csv = read(&dir.path().join("results.csv"));
    let labels: Vec<_> = csv
        .lines()
        .skip(1)
        .map(|r| r.split(',').next().unwrap())
        .collect();
    assert_eq!(labels, ["open_loop", "soft_a"], "{csv}");
    let summary = read(&dir.path().join("summary.md"));
    assert!(summary.contains("| soft_a |"), "{summary}");
    assert!(
        summary.contains("stiffness"),
        "the command line is in the summary"
    );
}

#[test]
fn list_names_every_experiment_and_what_it_can_run() {
    let o = lab(&["list"]);
    assert!(o.status.success());
    let names = String::from_utf8_lossy(&o.stdout);
    for line in [
        "  default: open_loop, a_ws_omega, dc_switching, ac_sfc",
        "  default: dc3d_nc, dc3d_ndc, dc3d_pdc, dc3d_switching",
        "  default: ac_sfc, ac, sfc, sw_open_loop",
        "  default: fixed, central, windowed, windowed_adaptive",
    ] {
        assert!(names.lines().any(|l| l == line), "{line}: {names}");
    }
    for experiment in [
        "pegboard",
        "peg-array",
        "rock-pile",
        "sidewinding",
        "pole",
        "flat-ground",
        "crossing",
    ] {
        assert!(
            names
                .lines()
                .any(|l| l.starts_with(&format!("{experiment}: "))),
            "{experiment}: {names}"
        );
    }
    // Crossing runs the navigator too (issue 44): named under it, and nowhere else.
    let crossing = names.split("\ncrossing: ").nth(1).expect("crossing listed");
    assert!(
        crossing.contains("navigator: navigator, navigator_sidewind_only, navigator_turn_only"),
        "{crossing}"
    );
    assert_eq!(names.matches("navigator_turn_only").count(), 1, "{names}");
}

/// Runs `args` expecting exit code 2 and returns stderr.
fn bad_input(args: &[&str]) -> String {
    let o = lab(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    err
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let err = bad_input(&["pegboard", "--controllers", "open_loop,nope", "--out", out]);
    assert!(
        err.contains("\"nope\"") && err.contains("known: open_loop"),
        "{err}"
    );
    let err = bad_input(&["pegboard", "--layouts", "0", "--out", out]);
    assert!(err.contains("no layouts"), "{err}");
    let err = bad_input(&[
        "pegboard",
        "--scenario",
        "/no/such/board.toml",
        "--out",
        out,
    ]);
    assert!(err.contains("/no/such/board.toml"), "{err}");
    let err = bad_input(&["pegboard", "--threads", "0", "--out", out]);
    assert!(err.contains("--threads"), "{err}");
    let err = bad_input(&["pegboard", "--seconds", "0", "--out", out]);
    assert!(err.contains("time limit"), "{err}");
    bad_input(&["pegboard", "--layouts", "many"]);
    let err = bad_input(&["pegboard", "--servo-loop", "stiff", "--out", out]);
    assert!(
        err.contains("speed-clamped") && err.contains("profiled"),
        "{err}"
    );
    let err = bad_input(&["pegboard", "--variant", "soft", "--out", out]);
    assert!(err.contains("LABEL=JSON"), "{err}");
    let err = bad_input(&[
        "pegboard",
        "--variant",
        r#"soft={"amplitude":{"gains":{"stifness":1}}}"#,
        "--out",
        out,
    ]);
    assert!(
        err.contains("config.amplitude.gains") && err.contains("stifness"),
        "{err}"
    );
    // The nominal gait is checked as the daemon checks `params.set`.
    let err = bad_input(&[
        "pegboard",
        "--nominal",
        r#"{"amplitude_lat_rad":2.0}"#,
        "--out",
        out,
    ]);
    assert!(
        err.contains("--nominal") && err.contains("amplitude_lat_rad"),
        "{err}"
    );
    let err = bad_input(&["peg-array", "--nominal", r#"{"amp":1}"#, "--out", out]);
    assert!(err.contains("--nominal") && err.contains("amp"), "{err}");
    let err = bad_input(&[
        "sidewinding",
        "--nominal",
        r#"{"temporal_freq_rad_s":1e9}"#,
        "--out",
        out,
    ]);
    assert!(
        err.contains("--nominal") && err.contains("temporal_freq_rad_s"),
        "{err}"
    );
    assert!(
        !dir.path().join("results.csv").exists(),
        "nothing written on bad input"
    );
}

#[test]
fn every_trial_can_be_recorded_and_the_file_holds_every_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("runs");
    let rec_s = rec.to_str().unwrap();
    pegboard(
        dir.path(),
        &[
            "--layouts",
            "1",
            "--variant",
            "soft_a={\"controller\":\"a\"}",
            "--record",
            rec_s,
        ],
    );
    let mut files: Vec<String> = std::fs::read_dir(&rec)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        ["open_loop-seed1000-s0.mcap", "soft_a-seed1000-s0.mcap"]
    );
    let bytes = std::fs::read(rec.join("soft_a-seed1000-s0.mcap")).unwrap();
    let mut counts = std::collections::BTreeMap::<String, u64>::new();
    for m in mcap::MessageStream::new(&bytes).expect("a finished MCAP file") {
        *counts.entry(m.unwrap().channel.topic.clone()).or_default() += 1;
    }
    // 2 s at 1 kHz through the daemon's loop, nothing dropped (the lab waits for the
    // writer), the pegs and the body in 3-D.
    assert_eq!(counts["/joints"], 2000, "{counts:?}");
    assert_eq!(counts["/commands"], 2000);
    assert_eq!(counts["/scene/world"], 1);
    assert!(counts["/tf"] >= 100, "{counts:?}");
}

/// Under a file-size limit with the default signal handling (`ulimit -f`, a batch job's
/// limit), a trial's recording that outgrows it is an error naming the file, not a
/// SIGXFSZ that kills the run without a word.
#[test]
fn a_recording_past_the_file_size_limit_is_reported_not_killed() {
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("runs");
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_snake-lab"));
    cmd.args(["pegboard", "--controllers", "open_loop", "--starts", "1"])
        .args(["--seconds", "2", "--layouts", "1", "--quiet", "--out"])
        .arg(dir.path().join("out"))
        .arg("--record")
        .arg(&rec);
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: 100_000,
                rlim_max: 100_000,
            };
            libc::setrlimit(libc::RLIMIT_FSIZE, &lim);
            libc::signal(libc::SIGXFSZ, libc::SIG_DFL);
            Ok(())
        });
    }
    let o = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.signal(), None, "killed by a signal: {err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    let file = rec.join("open_loop-seed1000-s0.mcap");
    assert!(
        err.contains(&file.display().to_string()) && err.contains("File too large"),
        "{err}"
    );
}

#[test]
fn peg_array_runs_poses_times_repeats_calibrated_and_reports_the_spread() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pa");
    let args = [
        "peg-array",
        "--controllers",
        "dc_nc,dc_switching",
        "--starts",
        "2",
        "--repeats",
        "2",
        "--seconds",
        "3",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = lab(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = read(&out.join("results.csv"));
    let rows: Vec<&str> = csv.lines().collect();
    assert!(
        rows[0].starts_with("controller,layout,pose,repeat,seconds,displacement_m,velocity_bl_min")
    );
    assert_eq!(rows.len(), 1 + 2 * 2 * 2, "{csv}");
    assert!(rows[1].starts_with("dc_nc,seed101,0,0,"), "{csv}");
    assert!(rows[2].starts_with("dc_nc,seed101,0,1,"), "{csv}");
    // Repeats of a pose differ only in their sensor noise: not bit-identical (in some
    // measured column: after 3 s they may agree to the printed digit in one of them).
    let measured = |r: &str| r.split(',').skip(5).map(str::to_owned).collect::<Vec<_>>();
    assert_ne!(measured(rows[1]), measured(rows[2]), "{csv}");
    let md = read(&out.join("summary.md"));
    assert!(md.contains("sd across poses"), "{md}");
    assert!(md.contains("| seed101 pose 1 |"), "{md}");
    assert!(
        md.contains("- dc_switching: `{\"dorsal_rad\""),
        "calibrated: {md}"
    );
    for f in [
        "velocity.png",
        "absitions-dc_switching.png",
        "path-dc_nc.png",
    ] {
        let bytes = std::fs::read(out.join(f)).unwrap();
        assert_eq!(bytes[..8], PNG_SIGNATURE, "{f}");
    }
}

#[test]
fn rock_pile_runs_the_3d_controllers() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rp");
    let o = lab(&[
        "rock-pile",
        "--controllers",
        "dc3d_switching",
        "--starts",
        "1",
        "--repeats",
        "1",
        "--seconds",
        "2",
        "--no-calibrate",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = read(&out.join("summary.md"));
    assert!(
        md.contains("rock pile") && md.contains("| dc3d_switching | 1 |"),
        "{md}"
    );
    assert!(!md.contains("Calibrated"), "--no-calibrate: {md}");
    // Bad input is refused before any trial.
    let o = lab(&[
        "rock-pile",
        "--repeats",
        "0",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = lab(&["peg-array", "--controllers", "a_ws_omega,bogus", "--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown controller"));
}

#[test]
fn sidewinding_runs_starts_times_repeats_and_writes_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sw");
    let o = lab(&[
        "sidewinding",
        "--controllers",
        "ac_sfc,sw_open_loop",
        "--starts",
        "1",
        "--repeats",
        "2",
        "--seconds",
        "3",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = read(&out.join("results.csv"));
    let rows: Vec<&str> = csv.lines().collect();
    assert!(
        rows[0].starts_with("controller,layout,start,repeat,outcome,seconds,first_opening"),
        "{csv}"
    );
    assert_eq!(rows.len(), 1 + 2 * 2, "{csv}");
    // Three seconds cannot get the body through the array: a time-out each.
    assert!(
        rows[1].starts_with("ac_sfc,") && rows[1].contains(",timeout,"),
        "{csv}"
    );
    assert!(rows[3].starts_with("sw_open_loop,"), "{csv}");
    let md = read(&out.join("summary.md"));
    assert!(md.contains("| ac_sfc | 2 | 0 |"), "{md}");
    for f in [
        "metrics.png",
        "trial-ac_sfc.png",
        "signals-sw_open_loop.png",
    ] {
        let bytes = std::fs::read(out.join(f)).unwrap();
        assert_eq!(bytes[..8], PNG_SIGNATURE, "{f}");
    }
    // A scenario without a peg array is refused before any trial.
    let o = lab(&[
        "sidewinding",
        "--scenario",
        concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat.toml"),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("peg_fence"));
}

#[test]
fn pole_runs_named_and_seeded_poles_and_writes_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pole");
    let o = lab(&[
        "pole",
        "--poles",
        "step-up",
        "--seeded",
        "1",
        "--starts",
        "1",
        "--controllers",
        "fixed,windowed_adaptive",
        "--seconds",
        "8",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = read(&out.join("results.csv"));
    let rows: Vec<&str> = csv.lines().collect();
    assert!(
        rows[0].starts_with("controller,pole,start,repeat,outcome,seconds,top_s"),
        "{csv}"
    );
    assert_eq!(rows.len(), 1 + 2 * 2, "{csv}");
    assert!(rows[1].starts_with("fixed,step-up,0,"), "{csv}");
    assert!(rows[2].starts_with("fixed,seed100,0,"), "{csv}");
    let md = read(&out.join("summary.md"));
    assert!(md.contains("| windowed_adaptive | 2 |"), "{md}");
    assert!(
        md.contains("| step-up |") && md.contains("| seed100 |"),
        "{md}"
    );
    // The windowed controller's half turns exist once the coil opens (about 3.5 s in).
    for f in ["climb.png", "windows-windowed_adaptive.png"] {
        let bytes = std::fs::read(out.join(f)).unwrap();
        assert_eq!(bytes[..8], PNG_SIGNATURE, "{f}");
    }
    let err = bad_input(&["pole", "--poles", "nope", "--out", out.to_str().unwrap()]);
    assert!(err.contains("\"nope\"") && err.contains("step-up"), "{err}");
    let err = bad_input(&["pole", "--mu", "0", "--out", out.to_str().unwrap()]);
    assert!(err.contains("--mu"), "{err}");
    let err = bad_input(&[
        "pole",
        "--controllers",
        "central,ac_sfc",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        err.contains("ac_sfc") && err.contains("windowed_adaptive"),
        "{err}"
    );
}
