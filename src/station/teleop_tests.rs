//! Teleop's mapping, resends, heading lead and dead-man (pure, time as an argument).
use super::*;

fn twist(forward: f64, turn: f64) -> Twist {
    Twist { forward, turn }
}

#[test]
fn a_twist_sets_speed_and_steering_within_limits() {
    let c = TeleopConfig::default();
    let mut t = Teleop::default();
    let r = t
        .on_twist(0.0, GaitKind::Slithering, twist(0.8, 1.0), Steer::Knob, &c)
        .pop()
        .unwrap();
    assert_eq!(r.method(), "params.set");
    assert_eq!(params(&r)["gait"], "slithering");
    assert!((params(&r)["temporal_freq_rad_s"].as_f64().unwrap() - 0.8).abs() < 1e-12);
    assert!(
        (params(&r)["offset_lat_rad"].as_f64().unwrap() + 0.2).abs() < 1e-12,
        "left is negative"
    );
    let r = t
        .on_twist(0.1, GaitKind::Slithering, twist(9.0, -9.0), Steer::Knob, &c)
        .pop()
        .unwrap();
    assert_eq!(
        params(&r)["temporal_freq_rad_s"],
        2.0,
        "clamped to max_speed_rad_s"
    );
    assert_eq!(
        params(&r)["offset_lat_rad"],
        0.25,
        "clamped to max_offset_rad"
    );
    // Backing: the turn keeps its sense.
    let r = t
        .on_twist(0.2, GaitKind::Slithering, twist(-1.0, 1.0), Steer::Knob, &c)
        .pop()
        .unwrap();
    assert!(params(&r)["offset_lat_rad"].as_f64().unwrap() > 0.0);
    let r = t
        .on_twist(
            0.3,
            GaitKind::ConicalSidewinding,
            twist(1.0, 1.0),
            Steer::Knob,
            &c,
        )
        .pop()
        .unwrap();
    assert!((params(&r)["taper"].as_f64().unwrap() + 0.4).abs() < 1e-12);
    let r = t.on_twist(
        0.35,
        GaitKind::Sidewinding,
        twist(1.0, 1.0),
        Steer::Knob,
        &c,
    );
    assert_eq!(
        params(&r[0]).as_object().unwrap().len(),
        2,
        "plain sidewinding: speed only"
    );
    let r = t
        .on_twist(0.4, GaitKind::Rolling, twist(1.0, 1.0), Steer::Knob, &c)
        .pop()
        .unwrap();
    assert_eq!(
        params(&r).as_object().unwrap().len(),
        2,
        "rolling: no steering: {}",
        params(&r)
    );
}

#[test]
fn a_repeated_twist_is_resent_only_now_and_then() {
    let c = TeleopConfig::default();
    let mut t = Teleop::default();
    let first = t.on_twist(0.0, GaitKind::Slithering, twist(1.0, 0.0), Steer::Knob, &c);
    assert_eq!(
        first.iter().map(|r| r.method()).collect::<Vec<_>>(),
        ["gait.resume", "params.set"],
        "a session starts by letting the gait move"
    );
    assert!(
        t.on_twist(0.2, GaitKind::Slithering, twist(1.0, 0.0), Steer::Knob, &c)
            .is_empty()
    );
    assert!(
        t.on_twist(0.5, GaitKind::Slithering, twist(0.5, 0.0), Steer::Knob, &c)
            .len()
            == 1
    );
    assert!(
        t.on_twist(1.25, GaitKind::Slithering, twist(0.5, 0.0), Steer::Knob, &c)
            .is_empty()
    );
    assert!(
        t.on_twist(
            0.5 + c.resend_s,
            GaitKind::Slithering,
            twist(0.5, 0.0),
            Steer::Knob,
            &c
        )
        .len()
            == 1
    );
}

#[test]
fn the_dead_man_stops_then_holds_and_a_twist_drives_again() {
    let c = TeleopConfig::default();
    let mut t = Teleop::default();
    assert_eq!(t.tick(100.0, &c), None, "never driven: nothing");
    t.on_twist(0.0, GaitKind::Slithering, twist(1.0, 0.0), Steer::Knob, &c);
    assert_eq!(t.tick(0.4, &c), None);
    let r = t.tick(0.5, &c).unwrap();
    assert_eq!(
        (r.method(), params(&r)["within_s"].as_f64()),
        ("gait.stop", Some(c.stop_s)),
        "a controlled stop, not a speed change blended over the blend time"
    );
    assert_eq!(t.state(), TeleopState::Stopped);
    // A twist within the stop resumes at once; the speed it asks for is live.
    let r = t.on_twist(0.6, GaitKind::Slithering, twist(1.0, 0.0), Steer::Knob, &c);
    assert_eq!(
        r.iter().map(|r| r.method()).collect::<Vec<_>>(),
        ["gait.resume"]
    );
    assert_eq!(t.tick(1.1, &c).unwrap().method(), "gait.stop");
    assert_eq!(t.tick(2.0, &c), None);
    assert_eq!(t.tick(3.0, &c), None);
    let r = t.tick(3.1, &c).unwrap();
    assert_eq!(r.method(), "hold");
    assert_eq!(t.state(), TeleopState::Idle);
    assert_eq!(t.tick(9.0, &c), None, "holds once");
    assert_eq!(t.stop_refused().method(), "hold");
    let r = t.on_twist(10.0, GaitKind::Slithering, twist(0.5, 0.0), Steer::Knob, &c);
    assert_eq!(
        r.iter().map(|r| r.method()).collect::<Vec<_>>(),
        ["gait.resume", "params.set"]
    );
}

#[test]
fn where_the_controller_steers_by_a_heading_the_turn_leads_it() {
    let c = TeleopConfig::default();
    let mut t = Teleop::default();
    let r = t.on_twist(
        0.0,
        GaitKind::Sidewinding,
        twist(1.0, 1.0),
        Steer::Heading(3.0),
        &c,
    );
    assert_eq!(r.len(), 3, "{r:?}");
    assert_eq!(r[0].method(), "gait.resume");
    assert!(
        params(&r[1]).get("taper").is_none(),
        "no taper: the controller steers"
    );
    assert_eq!(r[2].method(), "controller.heading");
    let h = params(&r[2])["heading_rad"].as_f64().unwrap();
    assert!(
        (h - crate::num::wrap_pi(3.0 + c.heading_lead_rad)).abs() < 1e-12,
        "{h}"
    );
    // Turning, each twist follows the body; the speed is not re-sent.
    let r = t.on_twist(
        0.1,
        GaitKind::Sidewinding,
        twist(1.0, 1.0),
        Steer::Heading(3.05),
        &c,
    );
    assert_eq!(
        r.iter().map(|r| r.method()).collect::<Vec<_>>(),
        ["controller.heading"]
    );
    // Straight again: the heading is held where the body is, once.
    let r = t.on_twist(
        0.2,
        GaitKind::Sidewinding,
        twist(1.0, 0.0),
        Steer::Heading(3.1),
        &c,
    );
    assert_eq!(r.len(), 2);
    assert!((params(&r[1])["heading_rad"].as_f64().unwrap() - 3.1).abs() < 1e-12);
    assert!(
        t.on_twist(
            0.3,
            GaitKind::Sidewinding,
            twist(1.0, 0.0),
            Steer::Heading(3.1),
            &c
        )
        .is_empty()
    );
}

#[test]
fn twists_are_parsed_and_bad_ones_refused() {
    let t = Twist::parse(br#"{"linear":{"x":0.5,"y":0,"z":0},"angular":{"x":0,"y":0,"z":-1}}"#)
        .unwrap();
    assert_eq!(t, twist(0.5, -1.0));
    assert_eq!(
        Twist::parse(br#"{"linear":{"x":0.2}}"#).unwrap(),
        twist(0.2, 0.0)
    );
    for bad in [
        &b"nope"[..],
        b"[1]",
        b"{}",
        br#"{"linear":"x"}"#,
        br#"{"linear":{"x":"fast"}}"#,
        br#"{"linear":{"x":1e999}}"#,
        br#"{"linear":{"x":1},"linear":{"x":-1}}"#,
        br#"{"linear":{"x":1,"x":-1}}"#,
        br#"{"linear":{"x":1},"angle":{"z":1}}"#,
        br#"{"linear":{"w":1}}"#,
    ] {
        assert!(
            Twist::parse(bad).is_err(),
            "{}",
            String::from_utf8_lossy(bad)
        );
    }
}

#[test]
fn bad_settings_are_refused() {
    assert!(TeleopConfig::default().check().is_ok());
    for bad in [
        TeleopConfig {
            timeout_s: 0.0,
            ..Default::default()
        },
        TeleopConfig {
            speed_rad_s: f64::NAN,
            ..Default::default()
        },
        TeleopConfig {
            max_taper: 2.0,
            ..Default::default()
        },
        TeleopConfig {
            topic: "cmd_vel".into(),
            ..Default::default()
        },
    ] {
        assert!(bad.check().is_err(), "{bad:?}");
    }
}

/// An act's params as the socket's method takes them.
fn params(a: &crate::operator::Act) -> serde_json::Value {
    crate::socket::act_params(a)
}
