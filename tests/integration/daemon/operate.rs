//! Operating from Foxglove (`[foxglove] operate`): a WebSocket client calls the
//! station's services and gets what the control socket answers, drives by publishing
//! twists as the Teleop panel does, and the dead-man stops then holds the robot when
//! the twists stop; with a token configured nothing but `auth`, `status` and `estop`
//! works until the client gave it; every action is an `/operator` event in the
//! recording naming the client.
use crate::support::{foxglove_ws, rig};

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use foxglove_ws::{FoxgloveClient, twist};
use rig::{Client, Proc, exe};
use serde_json::{Value, json};

fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

struct Daemon {
    proc: Proc,
    sock: Client,
    fox: SocketAddr,
    dir: tempfile::TempDir,
}

/// `snaked --emulated` on flat ground, operating from Foxglove with `extra` config.
fn daemon(extra: &str) -> Daemon {
    let dir = tempfile::tempdir().unwrap();
    let port = free_tcp_port();
    let config = dir.path().join("snaked.toml");
    std::fs::write(
        &config,
        format!("[foxglove]\noperate = true\nport = {port}\n{extra}\n"),
    )
    .unwrap();
    let sock = dir.path().join("s.sock");
    let world = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat.toml");
    let proc = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--world".into(),
            world.into(),
            "--config".into(),
            config.display().to_string(),
            "--socket".into(),
            sock.display().to_string(),
            "--record".into(),
            dir.path().join("run.mcap").display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(Duration::from_secs(30), "running", |s| {
        s["mode"] == "running"
    });
    Daemon {
        proc,
        sock: c,
        fox: SocketAddr::from(([127, 0, 0, 1], port)),
        dir,
    }
}

impl Daemon {
    /// SIGTERM, exit 0, and the `/operator` events of the recording.
    fn stop(self) -> Vec<Value> {
        self.stop_with(&["/operator"]).remove(0)
    }

    /// SIGTERM, exit 0, and the recording's messages on each of `topics`.
    fn stop_with(mut self, topics: &[&str]) -> Vec<Vec<Value>> {
        self.proc.signal(libc::SIGTERM);
        assert!(self.proc.wait(Duration::from_secs(30)).success(), "exit 0");
        let bytes = std::fs::read(self.dir.path().join("run.mcap")).expect("recording");
        let mut out = vec![Vec::new(); topics.len()];
        for m in mcap::MessageStream::new(&bytes).expect("MCAP") {
            let m = m.expect("a message");
            if let Some(k) = topics.iter().position(|t| *t == m.channel.topic) {
                out[k].push(serde_json::from_slice(&m.data).expect("JSON"));
            }
        }
        out
    }
}

fn slithering_speed(c: &mut Client) -> f64 {
    let p = c.call("params.get", json!({"gait": "slithering"}));
    p["params"]["temporal_freq_rad_s"]
        .as_f64()
        .expect("a speed")
}

#[test]
fn foxglove_drives_the_robot_and_the_dead_man_stops_then_holds_it() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    for s in [
        "gait.set",
        "params.set",
        "controller.set",
        "navigate",
        "hold",
        "limp",
        "arm",
        "estop",
        "auth",
        "status",
    ] {
        assert!(
            fx.services.contains_key(s),
            "service {s} advertised: {:?}",
            fx.services
        );
    }
    // A service answers what the socket answers, results and errors alike.
    let via_fox = fx
        .call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    assert_eq!(
        via_fox,
        d.sock.call("gait.set", json!({"gait": "slithering"}))
    );
    let bad = json!({"gait": "slithering", "amplitude_lat_rad": 99.0});
    let fox_err = fx.call("params.set", bad.clone()).expect_err("refused");
    let sock_err = d.sock.call_raw("params.set", bad);
    let msg = sock_err["error"]["message"].as_str().expect("an error");
    assert!(
        fox_err.contains(msg),
        "{fox_err:?} carries the socket's {msg:?}"
    );
    assert!(fx.call("gait.set", json!({"gait": "nope"})).is_err());
    let status = fx.call("status", json!({})).expect("status");
    assert_eq!(status["gait"], "slithering");

    // Drive: twists at 10 Hz set the speed (linear.x 0.8 → 0.8 rad/s) and the steering.
    fx.advertise(1, "/cmd_vel");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        fx.publish(1, &twist(0.8, 0.5));
        fx.drain(Duration::from_millis(100));
    }
    let p = d.sock.call("params.get", json!({"gait": "slithering"}));
    assert!(
        (p["params"]["temporal_freq_rad_s"].as_f64().unwrap() - 0.8).abs() < 1e-9,
        "{p}"
    );
    assert!(
        (p["params"]["offset_lat_rad"].as_f64().unwrap() + 0.1).abs() < 1e-9,
        "{p}"
    );
    assert_eq!(d.sock.call("status", json!({}))["mode"], "running");

    // The dead-man: the twists stop; the gait goes to zero speed (or, where the
    // controller refuses it, straight to the hold), then the robot holds.
    let stopped = Instant::now();
    let s = d
        .sock
        .wait_status(Duration::from_secs(10), "the dead-man's hold", |s| {
            s["mode"] == "hold"
        });
    let after = stopped.elapsed().as_secs_f64();
    assert!(
        after >= 0.5,
        "not before the twists expired: {after} s ({s})"
    );
    assert_eq!(
        slithering_speed(&mut d.sock),
        0.0,
        "zero speed before the hold"
    );
    // E-stop from Foxglove, and arming again.
    fx.call("estop", json!({})).expect("estop");
    d.sock
        .wait_status(Duration::from_secs(5), "e-stopped", |s| {
            s["mode"] == "e_stop"
        });
    fx.call("arm", json!({})).expect("arm");
    d.sock
        .wait_status(Duration::from_secs(10), "running again", |s| {
            s["mode"] == "running"
        });

    let events = d.stop();
    let actions: Vec<&str> = events.iter().filter_map(|e| e["action"].as_str()).collect();
    for a in ["gait.set", "params.set", "hold", "estop", "arm"] {
        assert!(actions.contains(&a), "{a} recorded: {actions:?}");
    }
    assert!(events.iter().all(|e| {
        e["client"]
            .as_str()
            .is_some_and(|c| c.contains("foxglove client"))
    }));
    let dead_man: Vec<&Value> = events
        .iter()
        .filter(|e| e["client"].as_str().unwrap().starts_with("dead-man"))
        .collect();
    eprintln!("the dead-man's actions: {dead_man:?}");
    assert!(
        dead_man
            .iter()
            .any(|e| e["action"] == "hold" && e["ok"] == true),
        "{dead_man:?}"
    );
    assert!(
        events.iter().any(|e| e["ok"] == false),
        "refusals recorded too"
    );
}

#[test]
fn with_a_token_a_client_operates_only_after_giving_it_and_estop_is_always_reachable() {
    let dir = tempfile::tempdir().unwrap();
    let token = dir.path().join("token");
    std::fs::write(&token, "correct-horse\n").unwrap();
    std::fs::set_permissions(&token, std::os::unix::fs::PermissionsExt::from_mode(0o600)).unwrap();
    let mut d = daemon(&format!("token_file = {:?}", token.display().to_string()));
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    let e = fx
        .call("gait.set", json!({"gait": "rolling"}))
        .expect_err("refused");
    assert!(e.contains("unauthorized"), "{e}");
    // Teleop without the token: refused with a status, nothing changes.
    let before = slithering_speed(&mut d.sock);
    fx.advertise(1, "/cmd_vel");
    for _ in 0..10 {
        fx.publish(1, &twist(1.7, 0.0));
        fx.drain(Duration::from_millis(50));
    }
    assert_eq!(slithering_speed(&mut d.sock), before);
    assert!(
        fx.statuses
            .iter()
            .any(|s| s["message"].as_str().is_some_and(|m| m.contains("auth"))),
        "{:?}",
        fx.statuses
    );
    assert!(fx.call("auth", json!({"token": "wrong"})).is_err());
    assert!(fx.call("gait.set", json!({"gait": "rolling"})).is_err());
    // E-stop needs no token.
    fx.call("estop", json!({})).expect("estop without a token");
    d.sock
        .wait_status(Duration::from_secs(5), "e-stopped", |s| {
            s["mode"] == "e_stop"
        });
    fx.call("auth", json!({"token": "correct-horse"}))
        .expect("the right token");
    fx.call("arm", json!({})).expect("arm once authorised");
    assert_eq!(
        fx.call("gait.set", json!({"gait": "rolling"})).unwrap(),
        json!({"gait": "rolling"})
    );
    // A second client is not authorised by the first one's token.
    let mut other = FoxgloveClient::connect(d.fox, Duration::from_secs(10));
    assert!(other.call("hold", json!({})).is_err());
    let events = d.stop();
    let auth: Vec<&Value> = events.iter().filter(|e| e["action"] == "auth").collect();
    assert!(
        auth.len() >= 2 && auth.iter().all(|e| e["params"] == json!({})),
        "tokens never recorded: {auth:?}"
    );
}

#[test]
fn operating_off_loopback_without_a_token_is_refused_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("snaked.toml");
    std::fs::write(&config, "[foxglove]\noperate = true\nhost = \"0.0.0.0\"\n").unwrap();
    let out = std::process::Command::new(exe("snaked"))
        .args(["--check-config", "--config"])
        .arg(&config)
        .output()
        .expect("run snaked");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("foxglove.token_file"), "{err}");
}

#[test]
fn the_parameters_panel_reads_live_values_and_sets_them_with_the_sockets_checks() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    d.sock.call("gait.set", json!({"gait": "slithering"}));
    // The robot's model is served as an asset: a URDF of the 18 modules.
    let urdf = fx
        .fetch_asset(snaked::record::urdf::URDF_URI)
        .expect("the URDF");
    let urdf = String::from_utf8(urdf).expect("text");
    assert_eq!(urdf.matches("type=\"revolute\"").count(), 18, "{urdf}");
    assert!(fx.fetch_asset("package://snaked/nope.stl").is_err());
    let all = fx.get_parameters(&[]);
    assert_eq!(all["gait"], "slithering");
    assert_eq!(
        all["params.temporal_freq_rad_s"],
        json!(slithering_speed(&mut d.sock))
    );
    assert!(all.contains_key("controller.name"), "{all:?}");
    let now = fx.set_parameters(&[("params.temporal_freq_rad_s", json!(0.6))]);
    assert_eq!(now["params.temporal_freq_rad_s"], json!(0.6));
    assert_eq!(slithering_speed(&mut d.sock), 0.6, "set through params.set");
    // A change made elsewhere (snakectl) reaches a panel that subscribed to updates.
    fx.subscribe_parameters(&["params.temporal_freq_rad_s"]);
    d.sock.call(
        "params.set",
        json!({"gait": "slithering", "temporal_freq_rad_s": 0.7}),
    );
    assert!(
        fx.wait_parameter("params.temporal_freq_rad_s", Duration::from_secs(10), |v| v
            == &json!(0.7)),
        "the update is published"
    );
    // Refused as the socket refuses it: the panel gets an error status and the live value.
    let now = fx.set_parameters(&[("params.amplitude_lat_rad", json!(99.0))]);
    assert!(
        now["params.amplitude_lat_rad"].as_f64().unwrap() < 2.0,
        "{now:?}"
    );
    fx.drain(Duration::from_millis(300));
    assert!(
        fx.statuses.iter().any(|s| s["message"]
            .as_str()
            .is_some_and(|m| m.contains("amplitude_lat_rad"))),
        "{:?}",
        fx.statuses
    );
    // The controller: its name and configuration, set through controller.set.
    let now = fx.set_parameters(&[("controller.name", json!("compliant_slithering"))]);
    assert_eq!(now["controller.name"], "compliant_slithering");
    let c = d.sock.call("controller.get", json!({"gait": "slithering"}));
    assert_eq!(c["controller"]["controller"], "compliant_slithering");
    // /stats is pushed once a second of loop time.
    d.sock
        .wait_status(Duration::from_secs(20), "two seconds of loop", |s| {
            s["t_s"].as_f64().is_some_and(|t| t > 2.1)
        });
    let [events, stats]: [Vec<Value>; 2] =
        d.stop_with(&["/operator", "/stats"]).try_into().unwrap();
    assert!(
        events
            .iter()
            .any(|e| e["action"] == "controller.set" && e["ok"] == true)
    );
    // The recorder's own health rides on /stats: its drops and the viewers connected.
    assert!(
        stats.iter().all(|s| s["recorder"]["dropped"].is_u64()),
        "{:?}",
        stats.last()
    );
    assert!(
        stats.iter().any(|s| s["recorder"]["live_clients"] == 1),
        "{:?}",
        stats.last()
    );
}

#[test]
fn teleop_turns_a_sidewinding_controllers_nominal_heading() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call(
        "controller.set",
        json!({"gait": "sidewinding", "controller": "anti_compliant_sidewinding", "preset": "ac_sfc"}),
    )
    .expect("controller.set");
    fx.call("gait.set", json!({"gait": "sidewinding"}))
        .expect("gait.set");
    d.sock.wait_status(
        Duration::from_secs(30),
        "sidewinding's controller drives",
        |s| {
            s["controller"]["controller"] == "anti_compliant_sidewinding"
                && s["controller"]["state"] == "engaged"
                && s["body"]["valid"] == true
        },
    );
    fx.advertise(1, "/cmd_vel");
    for _ in 0..10 {
        fx.publish(1, &twist(1.0, 1.0));
        fx.drain(Duration::from_millis(100));
    }
    let [events, signals]: [Vec<Value>; 2] = d
        .stop_with(&["/operator", "/controller/signals"])
        .try_into()
        .unwrap();
    let headings: Vec<&Value> = events
        .iter()
        .filter(|e| e["action"] == "controller.heading")
        .collect();
    assert!(
        headings.len() >= 5,
        "each turning twist leads the heading: {events:?}"
    );
    assert!(headings.iter().all(|e| e["ok"] == true), "{headings:?}");
    assert!(
        events
            .iter()
            .filter(|e| e["action"] == "params.set")
            .all(|e| e["params"].get("taper").is_none()),
        "no taper: the controller steers"
    );
    // The controller holds the last heading teleop sent.
    let last = headings.last().unwrap()["params"]["heading_rad"]
        .as_f64()
        .unwrap();
    let nominal = signals
        .iter()
        .rev()
        .find_map(|s| s["signals"]["heading_nominal_rad"].as_f64())
        .expect("the controller reports its nominal heading");
    assert!((nominal - last).abs() < 1e-9, "{nominal} vs {last}");
}

#[test]
fn teleop_takes_over_from_the_navigator() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    d.sock
        .wait_status(Duration::from_secs(20), "a valid estimate", |s| {
            s["body"]["valid"] == true
        });
    d.sock.call("navigate", json!({"heading_rad": 0.0}));
    d.sock
        .wait_status(Duration::from_secs(10), "navigating", |s| {
            s["navigator"]["active"] == true
        });
    fx.advertise(1, "/cmd_vel");
    fx.publish(1, &twist(0.5, 0.0));
    let s = d
        .sock
        .wait_status(Duration::from_secs(10), "navigation stopped", |s| {
            s["navigator"]["active"] == false
        });
    assert_eq!(s["navigator"]["stopped"], "off", "{}", s["navigator"]);
    let events = d.stop();
    assert!(
        events
            .iter()
            .any(|e| e["action"] == "navigate" && e["params"]["off"] == true)
    );
}

#[test]
fn a_viewer_that_cannot_keep_up_is_thinned_and_reported() {
    let d = daemon("");
    let mut slow = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    slow.drain(Duration::from_millis(500));
    slow.subscribe_all();
    // It never reads again: once the socket's buffers and its outbox are full, the
    // server drops its oldest messages, and every viewer is told.
    let mut watcher = FoxgloveClient::connect(d.fox, Duration::from_secs(10));
    assert!(
        watcher.wait_status_message("cannot keep up", Duration::from_secs(30)),
        "statuses seen: {:?}",
        watcher.statuses
    );
    let reports = d.stop_with(&["/live/viewers"]).remove(0);
    assert!(
        reports.iter().any(|r| r["event"] == "thinned"),
        "{reports:?}"
    );
    drop(slow);
}

#[test]
fn teleop_turns_a_slithering_controllers_held_heading_instead_of_fighting_it() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    fx.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega"}),
    )
    .expect("controller.set");
    fx.call("gait.set", json!({"gait": "slithering"}))
        .expect("gait.set");
    d.sock.wait_status(
        Duration::from_secs(30),
        "compliant slithering drives",
        |s| {
            s["controller"]["preset"] == "a_ws_omega"
                && s["controller"]["state"] == "engaged"
                && s["body"]["valid"] == true
        },
    );
    // Holding a heading: the controller steers by it, so teleop's turn moves it.
    d.sock.call(
        "controller.heading",
        json!({"gait": "slithering", "here": true}),
    );
    d.sock.wait_status(Duration::from_secs(10), "holding", |s| {
        s["controller"]["signals"]["steering"]
            .as_f64()
            .is_some_and(|x| x >= 1.0)
    });
    fx.advertise(1, "/cmd_vel");
    for _ in 0..5 {
        fx.publish(1, &twist(1.0, 1.0)); // the speed it has: nothing hands the joints back
        fx.drain(Duration::from_millis(100));
    }
    let events = d.stop();
    let turns: Vec<&Value> = events
        .iter()
        .filter(|e| e["action"] == "controller.heading")
        .collect();
    assert!(
        turns.len() >= 3 && turns.iter().all(|e| e["ok"] == true),
        "{events:?}"
    );
    assert!(
        events
            .iter()
            .filter(|e| e["action"] == "params.set")
            .all(|e| e["params"].get("offset_lat_rad").is_none()),
        "the offset is left to the controller: {events:?}"
    );
}
