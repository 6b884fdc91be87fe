//! Issue 44's probes of the station, as tests: the dead-man stops the joints within its
//! own time whatever the blend time; one operator drives at a time; an e-stop freezes
//! what runs after `arm`.
use super::{daemon, daemon_with, slithering_speed};
use crate::support::foxglove_ws::{FoxgloveClient, twist};
use crate::support::rig::wait_log;

use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// The largest joint speed of the commanded set-points over `window` cycles ending at
/// each `/commands` message, rad/s, with its loop time, s.
fn joint_speeds(commands: &[Value], window: usize) -> Vec<(f64, f64)> {
    let at = |m: &Value| -> (f64, Vec<f64>) {
        let t = m["t_ns"].as_f64().expect("t_ns") * 1e-9;
        let p = m["position_rad"]
            .as_array()
            .expect("positions")
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::NAN))
            .collect();
        (t, p)
    };
    commands
        .windows(window + 1)
        .map(|w| {
            let ((t0, p0), (t1, p1)) = (at(&w[0]), at(&w[window]));
            let moved = p0
                .iter()
                .zip(&p1)
                .map(|(a, b)| (a - b).abs())
                .filter(|d| d.is_finite())
                .fold(0.0, f64::max);
            (t1, moved / (t1 - t0))
        })
        .collect()
}

#[test]
fn the_dead_man_stops_the_joints_within_its_own_time_whatever_the_blend_time() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    d.sock
        .wait_status(Duration::from_secs(20), "slithering", |s| {
            s["gait"] == "slithering" && s["blend_progress"] == 1.0
        });
    // The slowest blend there is: a speed change blends in over 30 s.
    fx.call("params.set", json!({"blend_time_s": 30.0}))
        .expect("blend time");
    fx.advertise(1, "/cmd_vel");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        fx.publish(1, &twist(1.5, 0.0));
        fx.drain(Duration::from_millis(100));
    }
    // The client dies: no more twists.
    drop(fx);
    d.sock
        .wait_status(Duration::from_secs(10), "the dead-man's hold", |s| {
            s["mode"] == "hold"
        });
    let [events, commands]: [Vec<Value>; 2] =
        d.stop_with(&["/events", "/commands"]).try_into().unwrap();
    let stop = events
        .iter()
        .find(|e| e["request"] == "stop_gait" && e["applied"] == true)
        .unwrap_or_else(|| panic!("the dead-man's controlled stop: {events:?}"));
    let t_stop = stop["t_ns"].as_f64().unwrap() * 1e-9;
    let within = stop["args"]["within_s"].as_f64().unwrap();
    let speeds = joint_speeds(&commands, 20);
    eprintln!("joint speed (max over joints, commanded, 20 ms windows) after the dead-man's stop:");
    for (t, v) in speeds
        .iter()
        .filter(|(t, _)| *t >= t_stop - 0.1 && *t <= t_stop + 1.5)
        .step_by(50)
    {
        eprintln!("  {:+.2} s  {v:.3} rad/s", t - t_stop);
    }
    let before = speeds
        .iter()
        .filter(|(t, _)| (t_stop - 0.3..t_stop).contains(t))
        .map(|s| s.1)
        .fold(0.0, f64::max);
    assert!(before > 0.3, "moving before the stop: {before} rad/s");
    let after: Vec<&(f64, f64)> = speeds
        .iter()
        .filter(|(t, _)| *t >= t_stop + within + 0.025)
        .collect();
    assert!(after.len() > 500, "the recording goes on after the stop");
    let moving: Vec<_> = after.iter().filter(|(_, v)| *v > 1e-6).collect();
    assert!(
        moving.is_empty(),
        "at rest {within} s after the stop, whatever the blend time: {:?}",
        &moving[..moving.len().min(5)]
    );
}

#[test]
fn one_operator_drives_at_a_time_and_another_takes_over_only_explicitly() {
    let mut d = daemon("");
    let mut a = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    let mut b = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    a.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    a.advertise(1, "/cmd_vel");
    b.advertise(1, "/cmd_vel");
    // Both twist, opposite ways: the first to drive keeps it.
    let mut speeds = Vec::new();
    for _ in 0..20 {
        a.publish(1, &twist(1.0, 0.0));
        b.publish(1, &twist(-1.0, 0.0));
        a.drain(Duration::from_millis(50));
        b.drain(Duration::from_millis(50));
        speeds.push(slithering_speed(&mut d.sock));
    }
    assert!(
        speeds[5..].iter().all(|s| (*s - 1.0).abs() < 1e-9),
        "the speed never flips: {speeds:?}"
    );
    assert!(
        b.wait_status_message("is driving", Duration::from_secs(2)),
        "the second is told who drives: {:?}",
        b.statuses
    );
    // Its services and the socket meet the same rule.
    let e = b
        .call("gait.set", json!({"gait": "rolling"}))
        .expect_err("refused");
    assert!(
        e.contains("foxglove client") && e.contains("take_over"),
        "{e}"
    );
    let refused = d.once().call_raw(
        "params.set",
        json!({"gait": "slithering", "temporal_freq_rad_s": 0.2}),
    );
    assert_eq!(refused["error"]["code"], -32006, "{refused}");
    let status = d.sock.call("status", json!({}));
    assert!(
        status["driver"]["client"]
            .as_str()
            .is_some_and(|c| c.starts_with("foxglove client")),
        "{status}"
    );
    // B keeps twisting while A's twists stop: B's twists do not feed A's dead-man, which
    // stops the gait; the drive is then free and B's next twists drive.
    let mut stopped = false;
    let mut b_drives = false;
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(6) && !b_drives {
        b.publish(1, &twist(-1.0, 0.0));
        b.drain(Duration::from_millis(100));
        let s = d.sock.call("status", json!({}));
        stopped |= s["motion"]["state"] == "stopped" || s["motion"]["state"] == "stopping";
        b_drives = slithering_speed(&mut d.sock) < -0.99;
    }
    assert!(stopped, "A's dead-man fired though B kept twisting");
    assert!(b_drives, "B drives once A stopped");
    // A takes over explicitly, and B is refused again.
    a.call("take_over", json!({})).expect("take_over");
    let before = b.statuses.len();
    for _ in 0..5 {
        b.publish(1, &twist(-0.5, 0.0));
        b.drain(Duration::from_millis(50));
    }
    assert!(b.statuses.len() > before, "B is told it no longer drives");
    assert!(
        (slithering_speed(&mut d.sock) + 1.0).abs() < 1e-9,
        "B's twists after the take-over changed nothing"
    );
    let events = d.stop();
    assert!(
        events
            .iter()
            .any(|e| e["action"] == "take_over" && e["ok"] == true),
        "{events:?}"
    );
}

#[test]
fn an_estop_refuses_changes_until_arm_and_arm_resumes_what_ran_before() {
    let logs = tempfile::tempdir().unwrap();
    let log = logs.path().join("snaked.log");
    let mut d = daemon_with("", |c| {
        c.stderr(std::fs::File::create(&log).expect("log file"));
    });
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    let speed = slithering_speed(&mut d.sock);
    fx.call("estop", json!({})).expect("estop");
    d.sock
        .wait_status(Duration::from_secs(5), "e-stopped", |s| {
            s["mode"] == "e_stop"
        });
    for (method, params) in [
        (
            "params.set",
            json!({"gait": "slithering", "temporal_freq_rad_s": 0.3}),
        ),
        (
            "controller.set",
            json!({"gait": "slithering", "controller": "a_ws_omega"}),
        ),
        (
            "controller.heading",
            json!({"gait": "slithering", "heading_rad": 1.0}),
        ),
    ] {
        let e = fx.call(method, params).expect_err(method);
        assert!(e.contains("e-stop"), "{method}: {e}");
    }
    fx.advertise(1, "/cmd_vel");
    for _ in 0..5 {
        fx.publish(1, &twist(1.9, 0.0));
        fx.drain(Duration::from_millis(50));
    }
    assert!(
        fx.wait_status_message("e-stop", Duration::from_secs(2)),
        "teleop is told: {:?}",
        fx.statuses
    );
    // Refused operator requests are logged, naming the client and why.
    wait_log(
        &log,
        &[
            "station: foxglove client 1's params.set refused",
            "e-stop is latched",
            "teleop gait.resume refused",
        ],
    );
    fx.call("arm", json!({})).expect("arm");
    d.sock.wait_status(Duration::from_secs(10), "running", |s| {
        s["mode"] == "running"
    });
    assert_eq!(
        slithering_speed(&mut d.sock),
        speed,
        "what ran before the stop"
    );
    let c = d.sock.call("controller.get", json!({"gait": "slithering"}));
    assert_ne!(c["controller"]["preset"], "a_ws_omega", "{c}");
}
