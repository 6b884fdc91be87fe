//! Issue 45: the operator's commonest actions keep the compliant controller driving.
//! Among the 40-peg board, compliant slithering (`a_ws_omega`) engaged, the Teleop
//! panel's speed and steering change every 0.5 s for 20 s, then the Parameters panel
//! changes a gain every second for 20 s: the controller drives ≥ 95 % of the cycles
//! (it follows each change and takes each configuration in place), no set-point jumps,
//! the set-point guard never acts.
use super::daemon_in;
use crate::support::foxglove_ws::{FoxgloveClient, twist};

use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// The joints' speed limit, rad/s (what a jump would exceed).
const MAX_SPEED_RAD_S: f64 = 3.46 * 1.001;

/// The loop time now, s.
fn loop_time(s: &Value) -> f64 {
    s["t_s"].as_f64().expect("t_s")
}

/// Of the cycles recorded in `[from, to]` (loop time, s): how many, how many the
/// controller drove, and the fastest any commanded position moved between two cycles
/// (rad/s: a loaded machine may skip periods, so a step spans their time).
fn window(signals: &[Value], commands: &[Value], from: f64, to: f64) -> (usize, usize, f64) {
    let within = |m: &Value| {
        let t = m["t_ns"].as_f64().unwrap() * 1e-9;
        (from..=to).contains(&t)
    };
    let cycles: Vec<&Value> = signals.iter().filter(|m| within(m)).collect();
    let driven = cycles.iter().filter(|m| m["engaged"] == true).count();
    let mut step = 0.0f64;
    let mut last: Option<(f64, Vec<f64>)> = None;
    for m in commands.iter().filter(|m| within(m)) {
        let t = m["t_ns"].as_f64().unwrap() * 1e-9;
        let now: Vec<f64> = m["position_rad"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::NAN))
            .collect();
        if let Some((t0, prev)) = &last {
            for (a, b) in now.iter().zip(prev) {
                step = step.max((a - b).abs() / (t - t0));
            }
        }
        last = Some((t, now));
    }
    (cycles.len(), driven, step)
}

#[test]
fn teleop_and_gain_changes_keep_compliant_slithering_driving_among_pegs() {
    let mut d = daemon_in("peg-board-40.toml", "", |_| {});
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega"}),
    )
    .expect("controller.set");
    fx.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    // Teleop from the start (the dead-man stops a gait whose twists stop).
    fx.advertise(1, "/cmd_vel");
    let start = Instant::now();
    let before = loop {
        fx.publish(1, &twist(1.0, 0.0));
        fx.drain(Duration::from_millis(100));
        let s = d.sock.call("status", json!({}));
        if s["controller"]["preset"] == "a_ws_omega" && s["controller"]["state"] == "engaged" {
            break s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "never engaged: {s}"
        );
    };

    // 20 s of teleop: a new speed and steering every 0.5 s, twists at 10 Hz.
    let speeds = [0.6, 1.2, 0.8, 1.5, 1.0];
    let turns = [0.0, 0.5, -0.5, 0.3, -0.2, 0.6, 0.0];
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(20) {
        let k = (start.elapsed().as_secs_f64() / 0.5) as usize;
        fx.publish(1, &twist(speeds[k % speeds.len()], turns[k % turns.len()]));
        fx.drain(Duration::from_millis(100));
    }
    let teleop_end = d.sock.call("status", json!({}));
    let p = d.sock.call("params.get", json!({"gait": "slithering"}));
    let last = speeds[39 % speeds.len()];
    assert!(
        (p["params"]["temporal_freq_rad_s"].as_f64().unwrap() - last).abs() < 1e-9,
        "the last speed was set: {p}"
    );

    // 20 s of gain edits from the Parameters panel, one a second (teleop holds a speed).
    let start = Instant::now();
    let mut edits = 0;
    while start.elapsed() < Duration::from_secs(20) {
        let damping = if edits % 2 == 0 { 8.0 } else { 6.0 };
        let now =
            fx.set_parameters(&[("controller.config.amplitude.gains.damping", json!(damping))]);
        assert_eq!(
            now["controller.config.amplitude.gains.damping"],
            json!(damping),
            "edit {edits} taken"
        );
        edits += 1;
        while start.elapsed() < Duration::from_secs(edits) {
            fx.publish(1, &twist(1.0, 0.0));
            fx.drain(Duration::from_millis(100));
        }
    }
    let after = d.sock.call("status", json!({}));
    assert_eq!(
        after["controller"]["takeovers"], before["controller"]["takeovers"],
        "never handed back: {after}"
    );
    assert_eq!(after["guard"], before["guard"], "the guard never acted");
    let (t0, t1, t2) = (
        loop_time(&before),
        loop_time(&teleop_end),
        loop_time(&after),
    );
    let [signals, commands, operator]: [Vec<Value>; 3] = d
        .stop_with(&["/controller/signals", "/commands", "/operator"])
        .try_into()
        .unwrap();
    let sets = operator
        .iter()
        .filter(|e| e["action"] == "params.set" && e["ok"] == true)
        .count();
    assert!(sets >= 38, "teleop set the speed every 0.5 s: {sets}");
    for (what, from, to) in [("teleop", t0, t1), ("gain edits", t1, t2)] {
        let (cycles, driven, step) = window(&signals, &commands, from, to);
        let share = driven as f64 / cycles as f64;
        println!(
            "{what}: {cycles} cycles, the controller drove {:.1} %, fastest set-point \
             {step:.3} rad/s",
            100.0 * share
        );
        assert!(cycles > 15_000, "{what}: {cycles} cycles recorded");
        assert!(share >= 0.95, "{what}: the controller drove {share}");
        assert!(
            step <= MAX_SPEED_RAD_S,
            "{what}: a set-point jumped ({step} rad/s)"
        );
    }
}
