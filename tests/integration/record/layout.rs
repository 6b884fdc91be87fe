//! The shipped Foxglove layout (`docs/foxglove/snaked.layout.json`) against what the
//! daemon serves: every panel placed and every placed panel configured, every topic one
//! the recorder or the station publishes, every service one the station offers, the
//! teleop panel publishing faster than the dead-man expires, every message path's fields
//! in its topic's schema, and the signals it plots ones the controllers report.
use std::collections::BTreeSet;

use serde_json::Value;
use snaked::controllers::steering::HeadingHold;
use snaked::record::Topic;
use snaked::station::TeleopConfig;
use snaked::station::services::SERVICES;

fn layout() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/foxglove/snaked.layout.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).expect("the layout")).expect("JSON")
}

fn placed(node: &Value, out: &mut BTreeSet<String>) {
    match node {
        Value::String(id) => {
            out.insert(id.clone());
        }
        Value::Object(m) => {
            placed(&m["first"], out);
            placed(&m["second"], out);
        }
        other => panic!("a layout node is a panel id or a split: {other}"),
    }
}

/// The topic of a message path (`/joints.torque_nm[0]` → `/joints`).
fn topic_of(path: &str) -> &str {
    path.split(['.', '[']).next().unwrap_or(path)
}

/// Whether the fields of a message path (`.world.position_m[0]`, `.fields[0].windows[:]`)
/// are in the topic's JSON schema: each name a property (or one of a map's
/// `additionalProperties`), each index an array's items.
fn schema_has(schema: &Value, fields: &str) -> bool {
    let mut s = schema;
    for part in fields.split('.').filter(|p| !p.is_empty()) {
        let (name, indices) = part.split_once('[').unwrap_or((part, ""));
        if !name.is_empty() {
            match s.get("properties").and_then(|p| p.get(name)) {
                Some(next) => s = next,
                None => match s.get("additionalProperties") {
                    Some(next) if next.is_object() => s = next,
                    _ => return false,
                },
            }
        }
        for _ in indices.matches(']') {
            match s.get("items") {
                Some(items) => s = items,
                None => return false,
            }
        }
    }
    true
}

#[test]
fn the_layout_shows_what_the_daemon_serves() {
    let l = layout();
    let configs = l["configById"].as_object().expect("configById");
    let mut ids = BTreeSet::new();
    placed(&l["layout"], &mut ids);
    let configured: BTreeSet<String> = configs.keys().cloned().collect();
    assert_eq!(
        ids, configured,
        "every panel placed, every placed panel configured"
    );

    let mut topics: BTreeSet<String> = Topic::ALL.iter().map(|t| t.name().to_owned()).collect();
    topics.insert(snaked::station::actions::TOPIC.to_owned());
    let teleop = TeleopConfig::default();
    let mut paths = Vec::new();
    for (id, c) in configs {
        let kind = id.split('!').next().unwrap();
        match kind {
            "Plot" | "StateTransitions" => {
                for p in c["paths"].as_array().expect("paths") {
                    paths.push(p["value"].as_str().expect("a path").to_owned());
                }
            }
            "RawMessages" => paths.push(c["topicPath"].as_str().unwrap().to_owned()),
            "3D" => {
                for t in c["topics"].as_object().unwrap().keys() {
                    paths.push(t.clone());
                }
                let urdf = &c["layers"]["snake-urdf"];
                assert_eq!(urdf["url"], snaked::record::urdf::URDF_URI);
            }
            "CallService" => {
                let s = c["serviceName"].as_str().unwrap();
                assert!(SERVICES.contains(&s), "{id}: no service {s}");
                let payload = c["requestPayload"].as_str().unwrap();
                assert!(
                    serde_json::from_str::<Value>(payload).unwrap().is_object(),
                    "{id}"
                );
            }
            "Teleop" => {
                assert_eq!(c["topic"], teleop.topic.as_str());
                let rate = c["publishRate"].as_f64().unwrap();
                assert!(
                    rate > 2.0 / teleop.timeout_s,
                    "{rate} Hz outruns the dead-man"
                );
            }
            "Parameters" => {}
            other => panic!("{id}: a panel kind the test does not know ({other})"),
        }
    }
    for p in &paths {
        assert!(
            topics.contains(topic_of(p)),
            "{p}: no such topic; served: {topics:?}"
        );
        // The fields too, where the topic is one of the daemon's JSON ones.
        let schema = Topic::ALL
            .iter()
            .find(|t| t.name() == topic_of(p))
            .and_then(|t| t.json_schema());
        if let Some(schema) = schema {
            let fields = &p[topic_of(p).len()..];
            assert!(
                schema_has(&schema, fields),
                "{p}: no such field in {schema}"
            );
        }
    }
    let steering: Vec<&str> = HeadingHold::SIGNALS.iter().map(|s| s.0).collect();
    for p in paths
        .iter()
        .filter_map(|p| p.strip_prefix("/controller/signals.signals."))
    {
        assert!(
            steering.contains(&p) || p == "amplitude_mean_rad",
            "signal {p}"
        );
    }
}
