use super::*;
use crate::gait::GaitKind;
use serde_json::{Value, json};

fn to_value(v: &impl Serialize) -> Value {
    serde_json::from_slice(&serde_json::to_vec(v).expect("encodes")).expect("valid JSON")
}

fn info() -> ControllerInfo {
    ControllerInfo {
        id: 7,
        gait: GaitKind::Slithering,
        controller: "compliant",
        preset: "test",
        config: json!({"k": 1}),
        report: crate::controller_interface::testing::sample_report_spec(),
    }
}

fn record() -> CycleRecord {
    let mut r = CycleRecord::EMPTY;
    r.cycle = 3;
    r.t_ns = 3_000_000;
    r.modules = 2;
    r.joints[0].position_rad = 0.5;
    r.joints[1].cmd_position_rad = 0.25;
    r.joints[1].accel_m_s2 = [0.0, 0.0, 9.81];
    r.controller_id = 7;
    r.engaged = true;
    r.report.signals[0] = 0.4;
    r.report.fields[0].count = 2;
    r.report.fields[0].a[..2].copy_from_slice(&[f64::NEG_INFINITY, 0.5]);
    r.report.fields[0].b[..2].copy_from_slice(&[0.5, f64::INFINITY]);
    r.report.fields[0].columns[1][1] = 2.0;
    r
}

#[test]
fn joints_commands_and_imu_are_per_module_with_nan_as_null() {
    let r = record();
    let j = to_value(&Joints::new(&r));
    assert_eq!(j["position_rad"], json!([0.5, 0.0]));
    let c = to_value(&Commands::new(&r));
    assert_eq!(c["position_rad"], json!([null, 0.25]));
    let i = to_value(&Imu::new(&r));
    assert_eq!(
        i["modules"][1]["accel_m_s2"]["z"]
            .as_f64()
            .map(|z| z as f32),
        Some(9.81)
    );
}

#[test]
fn signals_are_named_and_only_while_engaged() {
    let mut r = record();
    let info = info();
    let s = to_value(&ControllerSignals::new(&r, Some(&info)));
    assert_eq!(
        s["signals"],
        json!({"amplitude_mean_rad": 0.4, "windows": null})
    );
    assert_eq!(s["controller"], "compliant");
    assert_eq!(s["gait"], "slithering");
    r.engaged = false;
    let s = to_value(&ControllerSignals::new(&r, Some(&info)));
    assert_eq!(s["signals"], json!({}));
    assert_eq!(s["controller_id"], 7);
}

#[test]
fn windows_carry_edges_and_named_columns_of_the_used_windows() {
    let r = record();
    let info = info();
    let w = to_value(&ControllerWindows::new(&r, Some(&info)).expect("engaged"));
    let f = &w["fields"][0];
    assert_eq!(f["name"], "amplitude");
    assert_eq!(f["count"], 2);
    assert_eq!(
        f["windows"],
        json!([
            {"a": null, "b": 0.5, "value": 0.0, "force": 0.0},
            {"a": 0.5, "b": null, "value": 0.0, "force": 2.0},
        ])
    );
    assert!(ControllerWindows::new(&r, None).is_none());
}

#[test]
fn events_say_their_kind() {
    use crate::rt::messages::{Refusal, Rejection};
    let mut out = Vec::new();
    let e = RecordEvent::Request {
        ticket: 9,
        request: LoopRequest::SetGait {
            gait: GaitKind::Sidewinding,
        },
        result: Err(Rejection::Failsafe(Refusal::EStopLatched)),
    };
    write_event(&mut out, 5, &e, |_| None).expect("encodes");
    let v: Value = serde_json::from_slice(&out).expect("json");
    assert_eq!(v["kind"], "request");
    assert_eq!(v["request"], "set_gait");
    assert_eq!(v["args"]["gait"], "sidewinding");
    assert_eq!(v["applied"], false);
    assert!(v["error"].as_str().is_some_and(|s| s.contains("e-stop")));
    out.clear();
    let e = RecordEvent::Engaged {
        gait: GaitKind::Slithering,
        controller_id: 7,
    };
    write_event(&mut out, 6, &e, |_| Some("compliant")).expect("encodes");
    let v: Value = serde_json::from_slice(&out).expect("json");
    assert_eq!(v["kind"], "engaged");
    assert_eq!(v["controller"], "compliant");
}

/// A request is recorded as `LoopRequest` defines it: its name, and its fields as
/// `args` (a controller command's name and fields beside the gait; none for a bare
/// request).
#[test]
fn requests_are_recorded_as_defined() {
    use crate::controller_interface::ControllerCommand;
    use crate::gait::ParamPatch;
    let json = |request: LoopRequest| {
        let mut out = Vec::new();
        let e = RecordEvent::Request {
            ticket: 1,
            request,
            result: Ok(None),
        };
        write_event(&mut out, 0, &e, |_| None).expect("encodes");
        let mut v: Value = serde_json::from_slice(&out).expect("json");
        assert_eq!(v["applied"], true);
        let o = v.as_object_mut().expect("object");
        json!({"request": o.remove("request"), "args": o.remove("args")})
    };
    let calibrate = LoopRequest::ControllerCommand {
        gait: GaitKind::Slithering,
        command: ControllerCommand::Calibrate { duration_s: 5.0 },
    };
    assert_eq!(
        json(calibrate),
        json!({"request": "controller_command",
               "args": {"gait": "slithering", "command": "calibrate", "duration_s": 5.0}})
    );
    let heading = LoopRequest::ControllerCommand {
        gait: GaitKind::Sidewinding,
        command: ControllerCommand::SetHeading { heading_rad: None },
    };
    assert_eq!(
        json(heading)["args"],
        json!({"gait": "sidewinding", "command": "set_heading", "heading_rad": null})
    );
    let patch = ParamPatch {
        taper: Some(0.5),
        ..ParamPatch::default()
    };
    let params = json(LoopRequest::SetParams {
        gait: GaitKind::Slithering,
        patch,
    });
    assert_eq!(params["request"], "set_params");
    assert_eq!(params["args"]["patch"]["taper"], 0.5);
    let blend = json(LoopRequest::SetBlendTime { blend_time_s: 2.0 });
    assert_eq!(blend["args"], json!({"blend_time_s": 2.0}));
    assert_eq!(
        json(LoopRequest::EStop),
        json!({"request": "estop", "args": null})
    );
}

/// Issue 45: what became of the gait's controller is recorded with the request.
#[test]
fn a_request_s_continuity_is_recorded() {
    use crate::gait::ParamPatch;
    use crate::rt::messages::Continuity;
    let record = |result| {
        let mut out = Vec::new();
        let e = RecordEvent::Request {
            ticket: 1,
            request: LoopRequest::SetParams {
                gait: GaitKind::Slithering,
                patch: ParamPatch::default(),
            },
            result,
        };
        write_event(&mut out, 0, &e, |_| None).expect("encodes");
        serde_json::from_slice::<Value>(&out).expect("json")
    };
    let v = record(Ok(Some(Continuity::Followed)));
    assert_eq!(v["continuity"], "followed");
    let why = "a reversal of the wave's direction";
    let v = record(Ok(Some(Continuity::HandedBack { why })));
    assert_eq!(
        (v["continuity"].as_str(), v["why"].as_str()),
        (Some("handed_back"), Some(why))
    );
    let v = record(Ok(None));
    assert!(v.get("continuity").is_none(), "{v}");
}
