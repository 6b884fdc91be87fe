//! Hardware-in-loop failsafe, in real time: a module of `snake-emu` falls silent;
//! `snaked` holds, then goes limp, reports why, and the emulator sees it.
mod common;

use std::time::Duration;

use common::{Client, Proc, Recording, exe, free_udp_ports};
use serde_json::json;

const N: usize = 8;
const SILENT: usize = 3;
const SILENCE_AT_S: f64 = 5.0;

#[test]
fn a_silent_module_makes_the_daemon_hold_then_go_limp() {
    let dir = tempfile::tempdir().unwrap();
    let base = free_udp_ports(N as u16);
    let rec_path = dir.path().join("truth.csv");
    let sock = dir.path().join("snaked.sock");
    let mut emu = Proc::spawn(
        "snake-emu",
        &exe("snake-emu"),
        &[
            "--modules".into(),
            N.to_string(),
            "--base-port".into(),
            base.to_string(),
            "--silence".into(),
            format!("{SILENT}@{SILENCE_AT_S}"),
            "--record".into(),
            rec_path.display().to_string(),
        ],
    );
    let cfg_path = dir.path().join("snaked.toml");
    // Timeouts generous enough for a loaded 2-core CI machine; the logic is the same.
    std::fs::write(
        &cfg_path,
        format!(
            r#"
[network]
targets = ["127.0.0.1:{base}-{last}"]
expected_modules = {N}
discovery_timeout_s = 5.0
command_lifetime_s = 0.25
[failsafe]
feedback_timeout_s = 0.2
limp_after_s = 1.0
[gait]
initial = "rolling"
start = "run"
[control]
socket = "{sock}"
"#,
            last = base + N as u16 - 1,
            sock = sock.display()
        ),
    )
    .unwrap();
    let mut daemon = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &["--config".into(), cfg_path.display().to_string()],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(Duration::from_secs(30), "running", |s| {
        s["mode"] == "running"
    });

    let held = c.wait_status(Duration::from_secs(30), "hold", |s| s["mode"] != "running");
    assert_eq!(held["mode"], "hold", "a silent module first holds: {held}");
    assert_eq!(held["reason"], "feedback_timeout");
    let limp = c.wait_status(Duration::from_secs(30), "limp", |s| s["mode"] == "limp");
    assert_eq!(limp["reason"], "feedback_timeout");
    assert!(
        limp["joints"]["max_feedback_age_s"].as_f64().unwrap() >= 1.0,
        "{limp}"
    );
    let stats = c.call("stats", json!({}));
    assert!(
        stats["loop"]["late_feedback"].as_u64().unwrap() > 0,
        "{stats}"
    );
    // Arming is refused while the module stays silent.
    let arm = c.call_raw("arm", json!({}));
    assert!(
        arm.get("error").is_some(),
        "arm refused while feedback is stale: {arm}"
    );

    daemon.signal(libc::SIGINT);
    assert!(daemon.wait(Duration::from_secs(20)).success());
    emu.signal(libc::SIGTERM);
    assert!(emu.wait(Duration::from_secs(20)).success());

    // At the emulator: the others were driven before the silence and limp by the end.
    let rec = Recording::load(&rec_path, N);
    let before = rec.span(SILENCE_AT_S - 1.0, SILENCE_AT_S);
    assert!(
        before.clone().all(|k| rec.cmd[0][k].is_finite()),
        "driven before the silence"
    );
    let last = rec.t.len() - 1;
    for i in (0..N).filter(|&i| i != SILENT) {
        assert!(rec.cmd[i][last].is_nan(), "module {i} limp at the end");
    }
}
