//! Hardware-in-loop failsafe, in real time: a module of `snake-emu` falls silent;
//! `snaked` holds, then goes limp, reports why, and the emulator sees it.
use crate::support::rig;

use std::time::Duration;

use rig::Rig;
use serde_json::json;

const N: usize = 8;
const SILENT: usize = 3;
const SILENCE_AT_S: f64 = 5.0;

#[test]
fn a_silent_module_makes_the_daemon_hold_then_go_limp() {
    let silence = format!("{SILENT}@{SILENCE_AT_S}");
    // Timeouts generous enough for a loaded 2-core CI machine; the logic is the same.
    let mut rig = Rig::start(
        N,
        &["--silence", &silence],
        "command_lifetime_s = 0.25",
        "[failsafe]\nfeedback_timeout_s = 0.2\nlimp_after_s = 1.0\n[gait]\ninitial = \"rolling\"\nstart = \"run\"",
    );
    let c = &mut rig.client;
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

    let rec = rig.stop(N);

    // At the emulator: the others were driven before the silence and limp by the end.
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
