//! `navigate` to a goal through `snaked --emulated` (issue 48, point 4): refused without
//! a valid position; with fixes from an outside source it steers by position and
//! reports the goal, the distance and the cross-track error; when the source stops it
//! falls back to the heading only and says so; at the goal it stops the gait.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use serde_json::{Value, json};

use super::pose::now_s;
use crate::support::rig::{Client, Proc, exe};

/// The source's world is the estimate's shifted by this, m.
const SHIFT: [f64; 2] = [2.0, 1.0];

/// Where the body is in the source's world, from its own odometry (None: not valid).
fn source_position(s: &Value) -> Option<[f64; 2]> {
    let b = &s["body"];
    (b["valid"] == true).then(|| {
        [
            b["odometry_m"][0].as_f64().unwrap() + SHIFT[0],
            b["odometry_m"][1].as_f64().unwrap() + SHIFT[1],
        ]
    })
}

/// A source that follows the body at about 50 Hz while `feeding`, until `quit`.
fn feeder(sock: std::path::PathBuf, feeding: Arc<AtomicBool>, quit: Arc<AtomicBool>) {
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    while !quit.load(Ordering::Relaxed) {
        if feeding.load(Ordering::Relaxed) {
            let s = c.call("status", json!({}));
            if let Some(p) = source_position(&s) {
                let yaw = s["body"]["heading_rad"].as_f64().unwrap();
                c.call(
                    "pose.external",
                    json!({"position_m": p, "yaw_rad": yaw, "stamp_unix_s": now_s(),
                           "source": "mocap"}),
                );
            }
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
fn navigating_to_a_goal_steers_by_position_falls_back_without_it_and_stops_there() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let mut proc = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--socket".into(),
            sock.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(
        Duration::from_secs(30),
        "running, the estimate valid",
        |s| s["mode"] == "running" && s["body"]["valid"] == true,
    );
    // No source yet: a goal cannot be steered to.
    let r = c.call_raw("navigate", json!({"goal_m": [5.0, 1.0]}));
    assert!(
        r["error"]["message"]
            .as_str()
            .unwrap_or_default()
            .contains("no valid position"),
        "{r}"
    );
    for bad in [
        json!({"goal_m": [5.0]}),
        json!({"goal_m": [5.0, "north"]}),
        json!({"goal_m": [1e9, 0.0]}),
        json!({"goal_m": [5.0, 1.0], "heading_rad": 0.2}),
        json!({"goal_m": [5.0, 1.0], "config": {"steering": {"lookahead_m": 0.0}}}),
    ] {
        let r = c.call_raw("navigate", bad.clone());
        assert_eq!(r["error"]["code"], -32602, "{bad}: {r}");
    }
    let feeding = Arc::new(AtomicBool::new(true));
    let quit = Arc::new(AtomicBool::new(false));
    let feed = {
        let (sock, feeding, quit) = (sock.clone(), feeding.clone(), quit.clone());
        std::thread::spawn(move || feeder(sock, feeding, quit))
    };
    let s = c.wait_status(Duration::from_secs(20), "tracking", |s| {
        s["world"]["state"] == "tracking"
    });
    let p = [
        number(&s["world"]["position_m"][0]),
        number(&s["world"]["position_m"][1]),
    ];
    // A goal 4 m away, in the source's world.
    let goal = [p[0] + 4.0, p[1]];
    let r = c.call("navigate", json!({"goal_m": goal}));
    assert_eq!(r["navigating"], true, "{r}");
    assert_eq!(r["goal_m"], json!(goal), "{r}");
    let s = c.wait_status(Duration::from_secs(10), "steering by position", |s| {
        s["navigator"]["by_position"] == true && s["navigator"]["distance_m"].is_number()
    });
    let n = &s["navigator"];
    assert_eq!(n["goal_m"], json!(goal), "{n}");
    assert_eq!(n["active"], true, "{n}");
    let d = number(&n["distance_m"]);
    assert!((3.0..5.0).contains(&d), "about 4 m to go: {n}");
    assert!(number(&n["cross_track_m"]).abs() < 1.0, "{n}");
    // The source stops: stale, and the navigator goes on by heading, saying so.
    feeding.store(false, Ordering::Relaxed);
    let s = c.wait_status(Duration::from_secs(10), "by heading only", |s| {
        s["navigator"]["by_position"] == false
    });
    assert_eq!(s["navigator"]["active"], true, "{s}");
    assert_eq!(s["navigator"]["distance_m"], Value::Null, "{s}");
    assert_ne!(s["world"]["state"], "tracking", "{s}");
    // Back: by position again.
    feeding.store(true, Ordering::Relaxed);
    c.wait_status(Duration::from_secs(20), "by position again", |s| {
        s["navigator"]["by_position"] == true
    });
    // A goal where the body is: it arrives and stops the gait.
    let s = c.call("status", json!({}));
    let here = [
        number(&s["world"]["position_m"][0]),
        number(&s["world"]["position_m"][1]),
    ];
    c.call("navigate", json!({"goal_m": here}));
    let s = c.wait_status(Duration::from_secs(10), "arrived", |s| {
        s["navigator"]["stopped"] == "arrived"
    });
    assert_eq!(s["navigator"]["active"], false, "{s}");
    assert_ne!(s["motion"]["state"], "running", "the gait stops: {s}");
    quit.store(true, Ordering::Relaxed);
    feed.join().unwrap();
    proc.signal(libc::SIGTERM);
    assert!(proc.wait(Duration::from_secs(30)).success());
}
