//! The station's parameters (Foxglove's Parameters panel): the active gait, its
//! parameters and its controller's configuration, read live, set through the control
//! operator API's typed acts (`Act::SetGait`, `Act::SetParams`, `Act::SetController`)
//! with their checks and errors (a refusal is sent to the panel as an error status; the
//! panel then shows the values as they are). Changes made elsewhere reach subscribed
//! panels from the loop's snapshots as they come (`Operator::subscribe`).
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

use super::services::Operating;
use crate::controller_interface::Selection;
use crate::gait::params::Field;
use crate::gait::{GaitKind, ParamPatch};
use crate::operator::{Act, OperatorError};

/// The parameter handler.
pub struct Parameters {
    pub operating: Arc<Operating>,
}

/// What the parameters are read from.
struct Live {
    gait: GaitKind,
    params: Map<String, Value>,
    /// The gait's controller: `controller`, `preset`, `config` (null without one).
    controller: Value,
}

/// The active gait, its parameters and its controller, from the loop's snapshot.
fn live(op: &Operating) -> Result<Live, OperatorError> {
    let api = op.station.operator()?;
    let s = api.snapshot();
    let gait = s.gait;
    let params = match serde_json::to_value(s.params.get(gait)) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    };
    let controller = match api.installed(gait) {
        Some(i) => json!({ "controller": i.controller, "preset": i.preset, "config": i.config }),
        None => Value::Null,
    };
    Ok(Live {
        gait,
        params,
        controller,
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
    let mut out = vec![Parameter::string("gait", l.gait.name())];
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

/// The act setting parameter `name` to `value`, given what is live.
fn act_for(l: &Live, name: &str, value: Value) -> Result<Act, String> {
    if name == "gait" {
        let gait = value
            .as_str()
            .and_then(GaitKind::from_name)
            .ok_or_else(|| format!("gait: not a gait: {value}"))?;
        return Ok(Act::SetGait { gait });
    }
    if let Some(field) = name.strip_prefix("params.") {
        let field = Field::ALL
            .into_iter()
            .find(|f| f.name() == field)
            .ok_or_else(|| format!("no parameter {name:?}"))?;
        let x = value
            .as_f64()
            .ok_or_else(|| format!("{name} must be a number, not {value}"))?;
        let mut patch = ParamPatch::default();
        field.set_in_patch(&mut patch, x);
        return Ok(Act::SetParams {
            gait: l.gait,
            patch,
        });
    }
    let c = &l.controller;
    if !c.is_object() {
        return Err(format!(
            "{name}: the {} gait has no controller",
            l.gait.name()
        ));
    }
    let text = |v: &Value| v.as_str().map(str::to_owned);
    let mut sel = Selection {
        controller: text(&c["controller"]).unwrap_or_default(),
        preset: text(&c["preset"]),
        config: None,
    };
    match name {
        "controller.name" => {
            sel.controller = text(&value).ok_or_else(|| format!("{name} must be a string"))?;
            sel.preset = None;
        }
        "controller.preset" => {
            sel.preset = Some(text(&value).ok_or_else(|| format!("{name} must be a string"))?);
        }
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
            sel.config = Some(config);
        }
    }
    Ok(Act::SetController {
        gait: l.gait,
        selection: sel,
        patch: ParamPatch::default(),
    })
}

/// Parameter updates go out at most this often.
const UPDATE_EVERY: Duration = Duration::from_millis(100);

/// While a client subscribes to parameter updates (`subscribed` names > 0), publishes
/// those whose live value changed (by the panel, `snakectl` or the navigator) as the
/// loop's snapshots show them (at most every [`UPDATE_EVERY`]); the server sends each
/// client the ones it subscribed to. Runs until aborted.
pub async fn publish_changes(
    op: Arc<Operating>,
    server: Weak<WebSocketServerHandle>,
    subscribed: Arc<AtomicUsize>,
) {
    let mut last: BTreeMap<String, Parameter> = BTreeMap::new();
    // The operator API is bound once the control socket runs.
    let mut snapshots = loop {
        if let Ok(api) = op.station.operator() {
            break api.subscribe(UPDATE_EVERY);
        }
        tokio::time::sleep(UPDATE_EVERY).await;
    };
    loop {
        if snapshots.changed().await.is_err() {
            return; // The API stopped.
        }
        if subscribed.load(Ordering::Relaxed) == 0 {
            last.clear();
            continue;
        }
        let Ok(l) = live(&op) else { continue };
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
            let params = match live(&op) {
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
                    let l = match live(&op) {
                        Ok(l) => l,
                        Err(e) => {
                            client.send_error(format!("parameters: {e}"));
                            break;
                        }
                    };
                    let answer = match act_for(&l, &p.name, json_of(v)) {
                        Ok(act) => op
                            .act_logged(&who, "", act)
                            .await
                            .map_err(|e| e.to_string()),
                        Err(e) => Err(e),
                    };
                    if let Err(e) = answer {
                        client.send_error(format!("parameter {}: {e}", p.name));
                    }
                }
            }
            // What is live now, for the names asked about.
            let now = live(&op).map(|l| all(&l)).unwrap_or_default();
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
            gait: GaitKind::Slithering,
            params: json!({"temporal_freq_rad_s": 1.0})
                .as_object()
                .cloned()
                .unwrap(),
            controller: json!({"controller": "compliant_slithering", "preset": "a_ws_omega",
                "config": {"amplitude": {"enabled": true, "gains": {"min": 0.2}}}}),
        }
    }

    /// An act as the socket's method and params.
    fn request_for(l: &Live, name: &str, value: Value) -> Result<(&'static str, Value), String> {
        act_for(l, name, value).map(|a| (a.method(), crate::socket::act_params(&a)))
    }

    #[test]
    fn parameters_are_named_and_set_through_the_operator_s_acts() {
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
        assert_eq!(
            p,
            json!({"gait": "slithering", "controller": "open_loop", "preset": null, "config": null})
        );
        assert!(request_for(&l, "controller.config.nope", json!(1)).is_err());
        assert!(request_for(&l, "whatever", json!(1)).is_err());
        assert!(request_for(&l, "params.temporal_freq_rad_s", json!("fast")).is_err());
    }
}
