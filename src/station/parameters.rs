//! The station's parameters (Foxglove's Parameters panel): the active gait, its
//! parameters and its controller's configuration, read live, set through the control
//! socket's methods (`gait.set`, `params.set`, `controller.set`) with their checks and
//! errors (a refusal is sent to the panel as an error status; the panel then shows the
//! values as they are).
//!
//! Names: `gait` (string), `params.<field>` (the active gait's, numbers),
//! `controller.name`, `controller.preset` (strings) and `controller.config.<path>` (the
//! configuration's numbers, booleans and strings, dotted).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Weak};
use std::time::Duration;

use foxglove::WebSocketServerHandle;
use foxglove::websocket::{
    AnyClient, GetParametersResponder, Parameter, ParameterHandler, ParameterValue,
    SetParametersResponder,
};
use serde_json::{Map, Value, json};

use super::CallError;
use super::services::Operating;

/// The parameter handler.
pub struct Parameters {
    pub operating: Arc<Operating>,
}

/// What the parameters are read from.
struct Live {
    gait: String,
    params: Map<String, Value>,
    controller: Value,
}

async fn live(op: &Operating) -> Result<Live, CallError> {
    let status = op.station.call("station", "status", json!({})).await?;
    let gait = status["gait"].as_str().unwrap_or_default().to_owned();
    let p = op
        .station
        .call("station", "params.get", json!({ "gait": gait }))
        .await?;
    let c = op
        .station
        .call("station", "controller.get", json!({ "gait": gait }))
        .await?;
    Ok(Live {
        params: p["params"].as_object().cloned().unwrap_or_default(),
        controller: c["controller"].clone(),
        gait,
    })
}

fn value_of(v: &Value) -> Option<ParameterValue> {
    match v {
        Value::Bool(b) => Some(ParameterValue::Bool(*b)),
        Value::Number(n) => n.as_f64().map(ParameterValue::Float64),
        Value::String(s) => Some(ParameterValue::String(s.clone())),
        _ => None,
    }
}

fn param(name: String, v: &Value) -> Option<Parameter> {
    Some(match value_of(v)? {
        ParameterValue::Float64(x) => Parameter::float64(name, x),
        ParameterValue::Bool(b) => Parameter::bool(name, b),
        ParameterValue::String(s) => Parameter::string(name, s),
        _ => return None,
    })
}

/// `config`'s leaves as dotted names under `prefix`.
fn flatten(prefix: &str, v: &Value, out: &mut Vec<Parameter>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                flatten(&format!("{prefix}.{k}"), x, out);
            }
        }
        leaf => out.extend(param(prefix.to_owned(), leaf)),
    }
}

fn all(l: &Live) -> Vec<Parameter> {
    let mut out = vec![Parameter::string("gait", l.gait.clone())];
    for (k, v) in &l.params {
        out.extend(param(format!("params.{k}"), v));
    }
    if l.controller.is_object() {
        out.extend(param("controller.name".into(), &l.controller["controller"]));
        out.extend(param("controller.preset".into(), &l.controller["preset"]));
        flatten("controller.config", &l.controller["config"], &mut out);
    }
    out
}

fn json_of(v: &ParameterValue) -> Value {
    match v {
        ParameterValue::Integer(i) => json!(i),
        ParameterValue::Float64(x) => json!(x),
        ParameterValue::Bool(b) => json!(b),
        ParameterValue::String(s) => json!(s),
        ParameterValue::Array(a) => Value::Array(a.iter().map(json_of).collect()),
        ParameterValue::Dict(d) => {
            Value::Object(d.iter().map(|(k, v)| (k.clone(), json_of(v))).collect())
        }
    }
}

/// The socket request setting parameter `name` to `value`, given what is live.
fn request_for(l: &Live, name: &str, value: Value) -> Result<(&'static str, Value), String> {
    if name == "gait" {
        return Ok(("gait.set", json!({ "gait": value })));
    }
    if let Some(field) = name.strip_prefix("params.") {
        let mut p = json!({ "gait": l.gait });
        p[field] = value;
        return Ok(("params.set", p));
    }
    let c = &l.controller;
    if !c.is_object() {
        return Err(format!("{name}: the {} gait has no controller", l.gait));
    }
    let mut sel = json!({ "gait": l.gait, "controller": c["controller"], "preset": c["preset"] });
    match name {
        "controller.name" => {
            sel["controller"] = value;
            sel.as_object_mut().map(|m| m.remove("preset"));
        }
        "controller.preset" => sel["preset"] = value,
        _ => {
            let path = name
                .strip_prefix("controller.config.")
                .ok_or_else(|| format!("no parameter {name:?}"))?;
            let mut config = c["config"].clone();
            let mut at = &mut config;
            for key in path.split('.') {
                at = at.get_mut(key).ok_or_else(|| {
                    format!("no parameter {name:?} in the controller's configuration")
                })?;
            }
            *at = value;
            sel["config"] = config;
        }
    }
    Ok(("controller.set", sel))
}

/// How often subscribed parameters are compared with what is live.
const UPDATE_EVERY: Duration = Duration::from_secs(1);

/// While a client subscribes to parameter updates (`subscribed` names > 0), publishes
/// those whose live value changed (by the panel, `snakectl` or the navigator) once a
/// second; the server sends each client the ones it subscribed to. Runs until aborted.
pub async fn publish_changes(
    op: Arc<Operating>,
    server: Weak<WebSocketServerHandle>,
    subscribed: Arc<AtomicUsize>,
) {
    let mut last: BTreeMap<String, Parameter> = BTreeMap::new();
    let mut tick = tokio::time::interval(UPDATE_EVERY);
    loop {
        tick.tick().await;
        if subscribed.load(Ordering::Relaxed) == 0 {
            last.clear();
            continue;
        }
        let Ok(l) = live(&op).await else { continue };
        let now = all(&l);
        let changed: Vec<Parameter> = now
            .iter()
            .filter(|p| last.get(&p.name) != Some(*p))
            .cloned()
            .collect();
        last = now.into_iter().map(|p| (p.name.clone(), p)).collect();
        if changed.is_empty() {
            continue;
        }
        match server.upgrade() {
            Some(h) => h.publish_parameter_values(changed),
            None => return,
        }
    }
}

impl ParameterHandler for Parameters {
    fn get(
        &self,
        _client: AnyClient,
        names: Vec<String>,
        _id: Option<String>,
        r: GetParametersResponder,
    ) {
        let op = self.operating.clone();
        tokio::spawn(async move {
            let params = match live(&op).await {
                Ok(l) => all(&l),
                Err(e) => {
                    r.client().send_error(format!("parameters: {e}"));
                    Vec::new()
                }
            };
            let wanted = |p: &Parameter| names.is_empty() || names.contains(&p.name);
            r.respond(params.into_iter().filter(wanted).collect());
        });
    }

    fn set(
        &self,
        client: AnyClient,
        parameters: Vec<Parameter>,
        _id: Option<String>,
        r: SetParametersResponder,
    ) {
        let op = self.operating.clone();
        tokio::spawn(async move {
            let id = u32::from(client.id());
            let who = Operating::client_name(id);
            if !op.access.may_operate(id) {
                client.send_error(
                    "parameters: unauthorized: call the `auth` service with the token first",
                );
            } else {
                for p in &parameters {
                    let Some(v) = &p.value else { continue };
                    let l = match live(&op).await {
                        Ok(l) => l,
                        Err(e) => {
                            client.send_error(format!("parameters: {e}"));
                            break;
                        }
                    };
                    let answer = match request_for(&l, &p.name, json_of(v)) {
                        Ok((method, params)) => {
                            let a = op.station.call(&who, method, params.clone()).await;
                            let logged = a.clone().map_err(|e| e.to_string());
                            op.actions.log(&who, method, &params, &logged);
                            if let Err(e) = &a {
                                tracing::warn!("station: {who}'s {method} refused: {e}");
                            }
                            a.map(drop).map_err(|e| e.to_string())
                        }
                        Err(e) => Err(e),
                    };
                    if let Err(e) = answer {
                        client.send_error(format!("parameter {}: {e}", p.name));
                    }
                }
            }
            // What is live now, for the names asked about.
            let now = live(&op).await.map(|l| all(&l)).unwrap_or_default();
            let asked = |q: &Parameter| parameters.iter().any(|p| p.name == q.name);
            r.respond(now.into_iter().filter(asked).collect());
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn live() -> Live {
        Live {
            gait: "slithering".into(),
            params: json!({"temporal_freq_rad_s": 1.0})
                .as_object()
                .cloned()
                .unwrap(),
            controller: json!({"controller": "compliant_slithering", "preset": "a_ws_omega",
                "config": {"amplitude": {"enabled": true, "gains": {"min": 0.2}}}}),
        }
    }

    #[test]
    fn parameters_are_named_and_set_through_the_socket_methods() {
        let l = live();
        let names: Vec<String> = all(&l).into_iter().map(|p| p.name).collect();
        assert_eq!(
            names,
            [
                "gait",
                "params.temporal_freq_rad_s",
                "controller.name",
                "controller.preset",
                "controller.config.amplitude.enabled",
                "controller.config.amplitude.gains.min",
            ]
        );
        assert_eq!(
            request_for(&l, "gait", json!("rolling")).unwrap(),
            ("gait.set", json!({"gait": "rolling"}))
        );
        let (m, p) = request_for(&l, "params.temporal_freq_rad_s", json!(0.5)).unwrap();
        assert_eq!(
            (m, p),
            (
                "params.set",
                json!({"gait": "slithering", "temporal_freq_rad_s": 0.5})
            )
        );
        let (m, p) = request_for(&l, "controller.config.amplitude.gains.min", json!(0.3)).unwrap();
        assert_eq!(m, "controller.set");
        assert_eq!(p["config"]["amplitude"]["gains"]["min"], 0.3);
        assert_eq!(p["config"]["amplitude"]["enabled"], true, "the rest kept");
        assert_eq!(p["preset"], "a_ws_omega");
        let (_, p) = request_for(&l, "controller.name", json!("open_loop")).unwrap();
        assert_eq!(p, json!({"gait": "slithering", "controller": "open_loop"}));
        assert!(request_for(&l, "controller.config.nope", json!(1)).is_err());
        assert!(request_for(&l, "whatever", json!(1)).is_err());
    }
}
