//! One operator drives at a time (the drive lease) and guessing the TCP token is slow:
//! issue 44's points 3 and 8 on the socket, against the real server and a fake loop.
use crate::support::socket;

use std::time::{Duration, Instant};

use serde_json::json;
use snaked::socket::ServerConfig;
use snaked::socket::api::code;
use snaked::socket::client::{Client, Endpoint};
use socket::{Harness, LoopSpec, call, error_code, error_message, fake_loop};

#[test]
fn the_first_to_drive_holds_the_drive_until_it_stops_leaves_or_lapses() {
    let h = Harness::new(LoopSpec::default(), |c| {
        c.driver_timeout = Duration::from_millis(800)
    });
    let (mut a, mut b) = (h.client(), h.client());
    let rolling = json!({"gait": "rolling"});
    assert!(call(&mut a, "gait.set", rolling.clone())["result"].is_object());
    // B may read, but not drive; its refusal names A and the way out.
    assert!(call(&mut b, "status", json!({}))["result"].is_object());
    let refused = call(
        &mut b,
        "params.set",
        json!({"gait": "rolling", "temporal_freq_rad_s": 1.0}),
    );
    assert_eq!(error_code(&refused), code::DRIVEN_BY_OTHER, "{refused}");
    let why = error_message(&refused);
    assert!(
        why.contains("unix client") && why.contains("take_over"),
        "{why}"
    );
    let status = call(&mut b, "status", json!({}));
    let driver = status["result"]["driver"]["client"]
        .as_str()
        .unwrap()
        .to_owned();
    assert!(why.contains(&driver), "{why} names {driver}");
    // Anyone may stop the robot; the drive is free afterwards.
    assert_eq!(call(&mut b, "hold", json!({}))["result"]["ok"], true);
    assert!(call(&mut b, "gait.set", rolling.clone())["result"].is_object());
    assert_eq!(
        error_code(&call(&mut a, "gait.set", rolling.clone())),
        code::DRIVEN_BY_OTHER
    );
    // B leaves: the drive is free.
    drop(b);
    let deadline = Instant::now() + Duration::from_secs(5);
    while call(&mut a, "status", json!({}))["result"]["driver"] != json!(null) {
        assert!(Instant::now() < deadline, "a departed driver is forgotten");
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(call(&mut a, "gait.set", rolling.clone())["result"].is_object());
    // A lapses after the timeout without driving.
    let mut c = h.client();
    assert_eq!(
        error_code(&call(&mut c, "arm", json!({}))),
        code::DRIVEN_BY_OTHER
    );
    std::thread::sleep(Duration::from_millis(900));
    assert!(call(&mut c, "arm", json!({}))["result"].is_object());
    // Taking over is explicit and says from whom.
    let status = call(&mut a, "status", json!({}));
    let c_name = status["result"]["driver"]["client"].clone();
    assert_ne!(c_name, driver_name_of(&driver), "C drives now");
    let t = call(&mut a, "take_over", json!({}));
    assert_eq!(t["result"]["taken_from"], c_name, "{t}");
    assert_eq!(
        error_code(&call(&mut c, "gait.resume", json!({}))),
        code::DRIVEN_BY_OTHER
    );
    // A stop is never refused, whoever drives.
    assert_eq!(
        call(&mut c, "gait.stop", json!({"within_s": 0.2}))["result"]["motion"],
        "stopping"
    );
    assert!(call(&mut c, "gait.resume", json!({}))["result"].is_object());
}

fn driver_name_of(name: &str) -> serde_json::Value {
    json!(name)
}

#[test]
fn a_wrong_tcp_token_costs_a_second_and_the_third_closes_the_connection() {
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: None,
        tcp_port: Some(0),
        tcp_token: Some("correct-horse-battery-staple".into()),
        ..ServerConfig::default()
    };
    let server = snaked::socket::start(cfg, handle).unwrap();
    let addr = server.tcp_addr().unwrap();
    let mut c = Client::connect(
        &Endpoint::Tcp(addr.to_string()),
        Some(Duration::from_secs(10)),
    )
    .unwrap();
    let start = Instant::now();
    for k in 1..=3 {
        let e = call(&mut c, "auth", json!({"token": "guess"}));
        assert_eq!(error_code(&e), code::UNAUTHORIZED, "{e}");
        if k == 3 {
            assert!(error_message(&e).contains("closing"), "{e}");
        }
    }
    assert!(
        start.elapsed() >= Duration::from_secs(3),
        "each wrong token is answered after a second: {:?}",
        start.elapsed()
    );
    assert!(
        c.call("status", None).is_err(),
        "the connection is closed after the third"
    );
    server.shutdown();
}
