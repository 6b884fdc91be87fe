//! Every method against the real server and a fake loop; the loop's answers
//! (ok, refused, busy, silent) and many clients at once.
use crate::support::socket;

use std::sync::Arc;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use snaked::gait::{GaitKind, ParamPatch};
use snaked::rt::messages::{LoopRequest, Refusal, Rejection};
use snaked::socket::api::code;
use snaked::socket::client::ClientError;
use socket::{Harness, LoopSpec, error_code, error_message, raw};

#[test]
fn every_method_answers() {
    let h = Harness::default_server();
    let mut c = h.client();

    let s = c.call("status", None).unwrap();
    assert_eq!(s["gait"], "slithering");
    assert_eq!(s["modules"], 8);
    assert_eq!(s["daemon"]["bus"], "emulated");
    assert_eq!(s["daemon"]["module_names"][0], "SA000");
    assert_eq!(s["joints"]["position_rad"].as_array().unwrap().len(), 8);
    assert!(s["cycle"].as_u64().is_some() && s["t_s"].as_f64().is_some());

    let l = c.call("gait.list", None).unwrap();
    assert_eq!(l["active"], "slithering");
    assert_eq!(l["gaits"].as_array().unwrap().len(), 6);

    let g = c
        .call("gait.set", Some(json!({"gait": "rolling"})))
        .unwrap();
    assert_eq!(g["gait"], "rolling");

    let one = c
        .call("params.get", Some(json!({"gait": "sidewinding"})))
        .unwrap();
    assert_eq!(one["gait"], "sidewinding");
    assert_eq!(one["params"]["amplitude_dor_rad"], 0.3);
    assert_eq!(one["blend_time_s"], 2.0);
    let all = c.call("params.get", None).unwrap();
    assert_eq!(all["gaits"].as_object().unwrap().len(), 6);

    let p = c
        .call(
            "params.set",
            Some(json!({"gait": "slithering", "amplitude_lat_rad": 0.5})),
        )
        .unwrap();
    assert_eq!(p["params"]["amplitude_lat_rad"], 0.5);
    assert_eq!(p["params"]["temporal_freq_rad_s"], 1.5, "other fields kept");
    let b = c
        .call("params.set", Some(json!({"blend_time_s": 3.5})))
        .unwrap();
    assert_eq!(b["blend_time_s"], 3.5);

    for m in ["hold", "limp", "estop", "arm"] {
        assert_eq!(c.call(m, None).unwrap()["ok"], true, "{m}");
    }
    let st = c.call("stats", None).unwrap();
    assert!(
        st["loop"]["period_error"]["p99_us"].as_f64().unwrap() > 0.0,
        "{st}"
    );
    assert!(st["loop"]["wakeup_latency"]["p99_us"].is_number(), "{st}");
    assert!(st["bus"]["feedback_received"].as_u64().unwrap() > 0);
    assert!(st["cycles"].as_u64().unwrap() > 0);

    let sub = c.call("telemetry.subscribe", None).unwrap();
    assert_eq!(sub, json!({"subscribed": true, "rate_hz": 10.0}));
    let un = c.call("telemetry.unsubscribe", None).unwrap();
    assert_eq!(un["subscribed"], false);
    assert_eq!(c.call("ping", None).unwrap()["pong"], true);

    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.5),
        ..ParamPatch::default()
    };
    assert_eq!(
        h.fake.seen(),
        vec![
            LoopRequest::SetGait {
                gait: GaitKind::Rolling
            },
            LoopRequest::SetParams {
                gait: GaitKind::Slithering,
                patch
            },
            LoopRequest::SetBlendTime { blend_time_s: 3.5 },
            LoopRequest::Hold,
            LoopRequest::Limp,
            LoopRequest::EStop,
            LoopRequest::Arm,
        ]
    );
}

#[test]
fn applied_changes_show_in_later_answers() {
    let h = Harness::default_server();
    let mut c = h.client();
    c.call(
        "params.set",
        Some(json!({"gait": "rolling", "temporal_freq_rad_s": 2.0})),
    )
    .unwrap();
    c.call("estop", None).unwrap();
    // The loop acks before it publishes the cycle's snapshot: poll for it.
    let deadline = Instant::now() + Duration::from_secs(10);
    let s = loop {
        let s = c.call("status", None).unwrap();
        if s["requests_applied"] == 2 || Instant::now() > deadline {
            break s;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert_eq!(s["mode"], "e_stop");
    assert_eq!(s["requests_applied"], 2);
    let p = c
        .call("params.get", Some(json!({"gait": "rolling"})))
        .unwrap();
    assert_eq!(p["params"]["temporal_freq_rad_s"], 2.0);
}

#[test]
fn refused_requests_carry_the_loops_reason() {
    let spec = LoopSpec {
        policy: Arc::new(|r| {
            Some(match r {
                LoopRequest::Arm => Err(Rejection::Failsafe(Refusal::FeedbackUnhealthy)),
                LoopRequest::SetGait { .. } => Err(Rejection::Failsafe(Refusal::EStopLatched)),
                _ => Ok(()),
            })
        }),
        ..LoopSpec::default()
    };
    let h = Harness::new(spec, |_| {});
    let mut c = h.client();
    let a = raw(&mut c, r#"{"id":1,"method":"arm"}"#);
    assert_eq!(error_code(&a), code::REFUSED);
    assert!(error_message(&a).contains("feedback is not healthy"), "{a}");
    let a = raw(
        &mut c,
        r#"{"id":2,"method":"gait.set","params":{"gait":"rolling"}}"#,
    );
    assert_eq!(error_code(&a), code::REFUSED);
    assert!(error_message(&a).contains("e-stop is latched"), "{a}");
    assert_eq!(c.call("hold", None).unwrap()["ok"], true, "still usable");
}

#[test]
fn busy_when_the_loops_channel_is_full() {
    let spec = LoopSpec {
        channel_capacity: 1,
        drains: false,
        ..LoopSpec::default()
    };
    let h = Harness::new(spec, |c| c.ack_timeout = Duration::from_millis(200));
    let mut c = h.client();
    // The first request fills the channel and is never answered.
    let a = raw(&mut c, r#"{"id":1,"method":"hold"}"#);
    assert_eq!(error_code(&a), code::LOOP_TIMEOUT, "{a}");
    // The next one finds the channel full: busy, without waiting for any ack.
    let mut other = h.client();
    let a = raw(&mut other, r#"{"id":2,"method":"limp"}"#);
    assert_eq!(error_code(&a), code::BUSY, "{a}");
    assert_eq!(a["id"], 2);
    // Reading methods do not need the channel.
    assert_eq!(c.call("status", None).unwrap()["modules"], 8);
}

#[test]
fn a_silent_loop_times_out_and_the_connection_stays_usable() {
    let spec = LoopSpec {
        policy: Arc::new(|r| match r {
            LoopRequest::Hold => None, // drained, never acked
            _ => Some(Ok(())),
        }),
        ..LoopSpec::default()
    };
    let h = Harness::new(spec, |c| c.ack_timeout = Duration::from_millis(100));
    let mut c = h.client();
    let a = raw(&mut c, r#"{"id":"h","method":"hold"}"#);
    assert_eq!(error_code(&a), code::LOOP_TIMEOUT, "{a}");
    assert_eq!(a["id"], "h");
    assert!(error_message(&a).contains("100 ms"), "{a}");
    assert_eq!(c.call("limp", None).unwrap()["ok"], true);
}

#[test]
fn many_clients_at_once() {
    let h = Harness::default_server();
    let threads: Vec<_> = (0..16)
        .map(|t| {
            let mut c = h.client();
            std::thread::spawn(move || {
                for i in 0..20 {
                    let id = format!("{t}-{i}");
                    let method = if i % 2 == 0 { "status" } else { "hold" };
                    let a = raw(&mut c, &json!({"id": id, "method": method}).to_string());
                    assert_eq!(a["id"], Value::from(id.as_str()));
                    assert!(a.get("result").is_some(), "{a}");
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
    assert_eq!(h.fake.seen().len(), 16 * 10);
}

/// Count telemetry messages during `window`, reading `c` only.
fn count_stream(c: &mut snaked::socket::client::Client, window: Duration) -> Vec<Value> {
    let mut out = Vec::new();
    let end = Instant::now() + window;
    while Instant::now() < end {
        let m = c.next_message().unwrap();
        assert_eq!(m["method"], "telemetry", "{m}");
        assert!(m.get("id").is_none());
        out.push(m["params"].clone());
    }
    out
}

#[test]
fn telemetry_streams_at_about_the_requested_rate() {
    let h = Harness::default_server();
    let mut fast = h.client();
    let mut slow = h.client();
    let a = fast
        .call("telemetry.subscribe", Some(json!({"rate_hz": 100})))
        .unwrap();
    assert_eq!(a["rate_hz"], 100.0);
    slow.call("telemetry.subscribe", Some(json!({"rate_hz": 2})))
        .unwrap();
    let msgs = count_stream(&mut fast, Duration::from_secs(1));
    let slow_msgs = count_stream(&mut slow, Duration::from_millis(100));
    // Loose: 100 Hz for 1 s gives far more than 10; 2 Hz for ~1.1 s gives at most a few.
    assert!(msgs.len() > 10, "only {} messages at 100 Hz", msgs.len());
    assert!(
        (1..=5).contains(&slow_msgs.len()),
        "{} messages at 2 Hz",
        slow_msgs.len()
    );
    let p = &msgs[0];
    for key in ["t_s", "cycle", "mode", "gait", "blend_progress"] {
        assert!(p.get(key).is_some(), "{key} missing in {p}");
    }
    let j = &p["joints"][0];
    for key in [
        "setpoint_rad",
        "position_rad",
        "velocity_rad_s",
        "torque_nm",
        "feedback_age_s",
    ] {
        assert!(j.get(key).is_some(), "{key} missing in {j}");
    }
    let cycles: Vec<u64> = msgs.iter().map(|m| m["cycle"].as_u64().unwrap()).collect();
    assert!(
        cycles.windows(2).all(|w| w[0] <= w[1]),
        "cycles go back: {cycles:?}"
    );

    // After the unsubscribe answer, nothing more streams.
    fast.send_line(r#"{"id":"u","method":"telemetry.unsubscribe"}"#)
        .unwrap();
    loop {
        let m = fast.next_message().unwrap();
        if m["id"] == "u" {
            assert_eq!(m["result"]["subscribed"], false);
            break;
        }
    }
    std::thread::sleep(Duration::from_millis(100));
    fast.send_line(r#"{"id":"p","method":"ping"}"#).unwrap();
    assert_eq!(
        fast.next_message().unwrap()["id"],
        "p",
        "a stream message followed unsubscribe"
    );
}

#[test]
fn a_slow_subscriber_slows_nobody_else() {
    let spec = LoopSpec {
        joints: 64, // big messages fill the socket buffer quickly
        ..LoopSpec::default()
    };
    let h = Harness::new(spec, |_| {});
    let mut sleeper = h.client();
    sleeper
        .call("telemetry.subscribe", Some(json!({"rate_hz": 200})))
        .unwrap();
    // The sleeper reads nothing for a while; another client works normally.
    let mut busy = h.client();
    for i in 0..50 {
        let a = raw(&mut busy, &json!({"id": i, "method": "status"}).to_string());
        assert_eq!(a["id"], i);
    }
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(busy.call("ping", None).unwrap()["pong"], true);
    // The sleeper's backlog is bounded: its stream dropped messages instead.
    sleeper
        .send_line(r#"{"id":"u","method":"telemetry.unsubscribe"}"#)
        .unwrap();
    let mut backlog = 0;
    let answer = loop {
        let m = sleeper.next_message().unwrap();
        if m["id"] == "u" {
            break m;
        }
        backlog += 1;
    };
    assert!(
        answer["result"]["dropped"].as_u64().unwrap() > 0,
        "{answer}"
    );
    assert!(backlog < 300, "backlog of {backlog} messages");
}

#[test]
fn the_client_reports_daemon_errors_as_rpc_errors() {
    let h = Harness::default_server();
    let mut c = h.client();
    match c.call("gait.set", Some(json!({"gait": "nope"}))) {
        Err(ClientError::Rpc(e)) => assert_eq!(e.code, code::INVALID_PARAMS),
        other => panic!("expected an RPC error, got {other:?}"),
    }
}

#[test]
fn a_half_closed_subscriber_keeps_its_stream() {
    use std::io::{BufRead, BufReader, Write};
    let h = Harness::default_server();
    // As `echo '{...subscribe...}' | socat - UNIX-CONNECT:...` does.
    let mut s = std::os::unix::net::UnixStream::connect(&h.path).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s.write_all(b"{\"id\":1,\"method\":\"telemetry.subscribe\",\"params\":{\"rate_hz\":50}}\n")
        .unwrap();
    s.shutdown(std::net::Shutdown::Write).unwrap();
    let mut lines = BufReader::new(s).lines();
    let first: Value = serde_json::from_str(&lines.next().unwrap().unwrap()).unwrap();
    assert_eq!(first["result"]["subscribed"], true);
    for _ in 0..3 {
        let m: Value = serde_json::from_str(&lines.next().unwrap().unwrap()).unwrap();
        assert_eq!(m["method"], "telemetry");
    }
}
