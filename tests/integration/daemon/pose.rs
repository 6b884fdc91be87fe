//! `pose.external` through `snaked --emulated`: a fix from an outside source reaches the
//! loop's estimators with its stamp as loop time, shows in `status` and the recording,
//! and bad fixes are refused with the reason; a source that follows the body is fused
//! into its position in the source's world, which goes stale when the source stops.
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde_json::{Value, json};

use crate::support::rig::{Client, Proc, exe};

/// Wall-clock time, s since the Unix epoch (a source's stamps).
pub(super) fn now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

#[test]
fn an_external_fix_reaches_the_loop_as_loop_time_and_a_bad_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let mcap = dir.path().join("run.mcap");
    let mut proc = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--socket".into(),
            sock.display().to_string(),
            "--record".into(),
            mcap.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    let s = c.wait_status(Duration::from_secs(30), "running", |s| {
        s["mode"] == "running"
    });
    assert_eq!(s["external_pose"]["number"], 0, "none yet: {s}");
    // Motion capture: measured 30 ms before it is sent.
    let a = c.call(
        "pose.external",
        json!({"position_m": [1.25, -0.5, 0.02], "yaw_rad": 0.3, "position_sd_m": 0.002,
               "stamp_unix_s": now_s() - 0.03, "source": "mocap"}),
    );
    assert_eq!(a["accepted"], true, "{a}");
    assert_eq!(a["number"], 1, "{a}");
    let latency = a["latency_s"].as_f64().unwrap();
    assert!((0.03..0.5).contains(&latency), "{a}");
    let t_fix = a["t_s"].as_f64().unwrap();
    // The loop took it: its loop time is the measurement's, so it is older than the
    // latency by the time the status is read.
    let s = c.wait_status(Duration::from_secs(10), "the fix", |s| {
        s["external_pose"]["number"] == 1
    });
    let fix = &s["external_pose"];
    assert_eq!(fix["position_m"], json!([1.25, -0.5, 0.02]), "{s}");
    let q = fix["orientation_wxyz"].as_array().unwrap();
    assert!(
        (q[3].as_f64().unwrap() - 0.15f64.sin()).abs() < 1e-9,
        "yaw 0.3: {s}"
    );
    let age = fix["age_s"].as_f64().unwrap();
    let t_loop = s["t_s"].as_f64().unwrap();
    assert!(
        (age - (t_loop - t_fix)).abs() < 1e-6,
        "age is loop time since: {s}"
    );
    assert!(
        age >= latency - 0.01 && age < 5.0,
        "{age} after {latency}: {s}"
    );
    // Refused, with the reason: each one says what is wrong; none reaches the loop.
    let refused = |c: &mut Client, params: Value, says: &str| {
        let e = c.call_raw("pose.external", params);
        let m = e["error"]["message"]
            .as_str()
            .unwrap_or_default()
            .to_owned();
        assert_eq!(e["error"]["code"], -32602, "{e}");
        assert!(m.contains(says), "{says:?} in {m:?}");
    };
    refused(&mut c, json!({}), "position_m");
    refused(&mut c, json!({"position_m": [1.0]}), "position_m");
    refused(
        &mut c,
        json!({"position_m": [0.0, 0.0], "stamp_unix_s": now_s() + 5.0}),
        "ahead",
    );
    refused(
        &mut c,
        json!({"position_m": [0.0, 0.0], "stamp_unix_s": now_s() - 60.0}),
        "old",
    );
    refused(
        &mut c,
        json!({"position_m": [0.0, 0.0], "orientation_wxyz": [0, 0, 0, 0]}),
        "norm",
    );
    refused(
        &mut c,
        json!({"position_m": [0.0, 0.0], "yaw_rad": 0.0, "orientation_wxyz": [1, 0, 0, 0]}),
        "not both",
    );
    refused(
        &mut c,
        json!({"position_m": [0.0, 0.0], "speed": 1}),
        "speed",
    );
    let s = c.call("status", json!({}));
    assert_eq!(s["external_pose"]["number"], 1, "{s}");
    // A source whose world is the estimate's turned by 0.3 rad and shifted by (2, 1),
    // tracking the chassis: the fused position follows it (the first fix above was
    // somewhere else: the gate rejects what disagrees, then the worlds align afresh).
    let (psi, shift) = (0.3f64, [2.0, 1.0]);
    let to_source = |p: [f64; 2]| {
        let (sn, cs) = psi.sin_cos();
        [
            cs * p[0] - sn * p[1] + shift[0],
            sn * p[0] + cs * p[1] + shift[1],
        ]
    };
    let mut last = Value::Null;
    for _ in 0..150 {
        let s = c.call("status", json!({}));
        let b = &s["body"];
        if b["valid"] != true {
            std::thread::sleep(Duration::from_millis(10));
            continue;
        }
        let odo = [
            b["odometry_m"][0].as_f64().unwrap(),
            b["odometry_m"][1].as_f64().unwrap(),
        ];
        let p = to_source(odo);
        let yaw = b["heading_rad"].as_f64().unwrap() + psi;
        c.call(
            "pose.external",
            json!({"position_m": p, "yaw_rad": yaw, "stamp_unix_s": now_s(), "source": "mocap"}),
        );
        last = json!({"expected": p, "world": s["world"]});
        std::thread::sleep(Duration::from_millis(10));
    }
    let s = c.call("status", json!({}));
    let w = &s["world"];
    assert_eq!(w["state"], "tracking", "{w} {last}");
    assert!(
        (w["yaw_offset_rad"].as_f64().unwrap() - psi).abs() < 0.05,
        "{w}"
    );
    let odo = [
        s["body"]["odometry_m"][0].as_f64().unwrap(),
        s["body"]["odometry_m"][1].as_f64().unwrap(),
    ];
    let p = to_source(odo);
    let err = (w["position_m"][0].as_f64().unwrap() - p[0])
        .hypot(w["position_m"][1].as_f64().unwrap() - p[1]);
    assert!(err < 0.02, "the fused position {w} against {p:?}: {err} m");
    assert!(w["accepted"].as_u64().unwrap() > 50, "{w}");
    // The source stops: stale after max_age_s (0.5 s), never a stale position as valid.
    let s = c.wait_status(Duration::from_secs(10), "stale", |s| {
        s["world"]["state"] == "stale"
    });
    assert!(s["world"]["age_s"].as_f64().unwrap() > 0.5, "{s}");
    proc.signal(libc::SIGTERM);
    assert!(proc.wait(Duration::from_secs(30)).success());
    // The recording's body estimate carries the fix.
    let bytes = std::fs::read(&mcap).unwrap();
    let mut seen = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/body/estimate" {
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            if v["fix"]["number"] == 1 {
                seen += 1;
            }
        }
    }
    assert!(seen > 0, "the recording shows the fix");
}
