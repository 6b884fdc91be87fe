//! Driving from Foxglove: services, teleop, the dead-man, steering by a heading, taking
//! over from the navigator.
use super::{daemon, slithering_speed};
use crate::support::foxglove_ws::{FoxgloveClient, twist};

use std::time::{Duration, Instant};

use serde_json::{Value, json};

#[test]
fn foxglove_drives_the_robot_and_the_dead_man_stops_then_holds_it() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    for s in [
        "gait.set",
        "params.set",
        "controller.set",
        "controller.heading",
        "controller.calibrate",
        "navigate",
        "hold",
        "limp",
        "arm",
        "estop",
        "auth",
        "status",
    ] {
        assert!(
            fx.services.contains_key(s),
            "service {s} advertised: {:?}",
            fx.services
        );
    }
    // A service answers what the socket answers, results and errors alike (each
    // socket connection drives only while connected: one operator at a time).
    let via_sock = d.once().call("gait.set", json!({"gait": "slithering"}));
    // The server frees that connection's drive once it has seen it close.
    d.sock
        .wait_status(Duration::from_secs(5), "the drive freed", |s| {
            s["driver"].is_null()
        });
    let via_fox = fx
        .call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    assert_eq!(via_fox, via_sock);
    let bad = json!({"gait": "slithering", "amplitude_lat_rad": 99.0});
    let fox_err = fx.call("params.set", bad.clone()).expect_err("refused");
    let mut other = d.once();
    other.call("take_over", json!({}));
    let sock_err = other.call_raw("params.set", bad);
    drop(other);
    let msg = sock_err["error"]["message"].as_str().expect("an error");
    assert!(
        fox_err.contains(msg),
        "{fox_err:?} carries the socket's {msg:?}"
    );
    assert!(fx.call("gait.set", json!({"gait": "nope"})).is_err());
    let status = fx.call("status", json!({})).expect("status");
    assert_eq!(status["gait"], "slithering");

    // Drive: twists at 10 Hz set the speed (linear.x 0.8 → 0.8 rad/s) and the steering.
    fx.advertise(1, "/cmd_vel");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        fx.publish(1, &twist(0.8, 0.5));
        fx.drain(Duration::from_millis(100));
    }
    let p = d.sock.call("params.get", json!({"gait": "slithering"}));
    assert!(
        (p["params"]["temporal_freq_rad_s"].as_f64().unwrap() - 0.8).abs() < 1e-9,
        "{p}"
    );
    assert!(
        (p["params"]["offset_lat_rad"].as_f64().unwrap() + 0.1).abs() < 1e-9,
        "{p}"
    );
    assert_eq!(d.sock.call("status", json!({}))["mode"], "running");

    // The dead-man: the twists stop; the gait makes a controlled stop, then the robot
    // holds.
    let stopped = Instant::now();
    let s = d
        .sock
        .wait_status(Duration::from_secs(10), "the dead-man's hold", |s| {
            s["mode"] == "hold"
        });
    let after = stopped.elapsed().as_secs_f64();
    assert!(
        after >= 0.5,
        "not before the twists expired: {after} s ({s})"
    );
    assert!(
        (slithering_speed(&mut d.sock) - 0.8).abs() < 1e-9,
        "the speed asked for stays: the stop stopped the gait, not its parameters"
    );
    // E-stop from Foxglove, and arming again.
    fx.call("estop", json!({})).expect("estop");
    d.sock
        .wait_status(Duration::from_secs(5), "e-stopped", |s| {
            s["mode"] == "e_stop"
        });
    fx.call("arm", json!({})).expect("arm");
    d.sock
        .wait_status(Duration::from_secs(10), "running again", |s| {
            s["mode"] == "running"
        });

    let events = d.stop();
    let actions: Vec<&str> = events.iter().filter_map(|e| e["action"].as_str()).collect();
    for a in ["gait.set", "params.set", "hold", "estop", "arm"] {
        assert!(actions.contains(&a), "{a} recorded: {actions:?}");
    }
    assert!(events.iter().all(|e| {
        e["client"]
            .as_str()
            .is_some_and(|c| c.contains("foxglove client"))
    }));
    let dead_man: Vec<&Value> = events
        .iter()
        .filter(|e| e["client"].as_str().unwrap().starts_with("dead-man"))
        .collect();
    eprintln!("the dead-man's actions: {dead_man:?}");
    assert!(
        dead_man
            .iter()
            .any(|e| e["action"] == "hold" && e["ok"] == true),
        "{dead_man:?}"
    );
    assert!(
        events.iter().any(|e| e["ok"] == false),
        "refusals recorded too"
    );
}

#[test]
fn teleop_turns_a_sidewinding_controllers_nominal_heading() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call(
        "controller.set",
        json!({"gait": "sidewinding", "controller": "anti_compliant_sidewinding", "preset": "ac_sfc"}),
    )
    .expect("controller.set");
    fx.call("gait.set", json!({"gait": "sidewinding"}))
        .expect("gait.set");
    d.sock.wait_status(
        Duration::from_secs(30),
        "sidewinding's controller drives",
        |s| {
            s["controller"]["controller"] == "anti_compliant_sidewinding"
                && s["controller"]["state"] == "engaged"
                && s["body"]["valid"] == true
        },
    );
    fx.advertise(1, "/cmd_vel");
    for _ in 0..10 {
        fx.publish(1, &twist(1.0, 1.0));
        fx.drain(Duration::from_millis(100));
    }
    let [events, signals]: [Vec<Value>; 2] = d
        .stop_with(&["/operator", "/controller/signals"])
        .try_into()
        .unwrap();
    let headings: Vec<&Value> = events
        .iter()
        .filter(|e| e["action"] == "controller.heading")
        .collect();
    assert!(
        headings.len() >= 5,
        "each turning twist leads the heading: {events:?}"
    );
    assert!(headings.iter().all(|e| e["ok"] == true), "{headings:?}");
    assert!(
        events
            .iter()
            .filter(|e| e["action"] == "params.set")
            .all(|e| e["params"].get("taper").is_none()),
        "no taper: the controller steers"
    );
    // The controller holds the last heading teleop sent.
    let last = headings.last().unwrap()["params"]["heading_rad"]
        .as_f64()
        .unwrap();
    let nominal = signals
        .iter()
        .rev()
        .find_map(|s| s["signals"]["heading_nominal_rad"].as_f64())
        .expect("the controller reports its nominal heading");
    assert!((nominal - last).abs() < 1e-9, "{nominal} vs {last}");
}

#[test]
fn teleop_turns_a_slithering_controllers_held_heading_instead_of_fighting_it() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega"}),
    )
    .expect("controller.set");
    fx.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    d.sock.wait_status(
        Duration::from_secs(30),
        "compliant slithering drives",
        |s| {
            s["controller"]["preset"] == "a_ws_omega"
                && s["controller"]["state"] == "engaged"
                && s["body"]["valid"] == true
        },
    );
    // Holding a heading: the controller steers by it, so teleop's turn moves it.
    fx.call(
        "controller.heading",
        json!({"gait": "slithering", "here": true}),
    )
    .expect("controller.heading");
    d.sock.wait_status(Duration::from_secs(10), "holding", |s| {
        s["controller"]["signals"]["steering"]
            .as_f64()
            .is_some_and(|x| x >= 1.0)
    });
    fx.advertise(1, "/cmd_vel");
    for _ in 0..5 {
        fx.publish(1, &twist(1.0, 1.0)); // the speed it has: nothing hands the joints back
        fx.drain(Duration::from_millis(100));
    }
    let events = d.stop();
    let turns: Vec<&Value> = events
        .iter()
        .filter(|e| e["action"] == "controller.heading")
        .collect();
    assert!(
        turns.len() >= 3 && turns.iter().all(|e| e["ok"] == true),
        "{events:?}"
    );
    assert!(
        events
            .iter()
            .filter(|e| e["action"] == "params.set")
            .all(|e| e["params"].get("offset_lat_rad").is_none()),
        "the offset is left to the controller: {events:?}"
    );
}

#[test]
fn teleop_takes_over_from_the_navigator() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    d.sock
        .wait_status(Duration::from_secs(20), "a valid estimate", |s| {
            s["body"]["valid"] == true
        });
    // A one-off navigate (as `snakectl navigate` is): its connection drives only while
    // it is open.
    d.once().call("navigate", json!({"heading_rad": 0.0}));
    d.sock
        .wait_status(Duration::from_secs(10), "navigating", |s| {
            s["navigator"]["active"] == true
        });
    fx.advertise(1, "/cmd_vel");
    fx.publish(1, &twist(0.5, 0.0));
    let s = d
        .sock
        .wait_status(Duration::from_secs(10), "navigation stopped", |s| {
            s["navigator"]["active"] == false
        });
    assert_eq!(s["navigator"]["stopped"], "off", "{}", s["navigator"]);
    let events = d.stop();
    assert!(
        events
            .iter()
            .any(|e| e["action"] == "navigate" && e["params"]["off"] == true)
    );
}
