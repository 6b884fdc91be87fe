//! The station's parameters (Foxglove's Parameters panel): the operator's parameters
//! (`operator::parameters`: names, values, the acts that set them) as the panel's. A
//! refusal is sent to the panel as an error status; the panel then shows the values as
//! they are. Changes made elsewhere reach subscribed panels from the loop's snapshots as
//! they come (`Operator::subscribe`).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Weak};
use std::time::Duration;

use foxglove::WebSocketServerHandle;
use foxglove::websocket::{
    AnyClient, GetParametersResponder, Parameter, ParameterHandler, ParameterValue,
    SetParametersResponder,
};
use serde_json::{Value, json};

use super::services::Operating;
use crate::operator::OperatorError;
use crate::operator::parameters::LiveParameters;

/// The parameter handler.
pub struct Parameters {
    pub operating: Arc<Operating>,
}

/// The live parameters, once the operator API is bound.
fn live(op: &Operating) -> Result<LiveParameters, OperatorError> {
    Ok(LiveParameters::read(op.station.operator()?))
}

fn param(name: String, v: &Value) -> Option<Parameter> {
    Some(match v {
        Value::Bool(b) => Parameter::bool(name, *b),
        Value::Number(n) => Parameter::float64(name, n.as_f64()?),
        Value::String(s) => Parameter::string(name, s.clone()),
        _ => return None,
    })
}

fn all(l: &LiveParameters) -> Vec<Parameter> {
    l.all()
        .into_iter()
        .filter_map(|(n, v)| param(n, &v))
        .collect()
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
                    let answer = match l.act_for(&p.name, json_of(v)) {
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
