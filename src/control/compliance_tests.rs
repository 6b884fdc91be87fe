use serde_json::json;

use super::*;
use crate::rt::compliance::Engagement;
use crate::shape::Centralization;
use crate::shape::admittance::Compliance;

fn open() -> ComplianceSetting {
    ComplianceSetting::OPEN_LOOP
}

fn err(v: Value) -> String {
    parse(&v, &open()).unwrap_err().message
}

#[test]
fn a_preset_with_overrides() {
    let s = parse(
        &json!({
            "controller": "a_ws",
            "amplitude": {"centralization": "per_joint", "gains": {"stiffness": 9.0, "max": 1.0}},
            "phase": {"enabled": true},
            "compliance": "anti_compliant",
            "torque_deadband_nm": 0.5
        }),
        &open(),
    )
    .unwrap();
    assert_eq!(s.controller, "a_ws");
    let c = s.config.unwrap();
    assert_eq!(c.amplitude.centralization, Centralization::PerJoint);
    assert_eq!(
        (c.amplitude.gains.stiffness, c.amplitude.gains.max),
        (9.0, 1.0)
    );
    assert_eq!(c.amplitude.gains.mass, 1.0, "the rest is the preset's");
    assert!(c.phase.enabled, "a_ws has it off; overridden");
    assert_eq!(c.compliance, Compliance::AntiCompliant);
    assert_eq!(c.torque_deadband_nm, 0.5);
}

#[test]
fn without_a_controller_the_current_setting_is_overridden() {
    let current = ComplianceSetting::named("a_ws_omega").unwrap();
    let s = parse(&json!({"edge_width_modules": 1.0}), &current).unwrap();
    assert_eq!(s.controller, "a_ws_omega");
    assert_eq!(s.config.unwrap().edge_width_modules, 1.0);
    // Open loop has nothing to override.
    let e = err(json!({"edge_width_modules": 1.0}));
    assert!(e.contains("open_loop") && e.contains("a_ws_omega"), "{e}");
    let e = parse(
        &json!({"controller": "cpg", "torque_cutoff_hz": 3.0}),
        &current,
    )
    .unwrap_err()
    .message;
    assert!(e.contains("cpg"), "{e}");
}

#[test]
fn null_bounds_are_unbounded() {
    let s = parse(
        &json!({"controller": "a", "amplitude": {"gains": {"min": null, "max": 1.0}}}),
        &open(),
    )
    .unwrap();
    assert_eq!(s.config.unwrap().amplitude.gains.min, f64::NEG_INFINITY);
    let e = err(json!({"controller": "a", "amplitude": {"gains": {"mass": null}}}));
    assert!(e.contains("compliance.amplitude.gains.mass"), "{e}");
}

#[test]
fn errors_name_the_field() {
    for (v, needle) in [
        (
            json!({"controller": "fast"}),
            "unknown slithering controller `fast`",
        ),
        (json!({"controller": 3}), "compliance.controller"),
        (json!({"controller": "a", "wobble": 1}), "compliance.wobble"),
        (
            json!({"controller": "a", "amplitude": {"gain": {}}}),
            "compliance.amplitude.gain",
        ),
        (
            json!({"controller": "a", "amplitude": {"gains": {"mass": 0.0}}}),
            "compliance.amplitude.gains",
        ),
        (
            json!({"controller": "a", "spatial_freq": {"gains": {"min": 5.0, "max": 4.0}}}),
            "compliance.spatial_freq.gains",
        ),
        (
            json!({"controller": "a", "phase": {"centralization": "global"}}),
            "compliance.phase.centralization",
        ),
        (
            json!({"controller": "a", "compliance": "soft"}),
            "compliance.compliance",
        ),
        (
            json!({"controller": "a", "torque_cutoff_hz": 0.0}),
            "torque_cutoff_hz",
        ),
        (
            json!({"controller": "a", "torque_cutoff_hz": "x"}),
            "compliance.torque_cutoff_hz",
        ),
        (
            json!({"controller": "a", "amplitude": {"enabled": 1}}),
            "compliance.amplitude.enabled",
        ),
        (json!({}), "controller"),
        (json!("a"), "object"),
    ] {
        let e = err(v.clone());
        assert!(e.contains(needle), "{v}: {e}");
    }
}

#[test]
fn views_show_windows_with_open_edges_as_null() {
    let mut t = ComplianceTelemetry {
        setting: ComplianceSetting::named("a_ws_omega").unwrap(),
        engagement: Engagement::Engaged,
        ..ComplianceTelemetry::default()
    };
    t.report.available = true;
    t.report.phase_lag_rad = -0.1;
    t.report.travelling_windows = 2;
    let windows = [
        crate::shape::window::Window {
            a: f64::NEG_INFINITY,
            b: 0.4,
        },
        crate::shape::window::Window {
            a: 0.4,
            b: f64::INFINITY,
        },
    ];
    t.report.fields[0].fill(
        true,
        Centralization::Windowed,
        &windows,
        &[0.7, 0.8],
        &[0.1, -0.2],
        0.0,
    );
    let v = telemetry_view(&t);
    assert_eq!(v["state"], "engaged");
    assert_eq!(v["windows"], 2);
    let amp = &v["fields"]["amplitude"];
    assert_eq!(amp["centralization"], "windowed");
    assert_eq!(amp["windows"][0]["a"], Value::Null);
    assert_eq!(amp["windows"][1]["value"], 0.8);
    assert_eq!(amp["windows"][1]["force"], -0.2);
    assert!(
        v["fields"].get("phase").is_none(),
        "empty fields are left out"
    );
    let line = serde_json::to_string(&v).unwrap();
    assert!(!line.contains("inf") && !line.contains("NaN"), "{line}");

    let s = setting_view(&t.setting);
    assert_eq!(
        s["config"]["phase"]["gains"]["max"],
        Value::Null,
        "unbounded"
    );
    assert_eq!(
        setting_view(&ComplianceSetting::OPEN_LOOP)["config"],
        Value::Null
    );
    let off = telemetry_view(&ComplianceTelemetry::default());
    assert_eq!(
        (off["controller"].as_str(), off["state"].as_str()),
        (Some("open_loop"), Some("off"))
    );
    assert!(off.get("fields").is_none());
}
