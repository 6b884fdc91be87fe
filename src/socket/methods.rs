//! The methods: reads answered from the latest snapshot, acts read into the operator
//! API's typed requests (`super::wire`) and carried out by the API as the connection's
//! client, the answer written as JSON. The Foxglove station's services use the same
//! path ([`call_json`]), so both edges answer alike.
use serde_json::{Value, json};

use super::api::{OperatorError, Params, code};
use super::controller_views;
use super::session::Session;
use super::shared::Shared;
use super::views;
use super::wire;
use crate::operator::Operator;

/// Every method the server knows (listed in the unknown-method error).
pub const METHODS: [&str; 24] = [
    "auth",
    "status",
    "gait.list",
    "gait.set",
    "gait.stop",
    "gait.resume",
    "take_over",
    "params.get",
    "params.set",
    "controller.list",
    "controller.get",
    "controller.set",
    "controller.calibrate",
    "controller.heading",
    "navigate",
    "pose.external",
    "hold",
    "limp",
    "estop",
    "arm",
    "stats",
    "telemetry.subscribe",
    "telemetry.unsubscribe",
    "ping",
];

/// Methods of a connection itself, not of the operator API.
const CONNECTION_ONLY: [&str; 3] = ["auth", "telemetry.subscribe", "telemetry.unsubscribe"];

/// Telemetry stream rate limits and default, Hz.
pub const RATE_RANGE_HZ: (f64, f64) = (1.0, 200.0);
pub const DEFAULT_RATE_HZ: f64 = 10.0;

pub(crate) async fn dispatch(
    shared: &Shared,
    session: &mut Session,
    method: &str,
    mut p: Params,
) -> Result<Value, OperatorError> {
    if !session.authorized() && method != "auth" {
        return Err(OperatorError::new(
            code::UNAUTHORIZED,
            "unauthorized: a TCP client sends `auth` with the token first",
        ));
    }
    match method {
        "auth" => auth(shared, session, p).await,
        "telemetry.subscribe" => {
            let (min, max) = RATE_RANGE_HZ;
            let rate_hz = p
                .take_f64_in("rate_hz", min, max)?
                .unwrap_or(DEFAULT_RATE_HZ);
            p.finish(&["rate_hz"])?;
            // Started by the connection once this answer is queued, so it comes first.
            session.subscribe_after_answer(rate_hz);
            Ok(json!({ "subscribed": true, "rate_hz": rate_hz }))
        }
        "telemetry.unsubscribe" => {
            p.finish(&[])?;
            let dropped = session.unsubscribe().await;
            Ok(json!({ "subscribed": false, "dropped": dropped }))
        }
        _ => call(&shared.op, session.who(), method, p).await,
    }
}

/// `method` with `params` (a JSON object) for the client `who`, as a socket
/// connection's request is carried out: the Foxglove station's services.
pub async fn call_json(
    op: &Operator,
    who: &str,
    method: &str,
    params: &Value,
) -> Result<Value, OperatorError> {
    if CONNECTION_ONLY.contains(&method) {
        return Err(OperatorError::new(
            code::METHOD_NOT_FOUND,
            format!("`{method}` belongs to a socket connection"),
        ));
    }
    call(op, who, method, Params::from_value(params)?).await
}

/// A read, or an act carried out by the API; its answer as JSON.
async fn call(op: &Operator, who: &str, method: &str, p: Params) -> Result<Value, OperatorError> {
    if READS.contains(&method) {
        return read(op, method, p);
    }
    if method == "pose.external" {
        return super::pose_method::call(op, who, p);
    }
    let act = wire::parse_act(op, method, p)?;
    let done = op.act(who, act).await?;
    Ok(wire::answer_json(op, done))
}

/// The methods that only read.
const READS: [&str; 7] = [
    "ping",
    "status",
    "gait.list",
    "params.get",
    "controller.list",
    "controller.get",
    "stats",
];

/// A reading method's answer from the latest snapshot.
fn read(op: &Operator, method: &str, mut p: Params) -> Result<Value, OperatorError> {
    let v = match method {
        "ping" => {
            p.finish(&[])?;
            json!({ "pong": true })
        }
        "status" => {
            p.finish(&[])?;
            let mut v = views::status(&op.snapshot(), op.info(), op.catalog());
            v["driver"] = views::driver(op.driver().as_ref());
            v["record"] = op.record();
            v
        }
        "gait.list" => {
            p.finish(&[])?;
            views::gait_list(&op.snapshot())
        }
        "params.get" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            let s = op.snapshot();
            views::params(&s.params, s.blend_time_s, gait)
        }
        "controller.list" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            controller_views::list(op, gait)
        }
        "controller.get" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            controller_views::get(op, gait)
        }
        "stats" => {
            p.finish(&[])?;
            let mut v = views::stats(&op.snapshot());
            v["record"] = op.record();
            v
        }
        _ => unreachable!("READS lists the reads"),
    };
    Ok(v)
}

/// A wrong token is answered after this long, and the connection closed after
/// [`MAX_FAILED_AUTHS`] of them: guessing costs a connection a second a try.
pub const AUTH_FAILURE_DELAY: std::time::Duration = std::time::Duration::from_secs(1);
pub const MAX_FAILED_AUTHS: u32 = 3;

async fn auth(
    shared: &Shared,
    session: &mut Session,
    mut p: Params,
) -> Result<Value, OperatorError> {
    let token = p.take_str("token")?.ok_or_else(|| wire::missing("token"))?;
    p.finish(&["token"])?;
    let ok = shared.tcp_token.as_deref().is_some_and(|t| {
        use subtle::ConstantTimeEq;
        bool::from(t.as_bytes().ct_eq(token.as_bytes()))
    });
    if !ok && !session.authorized() {
        session.failed_auths += 1;
        tracing::warn!(
            "{}: wrong token ({} of {MAX_FAILED_AUTHS})",
            session.who(),
            session.failed_auths
        );
        tokio::time::sleep(AUTH_FAILURE_DELAY).await;
        return Err(OperatorError::new(
            code::UNAUTHORIZED,
            if session.failed_auths >= MAX_FAILED_AUTHS {
                "unauthorized: wrong token; too many wrong tokens, closing"
            } else {
                "unauthorized: wrong token"
            },
        ));
    }
    session.set_authorized(true);
    Ok(json!({ "authorized": true }))
}

#[cfg(test)]
mod docs_tests {
    /// The README and the socket's reference name every method the socket answers.
    #[test]
    fn every_method_is_documented() {
        let readme = include_str!("../../README.md");
        let reference = include_str!("../../docs/control-socket.md");
        for m in super::METHODS {
            let quoted = format!("`{m}`");
            assert!(readme.contains(&quoted), "README.md does not list {quoted}");
            assert!(
                reference.contains(&quoted),
                "docs/control-socket.md does not name {quoted}"
            );
        }
    }
}
