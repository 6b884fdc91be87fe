//! Who may operate: the token, per client; e-stop always; refused off loopback.
use super::{daemon, slithering_speed};
use crate::support::foxglove_ws::{FoxgloveClient, twist};
use crate::support::rig::exe;

use std::time::Duration;

use serde_json::{Value, json};

#[test]
fn with_a_token_a_client_operates_only_after_giving_it_and_estop_is_always_reachable() {
    let dir = tempfile::tempdir().unwrap();
    let token = dir.path().join("token");
    std::fs::write(&token, "correct-horse-battery\n").unwrap();
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
    fx.call("auth", json!({"token": "correct-horse-battery"}))
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
