//! `snaked --emulated --world ... --record FILE` as an operator runs it: a few seconds
//! of the physics world at 1 kHz, a gait and a controller change, SIGTERM, and the file
//! finished properly: read back by the `mcap` crate and, where it is installed, by
//! Python's `mcap` package (an independent reader).
mod common;

use std::collections::BTreeMap;
use std::process::Command;
use std::time::Duration;

use common::{Client, Proc, exe};
use serde_json::{Value, json};

/// Per-topic message counts and the JSON messages of `topics`.
fn read(path: &std::path::Path, topics: &[&str]) -> (BTreeMap<String, u64>, Vec<(String, Value)>) {
    let bytes = std::fs::read(path).expect("the recording exists");
    let mut counts = BTreeMap::new();
    let mut kept = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let m = m.expect("a well-formed message");
        *counts.entry(m.channel.topic.clone()).or_insert(0) += 1;
        if topics.contains(&m.channel.topic.as_str()) {
            let v: Value = serde_json::from_slice(&m.data).expect("JSON");
            kept.push((m.channel.topic.clone(), v));
        }
    }
    (counts, kept)
}

#[test]
fn the_daemon_records_a_run_and_finishes_the_file_on_sigterm() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let file = dir.path().join("run.mcap");
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
            "--record".into(),
            file.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(Duration::from_secs(30), "engaged", |s| {
        s["controller"]["state"] == "engaged"
    });
    c.call("gait.set", json!({"gait": "slithering"}));
    c.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega"}),
    );
    c.wait_status(
        Duration::from_secs(60),
        "compliant slithering drives",
        |s| s["controller"]["preset"] == "a_ws_omega" && s["controller"]["state"] == "engaged",
    );
    let stats = c.call("stats", json!({}));
    let dropped_live = stats["record_dropped"].as_u64().expect("reported in stats");
    d.signal(libc::SIGTERM);
    assert!(d.wait(Duration::from_secs(30)).success(), "exit 0");

    let (counts, msgs) = read(
        &file,
        &[
            "/joints",
            "/events",
            "/controller/signals",
            "/body/estimate",
        ],
    );
    let cycles: Vec<u64> = msgs
        .iter()
        .filter(|(t, _)| t == "/joints")
        .map(|(_, v)| v["cycle"].as_u64().expect("cycle"))
        .collect();
    assert!(cycles.len() > 2000, "{counts:?}");
    for topic in ["/commands", "/imu", "/body/estimate", "/controller/signals"] {
        assert_eq!(counts[topic], cycles.len() as u64, "{topic}: {counts:?}");
    }
    // Cycles come in order; a gap is a skipped period (an overrun of this debug build
    // on a shared machine) or a record the full ring dropped, and `stats` counts both.
    assert!(cycles.windows(2).all(|w| w[1] > w[0]), "in order");
    let gaps: u64 = cycles.windows(2).map(|w| w[1] - w[0] - 1).sum();
    println!(
        "{} cycles recorded, {gaps} missing (dropped by the ring before the stop: {dropped_live})",
        cycles.len()
    );
    // The world and the body in 3-D, the ground truth as frames.
    assert_eq!(counts["/scene/world"], 1, "{counts:?}");
    assert!(
        counts["/tf"] > 50 && counts["/scene/body"] > 50,
        "{counts:?}"
    );
    assert!(counts["/stats"] >= 2, "once a second: {counts:?}");
    assert!(counts["/controller/windows"] > 0, "the compliant windows");
    assert!(
        counts["/controller/info"] >= 2,
        "open loop, then a_ws_omega"
    );
    // Events: the mode changes, both requests, the takeovers.
    let events: Vec<&Value> = msgs
        .iter()
        .filter(|(t, _)| t == "/events")
        .map(|(_, v)| v)
        .collect();
    let text = serde_json::to_string(&events).unwrap();
    for needle in [
        "running",
        "set_gait",
        "set_controller",
        "engaged",
        "shutdown",
    ] {
        assert!(text.contains(needle), "{needle} in {text}");
    }
    let named = msgs
        .iter()
        .any(|(t, v)| t == "/controller/signals" && v["signals"]["phase_lag_rad"].is_number());
    assert!(named, "compliant slithering's signals by name");
    // The pose estimate ran in the loop: a valid body frame with a finite heading.
    let estimated = msgs.iter().rfind(|(t, _)| t == "/body/estimate");
    let (_, body) = estimated.expect("body estimates recorded");
    assert_eq!(body["valid"], true, "{body}");
    assert!(
        body["heading_rad"].as_f64().is_some_and(f64::is_finite),
        "{body}"
    );
    assert_eq!(body["orientation_wxyz"].as_array().map(Vec::len), Some(4));

    // The independent reader, where it is installed (.ci/run installs it).
    let python = Command::new("python3")
        .args(["-c", "import mcap.reader"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !python {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have python3 mcap"
        );
        println!("skipped the Python reader: pip install mcap");
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/mcap-summary.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let joints_line = text
        .lines()
        .find(|l| l.trim_start().starts_with("/joints "))
        .unwrap_or_else(|| panic!("{text}"));
    let n: u64 = joints_line
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(n, cycles.len() as u64, "{text}");
    assert!(text.contains("metadata snaked.status"), "{text}");
}
