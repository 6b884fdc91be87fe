//! Tuning from Foxglove: the Parameters panel and the robot's model asset.
use super::{daemon, slithering_speed};
use crate::support::foxglove_ws::FoxgloveClient;

use std::time::Duration;

use serde_json::{Value, json};

#[test]
fn the_parameters_panel_reads_live_values_and_sets_them_with_the_sockets_checks() {
    let mut d = daemon("");
    let mut fx = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    d.once().call("gait.set", json!({"gait": "slithering"}));
    // The server frees that connection's drive once it has seen it close.
    d.sock
        .wait_status(Duration::from_secs(5), "the drive freed", |s| {
            s["driver"].is_null()
        });
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
    // A change made elsewhere (snakectl, taking the drive over from the panel's
    // client) reaches a panel that subscribed to updates.
    fx.subscribe_parameters(&["params.temporal_freq_rad_s"]);
    let mut snakectl = d.once();
    snakectl.call("take_over", json!({}));
    snakectl.call(
        "params.set",
        json!({"gait": "slithering", "temporal_freq_rad_s": 0.7}),
    );
    drop(snakectl);
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
