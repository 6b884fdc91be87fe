//! Slithering's compliant controller over the socket: `params.set` validation against
//! a fake loop, then `status`, telemetry, `params.get` and `snakectl` against the real
//! loop (over the echo bus, with scripted torques) behind the real server.
mod socket_support;

use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use snaked::bus::echo::EchoBus;
use snaked::control::api::code;
use snaked::control::client::{Client, Endpoint};
use snaked::control::{BusKind, DaemonInfo, LoopHandle, Pacing, RunningServer, ServerConfig};
use snaked::gait::{GaitKind, GaitTable};
use snaked::rt::harness::{PERIOD_NS, echo_harness_on};
use snaked::rt::messages::LoopRequest;
use snaked::safety::failsafe::FailsafeConfig;
use socket_support::{Harness, error_code, error_message, raw};

fn set(c: &mut Client, params: Value) -> Value {
    let line = json!({"id": 1, "method": "params.set", "params": params}).to_string();
    raw(c, &line)
}

#[test]
fn params_set_compliance_is_validated_and_sent_with_its_controller() {
    let h = Harness::default_server();
    let mut c = h.client();
    let ok = set(
        &mut c,
        json!({"gait": "slithering", "compliance": {"controller": "a_ws_omega",
            "amplitude": {"gains": {"stiffness": 6.0}}}}),
    );
    let r = &ok["result"];
    assert_eq!(r["compliance"]["controller"], "a_ws_omega", "{ok}");
    assert_eq!(
        r["compliance"]["config"]["amplitude"]["gains"]["stiffness"],
        6.0
    );
    assert_eq!(
        r["compliance"]["config"]["phase"]["gains"]["max"],
        Value::Null
    );
    assert_eq!(h.fake.seen(), [LoopRequest::SetCompliance]);

    for (params, needle) in [
        (
            json!({"gait": "slithering", "compliance": {"controller": "fast"}}),
            "unknown slithering controller `fast`",
        ),
        (
            json!({"gait": "slithering", "compliance": {"controller": "a",
                "amplitude": {"gains": {"damping": -1.0}}}}),
            "compliance.amplitude.gains",
        ),
        (
            json!({"gait": "slithering", "compliance": {"controller": "a", "stiff": 1}}),
            "unknown field `compliance.stiff`",
        ),
        (
            json!({"gait": "rolling", "compliance": {"controller": "a"}}),
            "only slithering",
        ),
        // The nominal amplitude must lie within the compliant amplitude's range.
        (
            json!({"gait": "slithering", "amplitude_lat_rad": 1.3,
                "compliance": {"controller": "a"}}),
            "compliance.amplitude",
        ),
        (json!({"gait": "slithering"}), "nothing to change"),
    ] {
        let a = set(&mut c, params.clone());
        assert_eq!(error_code(&a), code::INVALID_PARAMS, "{params}: {a}");
        let m = error_message(&a);
        assert!(m.contains(needle), "{params}: {m}");
    }
    assert_eq!(h.fake.seen().len(), 1, "nothing invalid reaches the loop");

    // Read back; new slithering params come with a controller rebuilt for them.
    let deadline = Instant::now() + Duration::from_secs(10);
    let got = loop {
        let g = c
            .call("params.get", Some(json!({"gait": "slithering"})))
            .unwrap();
        if g["compliance"]["controller"] == "a_ws_omega" || Instant::now() > deadline {
            break g;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert_eq!(
        got["compliance"]["config"]["amplitude"]["gains"]["stiffness"],
        6.0
    );
    let p = set(
        &mut c,
        json!({"gait": "slithering", "amplitude_lat_rad": 0.6}),
    );
    assert_eq!(p["result"]["params"]["amplitude_lat_rad"], 0.6, "{p}");
    assert_eq!(p["result"]["compliance"]["controller"], "a_ws_omega");
    assert_eq!(h.fake.controllers(), ["a_ws_omega", "a_ws_omega"]);
    assert!(matches!(
        h.fake.seen()[1],
        LoopRequest::SetParams(GaitKind::Slithering, _)
    ));
    // Other gaits' params never carry a controller.
    set(
        &mut c,
        json!({"gait": "rolling", "temporal_freq_rad_s": 1.2}),
    );
    set(
        &mut c,
        json!({"gait": "slithering", "compliance": {"controller": "open_loop"}}),
    );
    assert_eq!(
        h.fake.controllers(),
        ["a_ws_omega", "a_ws_omega", "open_loop"]
    );
}

/// The real loop over an echo bus (torques against the bend at every other lateral
/// joint), stepped about ten times faster than real time on its own thread.
struct RealLoop {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    server: Option<RunningServer>,
    path: std::path::PathBuf,
    _dir: tempfile::TempDir,
}

impl Drop for RealLoop {
    fn drop(&mut self) {
        if let Some(s) = self.server.take() {
            s.shutdown();
        }
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

fn pegs(i: usize, position_rad: f32) -> f32 {
    if i.is_multiple_of(4) && position_rad.abs() > 0.05 {
        2.0 * position_rad.signum()
    } else {
        0.0
    }
}

fn real_loop() -> RealLoop {
    let mut table = GaitTable::default();
    table.get_mut(GaitKind::Slithering).temporal_freq_rad_s = 3.0;
    let bus = EchoBus::new(18, PERIOD_NS).with_torque(pegs);
    let h = echo_harness_on(
        bus,
        table,
        GaitKind::Slithering,
        false,
        FailsafeConfig::default(),
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("snaked.sock");
    let handle = LoopHandle {
        requests: h.requests.clone(),
        acks: h.acks.clone(),
        telemetry: h.telemetry.clone(),
        info: DaemonInfo {
            version: "test".into(),
            module_count: 18,
            module_names: vec![],
            loop_rate_hz: 1000.0,
            bus: BusKind::Emulated,
            pacing: Pacing::Lockstep,
        },
        layout: h.layout.clone(),
        retired: h.retired.clone(),
    };
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        ..ServerConfig::default()
    };
    let server = snaked::control::start(cfg, handle).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let mut control = h.control;
    let thread = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                for _ in 0..10 {
                    control.step();
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    RealLoop {
        stop,
        thread: Some(thread),
        server: Some(server),
        path,
        _dir: dir,
    }
}

/// `status` once `ok` holds for it (or the last one after 30 s).
fn status_when(c: &mut Client, ok: impl Fn(&Value) -> bool) -> Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let s = c.call("status", None).unwrap();
        if ok(&s) || Instant::now() > deadline {
            return s;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn status_telemetry_and_snakectl_show_the_windows() {
    let l = real_loop();
    let mut c = Client::connect(
        &Endpoint::Unix(l.path.clone()),
        Some(Duration::from_secs(10)),
    )
    .unwrap();
    let s = c.call("status", None).unwrap();
    assert_eq!(s["compliance"]["controller"], "open_loop");
    assert_eq!(s["compliance"]["state"], "off");

    c.call(
        "params.set",
        Some(json!({"gait": "slithering", "compliance": {"controller": "a_ws_omega"}})),
    )
    .unwrap();
    let s = status_when(&mut c, |s| {
        s["compliance"]["state"] == "engaged"
            && s["compliance"]["windows_dropped"].as_u64() > Some(0)
    });
    let comp = &s["compliance"];
    assert_eq!(comp["state"], "engaged", "{comp}");
    assert!(comp["windows_born"].as_u64().unwrap() > 0, "{comp}");
    assert!(comp["phase_lag_rad"].is_number(), "{comp}");
    let amp = &comp["fields"]["amplitude"];
    assert_eq!(amp["centralization"], "windowed");
    let windows = amp["windows"].as_array().unwrap();
    assert_eq!(windows.len() as u64, comp["windows"].as_u64().unwrap());
    assert_eq!(windows[0]["a"], Value::Null, "the head window is open");
    assert_eq!(
        windows.last().unwrap()["b"],
        Value::Null,
        "so is the tail's"
    );
    assert!(
        windows[1]["a"]
            .as_f64()
            .is_some_and(|a| (0.0..1.0).contains(&a))
    );
    assert!(
        windows
            .iter()
            .any(|w| w["force"].as_f64().unwrap().abs() > 0.0)
    );
    let phase = &comp["fields"]["phase"];
    assert_eq!(phase["centralization"], "central");
    assert_eq!(phase["windows"].as_array().unwrap().len(), 1);
    assert!(comp["fields"]["spatial_freq"]["windows"].is_array());

    c.call("telemetry.subscribe", Some(json!({"rate_hz": 50})))
        .unwrap();
    let msg = loop {
        let m = c.next_message().unwrap();
        if m["method"] == "telemetry" {
            break m;
        }
    };
    let t = &msg["params"]["compliance"];
    assert_eq!(
        (t["controller"].as_str(), t["state"].as_str()),
        (Some("a_ws_omega"), Some("engaged"))
    );
    assert!(t["fields"]["amplitude"]["windows"].is_array(), "{t}");
    c.call("telemetry.unsubscribe", None).unwrap();

    let out = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .arg("--socket")
        .arg(&l.path)
        .arg("status")
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(out.status.success(), "{text}");
    assert!(text.contains("slithering a_ws_omega (engaged)"), "{text}");
    assert!(
        text.contains("amplitude, rad (windowed, compliant)"),
        "{text}"
    );
    assert!(
        text.contains("phase lag, rad (central, compliant)"),
        "{text}"
    );

    // snakectl sets it too; another gait takes the joints back.
    let out = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .arg("--socket")
        .arg(&l.path)
        .args(["params", "set", "slithering", "--compliance", "a"])
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        out.status.success() && text.contains("compliance    a\n"),
        "{text}"
    );
    c.call("gait.set", Some(json!({"gait": "rolling"})))
        .unwrap();
    let s = status_when(&mut c, |s| s["compliance"]["state"] == "waiting");
    assert_eq!(s["compliance"]["controller"], "a");
    assert_eq!(s["compliance"]["state"], "waiting");
    assert!(s["compliance"].get("fields").is_none());
}
