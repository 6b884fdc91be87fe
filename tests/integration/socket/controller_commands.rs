//! Commands to a controller over the socket and `snakectl` (calibration, its refusal
//! at shutdown, a nominal heading) and the pole-climbing controller tuned and reported,
//! against the real loop behind the real server.
use crate::support::socket;

use std::time::Duration;

use super::real::{real_loop, snakectl, status_when};
use serde_json::{Value, json};
use snaked::socket::api::code;
use snaked::socket::client::{Client, Endpoint};
use socket::{call, error_code, error_message};

#[test]
fn a_controller_is_calibrated_through_the_socket_and_snakectl() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(20)),
    )
    .unwrap();
    status_when(&mut c, |s| s["controller"]["state"] == "engaged");
    // Open loop has nothing to calibrate: refused by the loop, saying why.
    let r = call(&mut c, "controller.calibrate", json!({"seconds": 1.0}));
    assert_eq!(error_code(&r), code::REFUSED, "{r}");
    assert!(error_message(&r).contains("nothing to calibrate"), "{r}");
    // Bad input never reaches the loop.
    for bad in [
        json!({"seconds": -1.0}),
        json!({"seconds": 1e9}),
        json!({"seconds": 1.0, "clear": true}),
        json!({"clear": "yes"}),
        json!({"gait": "crawling"}),
        json!({"cycles": 3}),
    ] {
        let r = call(&mut c, "controller.calibrate", bad.clone());
        assert_eq!(error_code(&r), code::INVALID_PARAMS, "{bad}: {r}");
    }
    // Another gait's open-loop controller: the same refusal.
    let r = call(&mut c, "controller.calibrate", json!({"gait": "rolling"}));
    assert_eq!(error_code(&r), code::REFUSED, "{r}");

    c.call(
        "controller.set",
        Some(json!({"gait": "slithering", "controller": "dc_switching"})),
    )
    .unwrap();
    let s = status_when(&mut c, |s| {
        s["controller"]["preset"] == "dc_switching" && s["controller"]["state"] == "engaged"
    });
    assert_eq!(
        s["controller"]["signals"]["calibration"], 0.0,
        "uncalibrated: {s}"
    );
    let text = snakectl(
        &l,
        &["--take-over", "controller", "calibrate", "--seconds", "1"],
    );
    assert!(text.contains("calibrated over 1.0 s"), "{text}");
    assert!(text.contains("offset lateral_rad"), "{text}");
    assert!(text.contains("friction_offset"), "{text}");
    let s = c.call("status", None).unwrap();
    let sig = &s["controller"]["signals"];
    assert_eq!(sig["calibration"], 2.0, "{s}");
    // The scripted pegs press the body: the measured offsets (one per body section,
    // in the `sections_lateral` field) are not zero.
    let sections = s["controller"]["fields"]
        .as_array()
        .and_then(|f| f.iter().find(|f| f["name"] == "sections_lateral"))
        .cloned()
        .unwrap_or_else(|| panic!("a sections field: {s}"));
    let offsets: Vec<f64> = sections["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["offset"].as_f64().unwrap())
        .collect();
    assert_eq!(offsets.len(), 3, "{sections}");
    assert!(offsets.iter().any(|v| v.abs() > 1e-4), "{offsets:?}");
    // The default is three gait cycles (2.1 s each at ωT = 3 rad/s).
    let r = c
        .call("controller.calibrate", Some(json!({"gait": "slithering"})))
        .unwrap();
    assert!((r["seconds"].as_f64().unwrap() - 3.0 * std::f64::consts::TAU / 3.0).abs() < 1e-9);
    let text = snakectl(&l, &["--take-over", "controller", "calibrate", "--clear"]);
    assert!(text.contains("cleared"), "{text}");
    let s = status_when(&mut c, |s| s["controller"]["signals"]["calibration"] == 0.0);
    assert_eq!(s["controller"]["signals"]["calibration"], 0.0, "{s}");
}

/// Issue 25: the server shutting down while a calibration waits answers it with the
/// documented -32002 before the connection closes (the loop itself still runs here).
#[test]
fn a_calibration_waiting_when_the_server_shuts_down_is_refused_not_cut_off() {
    let mut l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(20)),
    )
    .unwrap();
    c.call(
        "controller.set",
        Some(json!({"gait": "slithering", "controller": "dc_switching"})),
    )
    .unwrap();
    status_when(&mut c, |s| {
        s["controller"]["preset"] == "dc_switching" && s["controller"]["state"] == "engaged"
    });
    let mut waiting = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(20)),
    )
    .unwrap();
    waiting.call("take_over", None).unwrap(); // c drove first: one operator at a time
    waiting
        .send_line(r#"{"id":3,"method":"controller.calibrate","params":{"seconds":60}}"#)
        .unwrap();
    status_when(&mut c, |s| s["controller"]["signals"]["calibration"] == 1.0);
    l.server.take().unwrap().shutdown();
    let answer = waiting.next_message().expect("answered before the close");
    assert_eq!(answer["id"], 3, "{answer}");
    assert_eq!(error_code(&answer), code::REFUSED, "{answer}");
    assert!(error_message(&answer).contains("shutting down"), "{answer}");
}

#[test]
fn a_nominal_heading_is_set_through_the_socket_and_snakectl() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(20)),
    )
    .unwrap();
    status_when(&mut c, |s| s["controller"]["state"] == "engaged");
    // Slithering's open loop steers by its lateral offset (issue 28) and reports it.
    let r = c
        .call("controller.heading", Some(json!({"heading_rad": 0.5})))
        .unwrap();
    assert_eq!(r["controller"], "open_loop", "{r}");
    let steering = |s: &Value| s["controller"]["signals"]["steering"].as_f64();
    let s = status_when(&mut c, |s| steering(s) > Some(0.0));
    assert!(steering(&s) > Some(0.0), "{s}");
    // Rolling's open loop does not steer: refused by the loop, saying why.
    let r = call(
        &mut c,
        "controller.heading",
        json!({"gait": "rolling", "heading_rad": 0.5}),
    );
    assert_eq!(error_code(&r), code::REFUSED, "{r}");
    assert!(error_message(&r).contains("does not steer"), "{r}");
    for bad in [
        json!({}),
        json!({"heading_rad": 0.5, "here": true}),
        json!({"heading_rad": 100.0}),
        json!({"heading_rad": "north"}),
        json!({"here": "yes"}),
        json!({"gait": "crawling", "here": true}),
    ] {
        let r = call(&mut c, "controller.heading", bad.clone());
        assert_eq!(error_code(&r), code::INVALID_PARAMS, "{bad}: {r}");
    }
    c.call(
        "controller.set",
        Some(json!({"gait": "sidewinding", "controller": "ac_sfc"})),
    )
    .unwrap();
    let r = c
        .call(
            "controller.heading",
            Some(json!({"gait": "sidewinding", "heading_rad": -1.0})),
        )
        .unwrap();
    assert_eq!(r["controller"], "anti_compliant_sidewinding", "{r}");
    assert_eq!(r["heading_rad"], -1.0);
    let text = snakectl(
        &l,
        &[
            "--take-over",
            "controller",
            "heading",
            "here",
            "--gait",
            "sidewinding",
        ],
    );
    assert!(text.contains("nominal heading \"here\""), "{text}");
    let text = snakectl(
        &l,
        &[
            "--take-over",
            "controller",
            "heading",
            "-0.3",
            "--gait",
            "sidewinding",
        ],
    );
    assert!(text.contains("nominal heading -0.3"), "{text}");
}

/// The pole-climbing controller tuned at run time (squeeze, adaptation, nominal radius)
/// and reported: it takes over as soon as the helix is selected, getting on (its stage
/// a signal), and its half turns (R, set point, force, grip) are a field of `status`.
#[test]
fn the_pole_climbing_controller_is_tuned_and_reported_through_the_socket() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(10)),
    )
    .unwrap();
    let text = snakectl(
        &l,
        &[
            "--take-over",
            "controller",
            "set",
            "rolling_helix",
            "windowed_adaptive",
            "gains.bias_force=20",
            "adaptive.low_nm=0.5",
            "adaptive.rate_per_s=0.05",
            "getting_on.side=right",
        ],
    );
    assert!(text.contains("helix_radius/windowed_adaptive"), "{text}");
    // A squeeze the stiffness cannot bound is refused, naming the field.
    let err = call(
        &mut c,
        "controller.set",
        json!({"gait": "rolling_helix", "controller": "helix_radius", "preset": "central",
               "config": {"gains": {"bias_force": 20.0}, "slip": {"squeeze_gain": 5.0}}}),
    );
    assert!(error_message(&err).contains("squeeze_gain"), "{err}");
    let p = c.call(
        "params.set",
        Some(json!({"gait": "rolling_helix", "helix_radius_m": 0.11, "helix_pitch_m": 0.044})),
    );
    assert!(p.is_ok(), "{p:?}");
    c.call("gait.set", Some(json!({"gait": "rolling_helix"})))
        .unwrap();
    // Engaged at the switch, getting on (no blend first).
    let s = status_when(&mut c, |s| {
        s["controller"]["state"] == "engaged"
            && s["controller"]["signals"]["getting_on"].as_f64() > Some(0.0)
    });
    assert_eq!(s["controller"]["controller"], "helix_radius", "{s}");
    assert!(
        s["controller"]["signals"]["getting_on"].as_f64() > Some(0.0),
        "{s}"
    );
    // Once the coil opens its half turns are reported.
    let s = status_when(&mut c, |s| {
        s["controller"]["fields"][0]["windows"]
            .as_array()
            .is_some_and(|w| !w.is_empty())
    });
    let field = &s["controller"]["fields"][0];
    assert_eq!(field["name"], "radius", "{s}");
    let w = &field["windows"][0];
    for col in ["radius_scale", "set_point", "shape_force", "grip_nm"] {
        assert!(w[col].is_number(), "{col}: {w}");
    }
    assert_eq!(s["controller"]["signals"]["squeeze"], 20.0, "{s}");
    let text = snakectl(&l, &["status"]);
    assert!(text.contains("helix_radius/windowed_adaptive"), "{text}");
}
