//! The station's services: one per control-socket method an operator changes state
//! with, plus `auth` (give the token) and `status` (read). A call's request is the
//! method's params as a JSON object (empty: none); its answer is what the socket
//! answers, the result as JSON or the failure `error CODE: message`. `estop` needs no
//! token: whoever sees the robot may stop it.

use std::sync::Arc;

use foxglove::Schema;
use foxglove::websocket::service::{Request, Service, ServiceSchema};
use serde_json::{Value, json};

use super::Station;
use super::access::Access;
use super::actions::Actions;
use crate::operator::{Act, Done, OperatorError, code};

/// The services, in the order they are advertised.
pub const SERVICES: [&str; 15] = [
    "auth",
    "status",
    "take_over",
    "gait.set",
    "gait.stop",
    "gait.resume",
    "params.set",
    "controller.set",
    "controller.heading",
    "controller.calibrate",
    "navigate",
    "hold",
    "limp",
    "arm",
    "estop",
];

/// Methods anyone connected may call.
const OPEN: [&str; 3] = ["auth", "status", "estop"];

/// What every service handler shares.
pub struct Operating {
    pub station: Station,
    pub access: Access,
    pub actions: Actions,
}

impl Operating {
    /// The name a client goes by in the recording.
    pub fn client_name(client: u32) -> String {
        format!("foxglove client {client}")
    }

    /// Carries out `method` for `client` (privilege checked), logs it, answers.
    pub async fn call(
        &self,
        client: u32,
        method: &str,
        params: Value,
    ) -> Result<Value, OperatorError> {
        let name = Self::client_name(client);
        if method != "auth" && (OPEN.contains(&method) || self.access.may_operate(client)) {
            return self.call_as(&name, method, params).await;
        }
        let answer = if method == "auth" {
            self.auth(client, &params).await
        } else {
            Err(OperatorError {
                code: code::UNAUTHORIZED,
                message: "unauthorized: call the `auth` service with the token first".into(),
            })
        };
        let shown = if method == "auth" { json!({}) } else { params };
        self.log(&name, method, &shown, &answer);
        answer
    }

    /// Carries out `method` as `who`, who may operate; logs it (but `status`), answers.
    pub async fn call_as(
        &self,
        who: &str,
        method: &str,
        params: Value,
    ) -> Result<Value, OperatorError> {
        let answer = self.station.call_json(who, method, &params).await;
        if method != "status" {
            self.log(who, method, &params, &answer);
        }
        answer
    }

    fn log(&self, who: &str, method: &str, params: &Value, answer: &Result<Value, OperatorError>) {
        let logged = answer.clone().map_err(|e| e.to_string());
        self.actions.log(who, method, params, &logged);
        if let Err(e) = answer {
            tracing::warn!("station: {who}'s {method} refused: {e}");
        }
    }

    /// Carries a typed `act` out as `who` (teleop, the Parameters panel) and records it
    /// on `/operator` as the socket's method with its params and answer; a refusal is
    /// logged, `what` naming where it came from ("teleop ", or "").
    pub async fn act_logged(&self, who: &str, what: &str, act: Act) -> Result<Done, OperatorError> {
        let (method, params) = (act.method(), crate::socket::act_params(&act));
        let answer = self.station.act(who, act).await;
        let logged = match (&answer, self.station.operator()) {
            (Ok(done), Ok(api)) => Ok(crate::socket::answer_json(api, done.clone())),
            (Err(e), _) => Err(e.to_string()),
            (Ok(_), Err(e)) => Err(e.to_string()),
        };
        self.actions.log(who, method, &params, &logged);
        if let Err(e) = &answer {
            tracing::warn!("station: {who}'s {what}{method} refused: {e}");
        }
        answer
    }

    async fn auth(&self, client: u32, params: &Value) -> Result<Value, OperatorError> {
        let bad = |message: &str| OperatorError {
            code: code::INVALID_PARAMS,
            message: message.into(),
        };
        let obj = params
            .as_object()
            .ok_or_else(|| bad("params must be an object"))?;
        if let Some(extra) = obj.keys().find(|k| *k != "token") {
            return Err(bad(&format!(
                "unknown param `{extra}` (auth takes `token`)"
            )));
        }
        let token = obj
            .get("token")
            .and_then(Value::as_str)
            .ok_or_else(|| bad("missing `token` (a string)"))?;
        match self.access.authenticate(client, token) {
            Ok(()) => Ok(json!({ "authorized": true })),
            Err(why) => {
                // Guessing costs a client a second a try, and a few tries in all.
                tokio::time::sleep(crate::station::access::FAILURE_DELAY).await;
                Err(OperatorError {
                    code: code::UNAUTHORIZED,
                    message: format!("unauthorized: {why}"),
                })
            }
        }
    }
}

/// A request's payload as a params object (empty: `{}`).
fn params_of(payload: &[u8]) -> Result<Value, OperatorError> {
    let text = std::str::from_utf8(payload).map_err(|_| OperatorError {
        code: code::INVALID_PARAMS,
        message: "the request is not UTF-8 JSON".into(),
    })?;
    if text.trim().is_empty() {
        return Ok(json!({}));
    }
    let v: Value = serde_json::from_str(text).map_err(|e| OperatorError {
        code: code::PARSE_ERROR,
        message: format!("the request is not JSON: {e}"),
    })?;
    if !v.is_object() {
        return Err(OperatorError {
            code: code::INVALID_PARAMS,
            message: "the request is a params object".into(),
        });
    }
    Ok(v)
}

/// Every service, bound to `operating`.
pub fn services(operating: &Arc<Operating>) -> Vec<Service> {
    let schema = |method: &str| {
        let any = Schema::new(
            format!("snaked.{method}"),
            "jsonschema",
            br#"{"type":"object"}"#.as_slice(),
        );
        ServiceSchema::new(format!("snaked.{method}"))
            .with_request("json", any.clone())
            .with_response("json", any)
    };
    SERVICES
        .iter()
        .map(|&method| {
            let op = operating.clone();
            Service::builder(method, schema(method)).async_handler_fn(move |req: Request| {
                let op = op.clone();
                async move {
                    let client = u32::from(req.client_id());
                    let params = params_of(req.payload())?;
                    let v = op.call(client, method, params).await?;
                    Ok::<Vec<u8>, OperatorError>(v.to_string().into_bytes())
                }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_is_a_params_object() {
        assert_eq!(params_of(b"").unwrap(), json!({}));
        assert_eq!(
            params_of(br#"{"gait":"rolling"}"#).unwrap()["gait"],
            "rolling"
        );
        assert_eq!(params_of(b"[1]").unwrap_err().code, code::INVALID_PARAMS);
        assert_eq!(params_of(b"{").unwrap_err().code, code::PARSE_ERROR);
        assert_eq!(params_of(&[0xff]).unwrap_err().code, code::INVALID_PARAMS);
    }
}
