//! Continuity (issue 45): a driving controller follows the operator's changes of its
//! gait's parameters and takes a configuration in place; what it cannot take says why;
//! changes before the takeover do not keep it waiting. Over the echo bus, among the
//! scripted pegs of the slot tests.
use super::tests::{
    MAX_STEP_RAD, SET, answer, build, engagement, harness, max_diff, pegs, request, retired, run,
    setpoints, table,
};
use crate::controller_interface::Selection;
use crate::gait::{GaitKind, ParamPatch};
use crate::rt::controller_slots::{Continuity, Engagement, Installed};
use crate::rt::harness::{Harness, build_installed};
use crate::rt::messages::LoopRequest;

/// Builds `name` with `config` overrides for slithering.
fn build_with(h: &Harness, name: &str, config: serde_json::Value) -> Installed {
    let sel = Selection {
        config: Some(config),
        ..Selection::named(name)
    };
    build_installed(&h.catalog, &h.layout, &table(), GaitKind::Slithering, &sel)
}

/// Engages `name` among the pegs: the returned harness's controller drives.
fn engaged_among_pegs(name: &str) -> Harness {
    let mut h = harness(Some(pegs));
    run(&mut h, None, 100);
    let c = build(&h, name);
    request(&mut h, SET, Some(c)).unwrap();
    run(&mut h, None, 2100);
    let c = h.telemetry.latest().controller;
    assert_eq!((c.engagement, c.takeovers), (Engagement::Engaged, 1));
    h
}

/// Steps `k` cycles; counts those in which the controller drove, and the largest
/// set-point step.
fn drive(h: &mut Harness, k: usize, driven: &mut usize, step: &mut f64) {
    let mut last = setpoints(h);
    for _ in 0..k {
        h.control.step();
        let now = setpoints(h);
        *step = step.max(max_diff(&now, &last));
        last = now;
        *driven += usize::from(engagement(h) == Engagement::Engaged);
    }
}

/// Issue 45: the teleop's speed (and steering) changes every 0.5 s for 20 s while
/// compliant slithering drives among pegs: it follows every one, never hands back,
/// keeps what it learnt, and nothing jumps or is limited by the guard.
#[test]
fn a_driving_controller_follows_the_operator_s_speed_changes() {
    let mut h = engaged_among_pegs("a_ws_omega");
    let (mut driven, mut step) = (0, 0.0f64);
    let speeds = [1.5, 0.6, 2.0, 1.0, 0.3, 1.8];
    for k in 0..40 {
        let patch = ParamPatch {
            temporal_freq_rad_s: Some(speeds[k % speeds.len()]),
            offset_lat_rad: Some(if k % 3 == 0 { 0.15 } else { -0.05 }),
            ..ParamPatch::default()
        };
        let gait = GaitKind::Slithering;
        let answer = answer(&mut h, LoopRequest::SetParams { gait, patch }, None);
        assert_eq!(answer, Ok(Some(Continuity::Followed)), "change {k}");
        driven += usize::from(engagement(&h) == Engagement::Engaged);
        drive(&mut h, 499, &mut driven, &mut step);
    }
    let c = h.telemetry.latest().controller;
    assert_eq!(driven, 40 * 500, "the controller drove every cycle");
    assert_eq!(c.takeovers, 1, "never handed back");
    assert!(
        step <= MAX_STEP_RAD,
        "a set-point jumped {step} rad in a cycle"
    );
    let guard = h.control.guard_counters();
    assert_eq!(guard.slew_limited_cycles, 0, "{guard:?}");
    assert_eq!(guard.range_clamped_cycles, 0, "{guard:?}");
    assert!(
        c.report.signals[3] >= 1.0,
        "its windows live on: {:?}",
        c.report
    );
}

/// Issue 45: a gain changed every second is taken in place: the same controller
/// drives on under the new id, with what it learnt.
#[test]
fn a_gain_change_is_taken_in_place() {
    let mut h = engaged_among_pegs("a_ws_omega");
    let (mut driven, mut step) = (0, 0.0f64);
    let born_before = h.telemetry.latest().controller.report.signals[4];
    let mut back = retired(&h).len();
    for k in 0..20 {
        let damping = if k % 2 == 0 { 8.0 } else { 5.0 };
        let c = build_with(
            &h,
            "a_ws_omega",
            serde_json::json!({
                "amplitude": {"gains": {"damping": damping}},
                "torque_cutoff_hz": 4.0 + k as f64 * 0.1,
            }),
        );
        let id = c.id;
        assert_eq!(
            answer(&mut h, SET, Some(c)),
            Ok(Some(Continuity::Reconfigured))
        );
        assert_eq!(h.telemetry.latest().controller.active_id, id);
        driven += usize::from(engagement(&h) == Engagement::Engaged);
        drive(&mut h, 999, &mut driven, &mut step);
        back += retired(&h).len();
    }
    let c = h.telemetry.latest().controller;
    assert_eq!(driven, 20 * 1000);
    assert_eq!(c.takeovers, 1);
    assert!(step <= MAX_STEP_RAD, "{step}");
    assert_eq!(h.control.guard_counters().slew_limited_cycles, 0);
    assert!(
        c.report.signals[4] > born_before,
        "the windows born count on from before the edits (not a fresh controller)"
    );
    assert_eq!(back, 21, "the default and each built copy go back");
    assert_eq!(c.freed_in_loop, 0);
}

/// What a controller cannot take in place is handed back or installed afresh, and
/// the answer says why.
#[test]
fn what_cannot_be_taken_in_place_says_why() {
    let mut h = engaged_among_pegs("a_ws_omega");
    // Another kind.
    let c = build(&h, "open_loop");
    assert_eq!(
        answer(&mut h, SET, Some(c)),
        Ok(Some(Continuity::Installed {
            why: "another controller"
        }))
    );
    assert_eq!(engagement(&h), Engagement::Waiting);
    // One that does not drive starts afresh anyway.
    let c = build(&h, "open_loop");
    let a = answer(&mut h, SET, Some(c));
    assert!(
        matches!(a, Ok(Some(Continuity::Installed { why })) if why.contains("not driving")),
        "{a:?}"
    );
    // Another shape (the amplitude central, not windowed): installed afresh.
    let mut h = engaged_among_pegs("a_ws_omega");
    let c = build(&h, "a_ws_omega_central");
    let a = answer(&mut h, SET, Some(c));
    assert!(
        matches!(a, Ok(Some(Continuity::Installed { why })) if why.contains("spread")),
        "{a:?}"
    );
    assert_eq!(engagement(&h), Engagement::Waiting);
    // Directional compliance follows a speed change but not a reversal.
    let mut h = engaged_among_pegs("dc_switching");
    let gait = GaitKind::Slithering;
    let patch = |w| ParamPatch {
        temporal_freq_rad_s: Some(w),
        ..ParamPatch::default()
    };
    let a = answer(
        &mut h,
        LoopRequest::SetParams {
            gait,
            patch: patch(1.4),
        },
        None,
    );
    assert_eq!(a, Ok(Some(Continuity::Followed)));
    let a = answer(
        &mut h,
        LoopRequest::SetParams {
            gait,
            patch: patch(-1.0),
        },
        None,
    );
    assert!(
        matches!(a, Ok(Some(Continuity::HandedBack { why })) if why.contains("reversal")),
        "{a:?}"
    );
    assert_eq!(engagement(&h), Engagement::Waiting);
    let (mut driven, mut step) = (0, 0.0f64);
    drive(&mut h, 2100, &mut driven, &mut step);
    assert!(step <= MAX_STEP_RAD, "{step}");
    let c = h.telemetry.latest().controller;
    assert_eq!((c.engagement, c.takeovers), (Engagement::Engaged, 2));
}

/// Issue 45: a controller waiting for its gait's blend is not kept waiting by the
/// operator's speed changes: once only the gait's own parameters blend, it takes over
/// from where the blend is and follows the rest, without a jump.
#[test]
fn speed_changes_before_the_takeover_do_not_keep_the_controller_waiting() {
    let mut h = harness(Some(pegs));
    run(&mut h, None, 100);
    let c = build(&h, "a_ws_omega");
    request(&mut h, SET, Some(c)).unwrap();
    let gait = GaitKind::Slithering;
    let (mut step, mut engaged_at) = (0.0f64, None);
    let mut last = setpoints(&h);
    for k in 0..8000 {
        if k % 500 == 0 {
            let patch = ParamPatch {
                temporal_freq_rad_s: Some(if (k / 500) % 2 == 0 { 1.4 } else { 0.7 }),
                ..ParamPatch::default()
            };
            request(&mut h, LoopRequest::SetParams { gait, patch }, None).unwrap();
        } else {
            h.control.step();
        }
        let now = setpoints(&h);
        step = step.max(max_diff(&now, &last));
        last = now;
        if engaged_at.is_none() && engagement(&h) == Engagement::Engaged {
            engaged_at = Some(k);
        }
    }
    // The hand-back's fade takes the blend time (2 s); the takeover follows it.
    let at = engaged_at.expect("the controller took over");
    assert!(at < 2200, "took over after {at} cycles");
    assert_eq!(engagement(&h), Engagement::Engaged);
    assert_eq!(h.telemetry.latest().controller.takeovers, 1);
    assert!(step <= MAX_STEP_RAD, "{step}");
    assert_eq!(h.control.guard_counters().slew_limited_cycles, 0);
}
