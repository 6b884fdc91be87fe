//! Controllers over the socket, for any gait: `controller.list/get/set` validated
//! against a fake loop, then `status`, telemetry and `snakectl` against the real loop
//! (over the echo bus, with scripted torques) behind the real server.
use crate::support::socket;

use std::time::{Duration, Instant};

use super::real::{real_loop, snakectl, status_when};
use serde_json::{Value, json};
use snaked::gait::GaitKind;
use snaked::rt::messages::LoopRequest;
use snaked::socket::api::code;
use snaked::socket::client::{Client, Endpoint};
use socket::{Harness, call, error_code, error_message};

#[test]
fn controller_list_shows_every_gait_s_controllers_from_the_registry() {
    let h = Harness::default_server();
    let mut c = h.client();
    let all = call(&mut c, "controller.list", json!({}));
    let gaits = all["result"]["gaits"].as_object().expect("per gait");
    assert_eq!(gaits.len(), GaitKind::ALL.len(), "{all}");
    for (name, g) in gaits {
        let names: Vec<&str> = g["controllers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["name"].as_str().unwrap())
            .collect();
        assert!(names.contains(&"open_loop"), "{name}: {names:?}");
    }
    let slithering = &gaits["slithering"]["controllers"];
    let compliant = slithering
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "compliant_slithering")
        .expect("listed for slithering");
    assert_eq!(compliant["default_preset"], "a_ws_omega");
    let presets: Vec<&str> = compliant["presets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert!(presets.contains(&"a") && presets.contains(&"a_ws_omega_per_joint"));
    let cfg = &compliant["default_config"];
    assert_eq!(
        cfg["phase"]["gains"]["max"],
        Value::Null,
        "unbounded shows null"
    );
    let signals = compliant["report"]["signals"].as_array().unwrap();
    let lag = signals
        .iter()
        .find(|s| s["name"] == "phase_lag_rad")
        .unwrap();
    assert_eq!(lag["unit"], "rad");
    let fields = compliant["report"]["fields"].as_array().unwrap();
    assert_eq!(fields[0]["name"], "amplitude");
    // One gait only.
    let one = call(&mut c, "controller.list", json!({"gait": "rolling"}));
    assert_eq!(
        one["result"]["gaits"].as_object().unwrap().len(),
        1,
        "{one}"
    );
}

#[test]
fn controller_set_is_validated_built_off_the_loop_and_sent() {
    let h = Harness::default_server();
    let mut c = h.client();
    let ok = call(
        &mut c,
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega",
            "config": {"amplitude": {"gains": {"stiffness": 6.0}}}}),
    );
    let r = &ok["result"]["controller"];
    assert_eq!(
        (r["controller"].as_str(), r["preset"].as_str()),
        (Some("compliant_slithering"), Some("a_ws_omega")),
        "{ok}"
    );
    assert_eq!(r["config"]["amplitude"]["gains"]["stiffness"], 6.0);
    assert_eq!(
        r["config"]["amplitude"]["gains"]["damping"], 6.0,
        "the preset's"
    );
    // Any gait: open loop for rolling, by controller name.
    let ok = call(
        &mut c,
        "controller.set",
        json!({"gait": "rolling", "controller": "open_loop"}),
    );
    assert_eq!(ok["result"]["controller"]["gait"], "rolling", "{ok}");
    assert_eq!(
        h.fake.seen(),
        [
            LoopRequest::SetController {
                gait: GaitKind::Slithering
            },
            LoopRequest::SetController {
                gait: GaitKind::Rolling
            }
        ]
    );
    assert_eq!(
        h.fake.controllers(),
        ["compliant_slithering/a_ws_omega", "open_loop/default"]
    );

    for (params, needle) in [
        (
            json!({"gait": "slithering", "controller": "fast"}),
            "unknown controller `fast` for slithering",
        ),
        (
            json!({"gait": "rolling", "controller": "cpg"}),
            "controller cpg does not run rolling",
        ),
        (
            json!({"gait": "slithering", "controller": "compliant_slithering", "preset": "b"}),
            "no preset `b`",
        ),
        (
            json!({"gait": "slithering", "controller": "a", "config": {"stiff": 1}}),
            "`config.stiff`: unknown field `stiff`",
        ),
        (
            json!({"gait": "slithering", "controller": "a",
                "config": {"amplitude": {"gains": {"damping": "x"}}}}),
            "`config.amplitude.gains.damping`",
        ),
        // Bounds are part of the check: a huge bias force would run a parameter away.
        (
            json!({"gait": "slithering", "controller": "a_ws_omega",
                "config": {"spatial_freq": {"gains": {"bias_force": 1e308}}}}),
            "`config.spatial_freq.gains.bias_force` = 1e308 is out of range",
        ),
        (
            json!({"gait": "slithering", "controller": "a_ws_omega",
                "config": {"phase": {"gains": {"bias_force": 1000.0}}}}),
            "`config.phase.gains.bias_force`",
        ),
        // The gait's nominal amplitude must lie within the compliant amplitude's range.
        (
            json!({"gait": "slithering", "controller": "a",
                "config": {"amplitude": {"gains": {"min": 0.9, "max": 1.2}}}}),
            "the nominal amplitude_lat_rad",
        ),
        (json!({"gait": "slithering"}), "missing `controller`"),
        (
            json!({"gait": "slithering", "controller": "a", "extra": 1}),
            "unknown field `extra`",
        ),
    ] {
        let a = call(&mut c, "controller.set", params.clone());
        assert_eq!(error_code(&a), code::INVALID_PARAMS, "{params}: {a}");
        let m = error_message(&a);
        assert!(m.contains(needle), "{params}: {m}");
    }
    assert_eq!(h.fake.seen().len(), 2, "nothing invalid reaches the loop");

    // What replaced slithering's `compliance` object still works, and says so on
    // other gaits.
    let old = call(
        &mut c,
        "params.set",
        json!({"gait": "slithering", "compliance": {"controller": "a",
            "amplitude": {"gains": {"stiffness": 9.0}}, "compliance": "anti_compliant"}}),
    );
    let r = &old["result"]["controller"];
    assert_eq!(r["preset"], "a", "{old}");
    assert_eq!(r["config"]["sign"], "anti_compliant");
    assert_eq!(r["config"]["amplitude"]["gains"]["stiffness"], 9.0);
    let bad = call(
        &mut c,
        "params.set",
        json!({"gait": "rolling", "compliance": {"controller": "a"}}),
    );
    assert!(error_message(&bad).contains("controller.set"), "{bad}");

    // controller.get names what each gait runs (from the loop's telemetry).
    let deadline = Instant::now() + Duration::from_secs(10);
    let got = loop {
        let g = call(&mut c, "controller.get", json!({"gait": "slithering"}));
        if g["result"]["controller"]["preset"] == "a" || Instant::now() > deadline {
            break g;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert_eq!(got["result"]["controller"]["preset"], "a", "{got}");
}

#[test]
fn status_telemetry_and_snakectl_show_any_controller_s_report() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(10)),
    )
    .unwrap();
    // Every gait starts on its open-loop controller, which takes over after the
    // start-up blend.
    let s = status_when(&mut c, |s| s["controller"]["state"] == "engaged");
    assert_eq!(s["controller"]["controller"], "open_loop", "{s}");
    assert!(s["controller"]["signals"]["phase_rad"].is_number(), "{s}");

    c.call(
        "controller.set",
        Some(json!({"gait": "slithering", "controller": "a_ws_omega"})),
    )
    .unwrap();
    let s = status_when(&mut c, |s| {
        s["controller"]["preset"] == "a_ws_omega"
            && s["controller"]["state"] == "engaged"
            && s["controller"]["signals"]["windows_dropped"].as_f64() > Some(0.0)
    });
    let ctl = &s["controller"];
    assert_eq!(ctl["state"], "engaged", "{ctl}");
    assert!(
        ctl["signals"]["windows_born"].as_f64().unwrap() > 0.0,
        "{ctl}"
    );
    assert!(ctl["signals"]["phase_lag_rad"].is_number(), "{ctl}");
    let fields = ctl["fields"].as_array().unwrap();
    let amp = &fields[0];
    assert_eq!(
        (amp["name"].as_str(), amp["centralization"].as_str()),
        (Some("amplitude"), Some("windowed"))
    );
    let windows = amp["windows"].as_array().unwrap();
    assert_eq!(
        windows.len() as f64,
        ctl["signals"]["windows"].as_f64().unwrap()
    );
    assert_eq!(windows[0]["a"], Value::Null, "the head window is open");
    assert_eq!(
        windows.last().unwrap()["b"],
        Value::Null,
        "so is the tail's"
    );
    assert!(
        windows
            .iter()
            .any(|w| w["force"].as_f64().unwrap().abs() > 0.0)
    );
    assert!(windows.iter().all(|w| w["value"].is_number()));
    let phase = &fields[2];
    assert_eq!(phase["centralization"], "central");
    assert!(phase["windows"][0]["lag"].is_number(), "{phase}");

    c.call("telemetry.subscribe", Some(json!({"rate_hz": 50})))
        .unwrap();
    let msg = loop {
        let m = c.next_message().unwrap();
        if m["method"] == "telemetry" {
            break m;
        }
    };
    let t = &msg["params"]["controller"];
    assert_eq!(
        (t["preset"].as_str(), t["state"].as_str()),
        (Some("a_ws_omega"), Some("engaged"))
    );
    assert!(t["fields"][0]["windows"].is_array(), "{t}");
    c.call("telemetry.unsubscribe", None).unwrap();

    let text = snakectl(&l, &["status"]);
    assert!(
        text.contains("control   compliant_slithering/a_ws_omega (engaged)"),
        "{text}"
    );
    assert!(text.contains("amplitude (windowed, compliant"), "{text}");
    assert!(text.contains("phase (central, compliant"), "{text}");

    // snakectl lists and sets too, with overrides by path; another gait takes the
    // joints back, and its own controller drives it.
    let text = snakectl(&l, &["controller", "list", "slithering"]);
    assert!(
        text.contains("compliant_slithering") && text.contains("* a_ws_omega"),
        "{text}"
    );
    let text = snakectl(
        &l,
        &[
            "--take-over",
            "controller",
            "set",
            "slithering",
            "a",
            "amplitude.gains.stiffness=5",
        ],
    );
    assert!(text.contains("compliant_slithering/a"), "{text}");
    assert!(text.contains("amplitude.gains.stiffness=5"), "{text}");
    c.call("gait.set", Some(json!({"gait": "rolling"})))
        .unwrap();
    let s = status_when(&mut c, |s| {
        s["gait"] == "rolling" && s["controller"]["state"] == "engaged"
    });
    assert_eq!(s["controller"]["controller"], "open_loop", "{s}");
    let got = c.call("controller.get", None).unwrap();
    assert_eq!(got["gaits"]["slithering"]["preset"], "a", "{got}");
    assert_eq!(
        got["gaits"]["slithering"]["config"]["amplitude"]["gains"]["stiffness"],
        5.0
    );
    let text = snakectl(&l, &["controller", "get"]);
    assert!(
        text.contains("rolling") && text.contains("open_loop/default"),
        "{text}"
    );
}

#[test]
fn a_controller_of_another_gait_through_the_socket_and_snakectl() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(10)),
    )
    .unwrap();
    let text = snakectl(&l, &["controller", "list", "sidewinding"]);
    assert!(text.contains("serpenoid_admittance"), "{text}");
    assert!(text.contains("scale_lateral []"), "{text}");
    // A preset's name is enough when only one controller of the gait has it.
    let text = snakectl(
        &l,
        &[
            "controller",
            "set",
            "sidewinding",
            "anti_compliant",
            "dorsal.enabled=false",
            "lateral.gains.stiffness=12",
        ],
    );
    assert!(
        text.contains("serpenoid_admittance/anti_compliant"),
        "{text}"
    );
    assert!(text.contains("dorsal.enabled=false"), "{text}");
    c.call("gait.set", Some(json!({"gait": "sidewinding"})))
        .unwrap();
    let s = status_when(&mut c, |s| {
        s["gait"] == "sidewinding"
            && s["controller"]["state"] == "engaged"
            && s["controller"]["signals"]["scale_lateral"]
                .as_f64()
                .is_some_and(|k| (k - 1.0).abs() > 1e-3)
    });
    let ctl = &s["controller"];
    assert_eq!(ctl["controller"], "serpenoid_admittance", "{s}");
    let k = ctl["signals"]["scale_lateral"].as_f64().unwrap();
    // The echo bus pushes every fourth joint against its bend: anti-compliance
    // pushes back, opening the lateral wave; the dorsal one is off and stays nominal.
    assert!(k > 1.0, "anti-compliant lateral scale {k}");
    assert_eq!(ctl["signals"]["scale_dorsal"], 1.0, "{ctl}");
    let text = snakectl(&l, &["status"]);
    assert!(
        text.contains("control   serpenoid_admittance/anti_compliant (engaged)"),
        "{text}"
    );
    assert!(text.contains("scale_lateral"), "{text}");
    // The helix's amplitude is tied to its radius: not a gait this controller runs.
    let err = call(
        &mut c,
        "controller.set",
        json!({"gait": "rolling_helix", "controller": "serpenoid_admittance"}),
    );
    assert!(
        error_message(&err).contains("does not run rolling_helix"),
        "{err}"
    );
}
