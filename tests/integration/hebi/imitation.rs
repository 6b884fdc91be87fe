//! The whole daemon over HEBI's imitation group of 18: it starts, the loop turns through
//! libhebi, gaits switch and a controller chosen at run time drives through the control
//! socket, and SIGTERM stops it safely.
//!
//! What a controller gets from an imitation group: the imitation echoes each command as
//! feedback, so the joints' positions and velocities are what the bus commanded (a cycle
//! late). The bus commands an effort it leaves unset as 0 to an imitation, so the torque
//! every controller sees is 0: a compliant controller feels no force and behaves as open
//! loop there (its shape stays nominal). There is no IMU motion either: accelerometer and
//! gyro read 0, so the pose estimate has no gravity to start from and stays invalid.
use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use super::{config, libhebi, telemetry_until, write_config};
use crate::support::rig::{Client, Proc, exe};

const MODULES: usize = 18;
const WAIT: Duration = Duration::from_secs(30);

#[test]
fn the_daemon_drives_an_imitation_group_switches_gaits_engages_a_controller_and_stops_safely() {
    let started = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("snaked.sock");
    let log = dir.path().join("snaked.log");
    // A generous feedback timeout: a loaded machine must not starve libhebi's feedback
    // thread into a hold while the stream runs (the default is 50 ms).
    let rest = format!(
        "[failsafe]\nfeedback_timeout_s = 0.2\n[control]\nsocket = \"{}\"\n",
        sock.display()
    );
    let text = config(&libhebi(), &format!("imitation = {MODULES}"), &rest);
    let cfg = write_config(dir.path(), "snaked.toml", &text);
    let log_file = std::fs::File::create(&log).unwrap();
    let mut d = Proc::spawn_with(
        "snaked",
        &exe("snaked"),
        &[
            "--config".into(),
            cfg.display().to_string(),
            "--start".into(),
            "run".into(),
        ],
        |cmd| {
            cmd.env("RUST_LOG", "info")
                .env_remove("SNAKED_LIBHEBI")
                .stderr(log_file);
        },
    );
    let mut c = Client::connect(&sock, WAIT);
    let s = c.wait_status(WAIT, "running", |s| s["mode"] == "running");

    // The bus and the group.
    let info = &s["daemon"];
    assert_eq!(info["bus"], "hebi", "{s}");
    assert_eq!(info["module_count"], MODULES, "{s}");
    assert_eq!(s["modules"], MODULES, "{s}");
    let names: Vec<&str> = info["module_names"]
        .as_array()
        .expect("module names")
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let imitation: Vec<String> = (0..MODULES).map(|i| format!("imitation{i}")).collect();
    assert_eq!(names, imitation, "the imitation's modules, head first");
    // No accelerometer: no gravity, no pose estimate.
    assert_eq!(s["body"]["valid"], false, "{s}");

    loop_runs(&mut c);

    // A gait switch and back, each acknowledged and shown.
    let first = s["gait"].as_str().unwrap().to_owned();
    assert_ne!(
        first, "slithering",
        "the test switches away from the initial gait"
    );
    switch_gait(&mut c, &sock, "slithering");
    compliant_slithering_drives_open_loop(&mut c, &sock);
    switch_gait(&mut c, &sock, &first);
    // The gait's own controller drives again; slithering keeps the one installed.
    c.wait_status(WAIT, "the first gait's controller engaged", |s| {
        s["gait"] == first.as_str()
            && s["controller"]["controller"] == "open_loop"
            && s["controller"]["state"] == "engaged"
    });
    let got = c.call("controller.get", json!({"gait": "slithering"}));
    assert_eq!(
        got["controller"]["controller"], "compliant_slithering",
        "{got}"
    );
    let stats = c.call("stats", json!({}));
    assert_eq!(stats["requests_refused"], 0, "{stats}");
    assert_eq!(stats["loop"]["bus_errors"], 0, "{stats}");

    // SIGTERM: exit 0 after the safe stop.
    d.signal(libc::SIGTERM);
    let status = d.wait(WAIT);
    let log = std::fs::read_to_string(&log).unwrap();
    assert!(
        status.success(),
        "snaked exits 0 on SIGTERM: {status:?}\n{log}"
    );
    assert!(!sock.exists(), "the socket file is removed");
    assert!(log.contains("libhebi loaded"), "{log}");
    assert!(log.contains("stopped safely"), "{log}");
    assert!(
        !log.contains("FeedbackTimeout") && !log.contains(" ERROR "),
        "no failsafe fault, no error: {log}"
    );
    eprintln!("the imitation run took {:?}", started.elapsed());
}

/// The loop turns through libhebi: cycles grow, feedback comes in and commands go out,
/// every module's torque reads 0 and its position echoes its set-point.
fn loop_runs(c: &mut Client) {
    let a = c.call("stats", json!({}));
    std::thread::sleep(Duration::from_millis(300));
    let b = c.call("stats", json!({}));
    let at = |s: &Value, path: &[&str]| -> u64 {
        let v = path.iter().fold(s, |v, k| &v[k]);
        v.as_u64()
            .unwrap_or_else(|| panic!("stats.{}: {s}", path.join(".")))
    };
    assert!(at(&b, &["cycles"]) > at(&a, &["cycles"]), "{a}\n{b}");
    for k in ["feedback_received", "commands_sent"] {
        assert!(
            at(&b, &["bus", k]) > at(&a, &["bus", k]),
            "bus.{k}: {a}\n{b}"
        );
    }
    assert!(
        at(&b, &["bus", "feedback_received"]) >= MODULES as u64,
        "{b}"
    );
    assert_eq!(at(&b, &["bus", "send_errors"]), 0, "{b}");
    assert_eq!(at(&b, &["bus", "feedback_lost"]), 0, "{b}");
    assert!(at(&b, &["bus", "detail", "group_feedbacks"]) > 0, "{b}");
    assert!(at(&b, &["loop", "bus_io", "count"]) > 0, "{b}");
    assert_eq!(at(&b, &["loop", "bus_errors"]), 0, "{b}");

    let s = c.call("status", json!({}));
    assert_eq!(s["mode"], "running", "no failsafe fault: {s}");
    assert_eq!(s["reason"], "startup", "{s}");
    let torques = s["joints"]["torque_nm"].as_array().unwrap();
    assert_eq!(torques.len(), MODULES, "{s}");
    assert!(
        torques.iter().all(|t| t == 0.0),
        "the imitation's torque: {s}"
    );
    assert!(
        s["joints"]["max_tracking_error_rad"].as_f64().unwrap() < 0.1,
        "the imitation echoes the set-points: {s}"
    );
}

/// `gait.set` to `gait`, acknowledged, then shown by `status` (blend done) and telemetry.
fn switch_gait(c: &mut Client, sock: &Path, gait: &str) {
    let ack = c.call("gait.set", json!({"gait": gait}));
    assert_eq!(ack["gait"], gait, "{ack}");
    c.wait_status(WAIT, &format!("blended into {gait}"), |s| {
        s["gait"] == gait && s["blend_progress"] == 1.0 && s["mode"] == "running"
    });
    let t = telemetry_until(sock, gait, |t| t["gait"] == gait);
    let joints = t["joints"].as_array().unwrap();
    assert_eq!(joints.len(), MODULES, "{t}");
    for j in joints {
        assert_eq!(j["torque_nm"], 0.0, "{t}");
        let (p, sp) = (j["position_rad"].as_f64(), j["setpoint_rad"].as_f64());
        assert!((p.unwrap() - sp.unwrap()).abs() < 0.1, "echoed: {j}");
    }
    assert!(
        joints
            .iter()
            .any(|j| j["velocity_rad_s"].as_f64().unwrap().abs() > 1e-3),
        "the gait moves the joints: {t}"
    );
}

/// A compliant slithering controller, chosen over the socket, takes over and drives; with
/// no torque it feels no force, its shape stays the gait's nominal one (open loop).
fn compliant_slithering_drives_open_loop(c: &mut Client, sock: &Path) {
    let ack = c.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "compliant_slithering"}),
    );
    assert_eq!(ack["gait"], "slithering", "{ack}");
    assert_eq!(
        ack["controller"]["controller"], "compliant_slithering",
        "{ack}"
    );
    assert_eq!(ack["controller"]["preset"], "a_ws_omega", "{ack}");
    let s = c.wait_status(WAIT, "compliant slithering drives", |s| {
        s["gait"] == "slithering"
            && s["controller"]["controller"] == "compliant_slithering"
            && s["controller"]["state"] == "engaged"
    });
    assert_eq!(s["mode"], "running", "{s}");
    // Let it drive a while, then read what it made of the imitation's feedback.
    std::thread::sleep(Duration::from_millis(500));
    let s = c.call("status", json!({}));
    let ctl = &s["controller"];
    assert_eq!(ctl["controller"], "compliant_slithering", "{s}");
    assert_eq!(ctl["state"], "engaged", "{s}");
    let signal = |k: &str| {
        ctl["signals"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("signal {k}: {ctl}"))
    };
    for k in [
        "force_amplitude_peak",
        "force_spatial_freq_peak",
        "force_phase_peak",
        "phase_lag_rad",
    ] {
        assert_eq!(signal(k), 0.0, "{k}: no torque, no force: {ctl}");
    }
    let gaits = c.call("gait.list", json!({}));
    let nominal = gaits["gaits"]
        .as_array()
        .unwrap()
        .iter()
        .find(|g| g["name"] == "slithering")
        .expect("slithering listed")["params"]["amplitude_lat_rad"]
        .as_f64()
        .unwrap();
    assert!(
        (signal("amplitude_mean_rad") - nominal).abs() < 1e-9,
        "the amplitude stays nominal ({nominal}): {ctl}"
    );
    let t = telemetry_until(sock, "the controller in telemetry", |t| {
        t["controller"]["controller"] == "compliant_slithering"
    });
    assert_eq!(t["controller"]["state"], "engaged", "{t}");
}
