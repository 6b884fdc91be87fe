//! `snaked` as an operator starts it: bad configurations, no modules, and the
//! embedded emulator from start to safe stop.
use crate::support::rig;

use std::os::unix::fs::PermissionsExt;
use std::process::Command;
use std::time::Duration;

use rig::{Client, Proc, exe};
use serde_json::json;

fn run_with_config(text: &str) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(exe("snaked"))
        .args(["--config", path.to_str().unwrap()])
        .env("RUST_LOG", "off")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_bad_configuration_is_named_and_exits_non_zero() {
    let (code, err) = run_with_config("[loop]\nrate_hz = 1000\nratee = 5\n");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.toml") && err.contains("ratee"), "{err}");
    let (code, err) = run_with_config("[failsafe]\nlimp_after_s = -1.0\n");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("failsafe.limp_after_s"), "{err}");
    let (code, err) = run_with_config("[gait.params.slithering]\namplitude_lat_rad = 9.0\n");
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("slithering"), "{err}");
    // A compliant spatial frequency must comply around the nominal one.
    let (code, err) = run_with_config(
        "[gait.controllers.slithering]\ncontroller = \"a_ws\"\n[gait.params.slithering]\nspatial_freq_rad = 15.0\n",
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("gait.controllers.slithering") && err.contains("spatial_freq_rad"),
        "{err}"
    );
}

/// `--check-config` finds what would stop the daemon later, exit 2, file and key named.
#[test]
fn check_config_finds_cross_field_and_named_file_errors() {
    let dir = tempfile::tempdir().unwrap();
    let open_key = dir.path().join("open.key");
    std::fs::write(&open_key, "ab".repeat(32)).unwrap();
    std::fs::set_permissions(&open_key, std::fs::Permissions::from_mode(0o644)).unwrap();
    let missing_key = format!(
        "[network]\nkey_file = \"{}/nope.key\"\n",
        dir.path().display()
    );
    let readable_key = format!("[network]\nkey_file = \"{}\"\n", open_key.display());
    // Issue 25: the daemon refuses a token file every user can read when it starts.
    let readable_token = format!(
        "[control]\ntcp_port = 7878\ntcp_token_file = \"{}\"\n",
        open_key.display()
    );
    for (text, key) in [
        (missing_key.as_str(), "network.key_file"),
        (readable_key.as_str(), "network.key_file"),
        (readable_token.as_str(), "control.tcp_token_file"),
        ("[failsafe]\nlimp_after_s = 0.0\n", "failsafe.limp_after_s"),
        (
            "[network]\nfeedback_rate_hz = 100.0\ncommand_lifetime_s = 0.002\n",
            "network.command_lifetime_s",
        ),
        (
            "[control]\nchannel_capacity = 2\n",
            "control.channel_capacity",
        ),
        (
            "[network]\ntargets = [\"127.0.0.1:9-1\"]\n",
            "network.targets",
        ),
        ("[emulator]\nworld = \"/nope.toml\"\n", "emulator.world"),
        (
            "[loop]\nrate_hz = 1000.0\nbusy_wait_s = 0.0005\n",
            "loop.busy_wait_s",
        ),
        (
            "[loop]\ncpu_dma_latency_s = -1.0\n",
            "loop.cpu_dma_latency_s",
        ),
        (
            "[gait.params.sidewinding]\nhelix_radius_m = 0.1\n",
            "gait.params.sidewinding",
        ),
    ] {
        let path = dir.path().join("c.toml");
        std::fs::write(&path, text).unwrap();
        let out = Command::new(exe("snaked"))
            .args(["--check-config", "--config", path.to_str().unwrap()])
            .env("RUST_LOG", "off")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{text}: {err}");
        assert!(err.contains("c.toml") && err.contains(key), "{text}: {err}");
    }
}

/// The command line's overrides are checked too: a TCP port without a token file would
/// stop the daemon, so `--check-config` refuses it.
#[test]
fn check_config_checks_the_command_line_s_overrides() {
    let out = Command::new(exe("snaked"))
        .args(["--check-config", "--tcp-port", "7878"])
        .env("RUST_LOG", "off")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("control.tcp_token_file"), "{err}");
}

#[test]
fn no_modules_on_the_network_is_a_clear_failure() {
    let port = rig::free_udp_ports(2);
    let (code, err) = run_with_config(&format!(
        "[network]\ntargets = [\"127.0.0.1:{port}-{}\"]\ndiscovery_timeout_s = 0.3\n[control]\nsocket = \"\"\n",
        port + 1
    ));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("discovery"), "{err}");
    // What was looked for, where, and what answered (nothing): no empty list.
    assert!(
        err.contains("looking for") && err.contains("127.0.0.1:"),
        "{err}"
    );
    let (code, err) = run_with_config(&format!(
        "[network]\ntargets = [\"127.0.0.1:{port}-{}\"]\nexpected_modules = 2\n\
         discovery_timeout_s = 0.3\n[control]\nsocket = \"\"\n",
        port + 1
    ));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("none answered"), "{err}");
    assert!(!err.trim_end().ends_with(':'), "{err}");
}

/// SIGTERM or SIGINT while discovery waits (here up to 30 s for modules that never
/// answer) stops the daemon at once, exit 0.
#[test]
fn a_signal_during_discovery_stops_it_at_once() {
    let port = rig::free_udp_ports(2);
    for sig in [libc::SIGTERM, libc::SIGINT] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.toml");
        std::fs::write(
            &path,
            format!(
                "[network]\ntargets = [\"127.0.0.1:{port}-{}\"]\ndiscovery_timeout_s = 30.0\n\
                 [control]\nsocket = \"\"\n",
                port + 1
            ),
        )
        .unwrap();
        let mut d = Proc::spawn(
            "snaked",
            &exe("snaked"),
            &["--config".into(), path.display().to_string()],
        );
        std::thread::sleep(Duration::from_millis(500));
        let sent = std::time::Instant::now();
        d.signal(sig);
        let status = d.wait(Duration::from_secs(10));
        println!("signal {sig}: exited {:?} after it", sent.elapsed());
        assert!(status.success(), "exit 0 on signal {sig}: {status:?}");
    }
}

#[test]
fn emulated_daemon_runs_switches_and_stops_safely() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let mut d = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--socket".into(),
            sock.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(20));
    let s = c.wait_status(Duration::from_secs(20), "running", |s| {
        s["mode"] == "running"
    });
    assert_eq!(s["gait"], "sidewinding");
    assert_eq!(s["modules"], 18);
    c.call("gait.set", json!({"gait": "rolling"}));
    c.wait_status(Duration::from_secs(20), "blend done", |s| {
        s["gait"] == "rolling" && s["blend_progress"] == 1.0
    });
    let stats = c.call("stats", json!({}));
    assert!(stats["cycles"].as_u64().unwrap() > 1000, "{stats}");
    assert_eq!(stats["loop"]["wakeup_latency"]["count"], stats["cycles"]);
    let periods = stats["loop"]["period_error"]["count"].as_u64().unwrap();
    assert_eq!(periods + 1, stats["cycles"].as_u64().unwrap(), "{stats}");
    // snakectl talks to the same socket.
    let out = Command::new(exe("snakectl"))
        .args(["--socket", sock.to_str().unwrap(), "--json", "status"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["gait"], "rolling");

    d.signal(libc::SIGINT);
    assert!(
        d.wait(Duration::from_secs(20)).success(),
        "exit 0 after the safe stop"
    );
    assert!(!sock.exists(), "socket removed");
}

/// Issue 25: a calibration in flight when the daemon is told to stop is answered with
/// the documented -32002 (shutting down) before the connection closes, not cut off.
#[test]
fn a_calibration_in_flight_at_sigterm_is_refused_not_cut_off() {
    use std::io::{BufRead, BufReader, Write};
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let cfg = dir.path().join("dc.toml");
    std::fs::write(
        &cfg,
        // No shutdown hold: the loop is gone within two cycles, before the calibration
        // polls it again; the server must still answer before it closes.
        "[failsafe]\nshutdown_hold_s = 0.0\n[gait]\ninitial = \"slithering\"\n\
         [gait.controllers.slithering]\ncontroller = \"dc_switching\"\n",
    )
    .unwrap();
    let mut d = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--config".into(),
            cfg.display().to_string(),
            "--socket".into(),
            sock.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(20));
    c.wait_status(Duration::from_secs(20), "the controller driving", |s| {
        s["controller"]["preset"] == "dc_switching" && s["controller"]["state"] == "engaged"
    });
    let mut calib = std::os::unix::net::UnixStream::connect(&sock).unwrap();
    calib
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    writeln!(
        calib,
        r#"{{"id":7,"method":"controller.calibrate","params":{{"seconds":60}}}}"#
    )
    .unwrap();
    c.wait_status(Duration::from_secs(20), "calibrating", |s| {
        s["controller"]["signals"]["calibration"] == 1.0
    });
    d.signal(libc::SIGTERM);
    let mut line = String::new();
    let n = BufReader::new(calib).read_line(&mut line).unwrap();
    assert!(n > 0, "the connection closed without an answer");
    let answer: serde_json::Value = serde_json::from_str(&line).unwrap();
    assert_eq!(answer["id"], 7, "{answer}");
    assert_eq!(answer["error"]["code"], -32002, "{answer}");
    assert!(
        answer["error"]["message"]
            .as_str()
            .unwrap()
            .contains("shutting down"),
        "{answer}"
    );
    assert!(d.wait(Duration::from_secs(20)).success());
}

/// The service manager's view: READY once the loop turns, watchdog pings while it
/// does, STOPPING on the safe stop. A datagram socket stands in for systemd.
#[test]
fn notifies_ready_pings_the_watchdog_and_says_stopping() {
    use std::os::unix::net::UnixDatagram;
    let dir = tempfile::tempdir().unwrap();
    let notify = dir.path().join("notify");
    let listener = UnixDatagram::bind(&notify).unwrap();
    listener
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let sock = dir.path().join("s.sock");
    let child = Command::new(exe("snaked"))
        .args(["--emulated", "--socket", sock.to_str().unwrap()])
        .env("NOTIFY_SOCKET", &notify)
        .env("WATCHDOG_USEC", "200000")
        .env("RUST_LOG", "warn")
        .spawn()
        .unwrap();
    let mut d = Proc {
        name: "snaked",
        child: Some(child),
    };
    let mut seen = String::new();
    let mut buf = [0u8; 512];
    let mut pings = 0;
    while pings < 3 {
        let n = listener.recv(&mut buf).expect("notifications arrive");
        let msg = String::from_utf8_lossy(&buf[..n]).into_owned();
        if msg.contains("WATCHDOG=1") {
            assert!(
                seen.contains("READY=1"),
                "READY comes before the first ping: {seen}"
            );
            pings += 1;
        }
        seen.push_str(&msg);
        seen.push('\n');
    }
    d.signal(libc::SIGTERM);
    assert!(d.wait(Duration::from_secs(20)).success());
    let mut rest = String::new();
    listener
        .set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    while let Ok(n) = listener.recv(&mut buf) {
        rest.push_str(&String::from_utf8_lossy(&buf[..n]));
    }
    assert!(rest.contains("STOPPING=1"), "{rest}");
}

/// `--emulated --world`: the daemon drives the rigid-body physics plant in process.
#[test]
fn emulated_daemon_drives_the_physics_world() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let world = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat.toml");
    let mut d = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--world".into(),
            world.into(),
            "--socket".into(),
            sock.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(20));
    let s = c.wait_status(Duration::from_secs(20), "sidewinding a while", |s| {
        s["mode"] == "running" && s["t_s"].as_f64().unwrap() > 2.5
    });
    // The joints follow the gait on the physics plant, and feel the ground. Under load
    // the worst joint lags its set-point by 0.1-0.45 rad (measured), and one snapshot may
    // catch it mid-bounce on its spring, so judge the median over ten snapshots across a
    // second against half a radian: joints that did not follow would be off by the order
    // of the gait's amplitude (π/4).
    let mut errs: Vec<f64> = (0..10)
        .map(|_| {
            std::thread::sleep(Duration::from_millis(100));
            c.call("status", json!({}))["joints"]["max_tracking_error_rad"]
                .as_f64()
                .unwrap()
        })
        .collect();
    errs.sort_by(f64::total_cmp);
    eprintln!("max tracking error over 10 snapshots: {errs:?}");
    assert!(
        errs[5] < 0.5,
        "median worst tracking error {}: {errs:?}",
        errs[5]
    );
    assert!(
        s["joints"]["max_abs_torque_nm"].as_f64().unwrap() > 0.05,
        "{s}"
    );
    d.signal(libc::SIGTERM);
    assert!(d.wait(Duration::from_secs(20)).success());
}

/// Logs go to stderr without colour codes unless it is a terminal, and in the journal's
/// style (no timestamp of our own) under systemd.
#[test]
fn logs_carry_no_colour_codes_off_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    // A failure after start-up (the configuration's check cannot see it): the socket's
    // directory is writable by every user.
    let open = dir.path().join("open");
    std::fs::create_dir(&open).unwrap();
    std::fs::set_permissions(&open, std::os::unix::fs::PermissionsExt::from_mode(0o777)).unwrap();
    let sock = open.join("s.sock");
    let run = |journal: bool| {
        let mut cmd = Command::new(exe("snaked"));
        cmd.arg("--emulated")
            .args(["--socket", sock.to_str().unwrap()])
            .env("RUST_LOG", "info")
            .env_remove("JOURNAL_STREAM");
        if journal {
            cmd.env("JOURNAL_STREAM", "8:12345");
        }
        let out = cmd.output().unwrap();
        assert_eq!(out.status.code(), Some(1));
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(out.stdout.is_empty(), "logs go to stderr");
        assert!(!stderr.contains('\u{1b}'), "no colour codes: {stderr:?}");
        assert!(stderr.contains("group ready"), "{stderr}");
        assert!(
            stderr.contains("directory") && stderr.contains("writable by every user"),
            "{stderr}"
        );
        stderr
    };
    let plain = run(false);
    assert!(
        plain.lines().next().unwrap().starts_with("20"),
        "timestamped: {plain}"
    );
    let journal = run(true);
    let first = journal.lines().next().unwrap();
    assert!(
        first.trim_start().starts_with("INFO"),
        "no timestamp of ours under systemd: {first}"
    );
}
