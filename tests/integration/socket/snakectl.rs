//! `snakectl` against the real server with a fake loop.
use crate::support::socket;

use std::process::{Command, Output};

use serde_json::Value;
use snaked::gait::GaitKind;
use snaked::rt::messages::LoopRequest;
use socket::Harness;

fn snakectl(h: &Harness, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .arg("--socket")
        .arg(&h.path)
        .args(args)
        .output()
        .expect("snakectl runs")
}

fn stdout(o: &Output) -> String {
    assert!(
        o.status.success(),
        "snakectl failed: {}\n{}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone()).unwrap()
}

#[test]
fn human_and_json_output() {
    let h = Harness::default_server();
    let status = stdout(&snakectl(&h, &["status"]));
    assert!(
        status.contains("slithering") && status.contains("modules"),
        "{status}"
    );

    let json: Value = serde_json::from_str(&stdout(&snakectl(&h, &["--json", "status"]))).unwrap();
    assert_eq!(json["modules"], 8);

    let list = stdout(&snakectl(&h, &["gait", "list"]));
    assert!(
        list.lines().any(|l| l.starts_with("* slithering")),
        "{list}"
    );

    let stats = stdout(&snakectl(&h, &["stats"]));
    for col in [
        "p50",
        "p99",
        "p99.9",
        "max",
        "period error",
        "feedback_received",
    ] {
        assert!(stats.contains(col), "stats lacks {col}:\n{stats}");
    }

    let params = stdout(&snakectl(&h, &["params", "get", "rolling"]));
    assert!(params.contains("phase_shift_rad"), "{params}");

    stdout(&snakectl(&h, &["gait", "set", "rolling"]));
    stdout(&snakectl(
        &h,
        &["params", "set", "rolling", "temporal_freq_rad_s=-0.5"],
    ));
    stdout(&snakectl(&h, &["params", "set", "--blend-time", "4"]));
    for cmd in ["hold", "limp", "estop", "arm"] {
        assert_eq!(stdout(&snakectl(&h, &[cmd])).trim(), "ok");
    }
    let raw: Value = serde_json::from_str(&stdout(&snakectl(&h, &["call", "ping"]))).unwrap();
    assert_eq!(raw["pong"], true);

    let seen = h.fake.seen();
    assert_eq!(
        seen[0],
        LoopRequest::SetGait {
            gait: GaitKind::Rolling
        }
    );
    assert!(
        matches!(seen[1], LoopRequest::SetParams { gait: GaitKind::Rolling, patch: p } if p.temporal_freq_rad_s == Some(-0.5))
    );
    assert_eq!(seen[2], LoopRequest::SetBlendTime { blend_time_s: 4.0 });
    assert_eq!(seen.len(), 7);
}

#[test]
fn watch_prints_the_requested_number_of_lines() {
    let h = Harness::default_server();
    let out = stdout(&snakectl(&h, &["watch", "--rate", "50", "--count", "3"]));
    assert_eq!(out.lines().count(), 3, "{out}");
    assert!(out.lines().all(|l| l.contains("cycle")), "{out}");
    let out = stdout(&snakectl(
        &h,
        &["--json", "watch", "--rate", "50", "--count", "2"],
    ));
    for line in out.lines() {
        let v: Value = serde_json::from_str(line).unwrap();
        assert!(v["joints"].is_array());
    }
    assert_eq!(out.lines().count(), 2);
}

#[test]
fn errors_exit_non_zero_with_a_message() {
    let h = Harness::default_server();
    let o = snakectl(&h, &["gait", "set", "swimming"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("-32602") && err.contains("swimming"), "{err}");

    let o = snakectl(&h, &["params", "set", "rolling", "taper=abc"]);
    assert_eq!(o.status.code(), Some(2), "bad value is a usage error");

    let o = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .args(["--socket", "/nonexistent/snaked.sock", "status"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("/nonexistent/snaked.sock") && err.contains("running"),
        "{err}"
    );
}

#[test]
fn the_socket_comes_from_the_environment() {
    let h = Harness::default_server();
    let o = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .env("SNAKED_SOCKET", &h.path)
        .args(["--json", "call", "ping"])
        .output()
        .unwrap();
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        r#"{"pong":true}"#
    );
}

/// `snakectl ... | head -c 10`: the reader goes away; snakectl stops quietly, as Unix
/// tools do, instead of panicking on the broken pipe.
#[test]
fn a_closed_pipe_ends_snakectl_quietly() {
    use std::process::Stdio;
    let h = Harness::default_server();
    let mut child = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .arg("--socket")
        .arg(&h.path)
        .args(["controller", "list"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("snakectl runs");
    // Close the read end before snakectl writes its (several kB of) output.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.is_empty(), "nothing said on a closed pipe: {err}");
    assert_ne!(out.status.code(), Some(101), "not a panic");
}

/// `snakectl --tcp ... --token-file F` authenticates first; without the file it says so.
#[test]
fn snakectl_over_tcp_sends_the_token() {
    let h = Harness::new(socket::LoopSpec::default(), |c| {
        c.tcp_port = Some(0);
        c.tcp_token = Some("t0ken".into());
    });
    let addr = h.server.as_ref().unwrap().tcp_addr().unwrap().to_string();
    let dir = tempfile::tempdir().unwrap();
    let token = dir.path().join("token");
    std::fs::write(&token, "t0ken\n").unwrap();
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_snakectl"))
            .args(["--tcp", &addr])
            .args(extra)
            .args(["--json", "status"])
            .env_remove("SNAKED_TOKEN_FILE")
            .output()
            .unwrap()
    };
    let ok = run(&["--token-file", token.to_str().unwrap()]);
    let v: Value = serde_json::from_str(&stdout(&ok)).unwrap();
    assert_eq!(v["modules"], 8);
    let no_token = run(&[]);
    assert_eq!(no_token.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&no_token.stderr).contains("--token-file"));
    std::fs::write(&token, "wrong\n").unwrap();
    let wrong = run(&["--token-file", token.to_str().unwrap()]);
    assert_eq!(wrong.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&wrong.stderr).contains("wrong token"));
}

/// Issue 25: with every client slot held, `snakectl estop` is served over the limit. The
/// server's greeting (`id` null, -32004) is not the answer: the stop is applied, snakectl
/// says so and exits 0, and the greeting is shown on stderr.
#[test]
fn an_estop_over_the_client_limit_reports_success_and_the_notice() {
    let h = Harness::new(socket::LoopSpec::default(), |c| c.max_clients = 2);
    // Subscribers are never evicted: both slots stay taken however long this takes.
    let holders: Vec<_> = (0..2)
        .map(|_| {
            let mut c = h.client();
            c.call(
                "telemetry.subscribe",
                Some(serde_json::json!({"rate_hz": 1})),
            )
            .unwrap();
            c
        })
        .collect();
    let o = snakectl(&h, &["estop"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "ok");
    assert!(
        err.contains("too many clients") && err.contains("estop") && err.contains("-32004"),
        "the greeting is shown: {err}"
    );
    assert_eq!(h.fake.seen(), [LoopRequest::EStop]);
    drop(holders);
}
