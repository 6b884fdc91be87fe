//! Hardware-in-loop staleness: `snake-emu --delay-ms D` holds every feedback datagram
//! back by D. Receipt times alone would call it fresh; the daemon measures the round
//! trip of the command each feedback reports as applied, so the age it reports is the
//! delay, and a delay past the feedback timeout keeps it from running, as missing
//! feedback does.
mod common;

use std::time::Duration;

use common::Rig;

const N: usize = 6;

fn rig(delay_ms: u32) -> Rig {
    let delay = delay_ms.to_string();
    Rig::start(
        N,
        &["--delay-ms", &delay],
        "command_lifetime_s = 0.5",
        // Generous for a loaded CI machine: 0.25 s is far from 40 ms and from 600 ms.
        "[failsafe]\nfeedback_timeout_s = 0.25\nlimp_after_s = 1.0\n[gait]\ninitial = \"rolling\"\nstart = \"run\"",
    )
}

#[test]
fn a_short_delay_shows_in_the_age_and_a_long_one_trips_the_failsafe() {
    let mut short = rig(40);
    let s = short
        .client
        .wait_status(Duration::from_secs(30), "running", |s| {
            s["mode"] == "running"
        });
    std::thread::sleep(Duration::from_millis(500));
    let s2 = short.client.call("status", serde_json::json!({}));
    let age = s2["joints"]["max_feedback_age_s"].as_f64().unwrap();
    assert!(
        age >= 0.035,
        "the 40 ms delay shows in the age: {age} ({s})"
    );
    assert_eq!(s2["mode"], "running", "{s2}");
    short.stop(N);

    let mut long = rig(600);
    // Feedback arrives (late) all the time, but never fresh enough to run on.
    std::thread::sleep(Duration::from_secs(3));
    let s = long.client.call("status", serde_json::json!({}));
    assert_ne!(
        s["mode"], "running",
        "600 ms old feedback must not drive: {s}"
    );
    let stats = long.client.call("stats", serde_json::json!({}));
    assert!(
        stats["bus"]["feedback_received"].as_u64().unwrap() > 0,
        "the feedback did arrive: {stats}"
    );
    let age = s["joints"]["max_feedback_age_s"]
        .as_f64()
        .unwrap_or(f64::INFINITY);
    assert!(age >= 0.5, "reported as old as it is: {age} ({s})");
    long.stop(N);
}
