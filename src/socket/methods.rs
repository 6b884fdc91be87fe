//! The methods: validate params completely on the async side, then either answer
//! from the latest snapshot or hand one request to the loop and wait for its ack.
use std::sync::Arc;

use serde_json::{Value, json};

use super::api::{PATCH_FIELDS, Params, RpcError, code};
use super::controllers;
use super::driver;
use super::navigate;
use super::session::Session;
use super::shared::Shared;
use super::views;
use crate::controller_interface::Selection;
use crate::gait::{BLEND_TIME_RANGE_S, GaitKind, ParamPatch};
use crate::rt::gait_clock::{DEFAULT_STOP_S, STOP_TIME_RANGE_S};
use crate::rt::messages::LoopRequest;

/// Every method the server knows (listed in the unknown-method error).
pub const METHODS: [&str; 23] = [
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
    "hold",
    "limp",
    "estop",
    "arm",
    "stats",
    "telemetry.subscribe",
    "telemetry.unsubscribe",
    "ping",
];

/// Telemetry stream rate limits and default, Hz.
pub const RATE_RANGE_HZ: (f64, f64) = (1.0, 200.0);
pub const DEFAULT_RATE_HZ: f64 = 10.0;

pub(crate) async fn dispatch(
    shared: &Arc<Shared>,
    session: &mut Session,
    method: &str,
    mut p: Params,
) -> Result<Value, RpcError> {
    if !session.authorized() && method != "auth" {
        return Err(RpcError::new(
            code::UNAUTHORIZED,
            "unauthorized: a TCP client sends `auth` with the token first",
        ));
    }
    let now = std::time::Instant::now();
    // Stopping the navigator stops driving: anyone may.
    let navigation_off = method == "navigate" && p.contains("off");
    if driver::DRIVING.contains(&method) && !navigation_off {
        shared.driver.claim(session.who(), now)?;
    }
    if navigate::TAKES_OVER.contains(&method) {
        navigate::operator_takes_over(shared);
    }
    if driver::STOPPING.contains(&method) {
        // Whoever stops the robot frees the drive; the stop itself is never refused.
        shared.driver.stopped();
    }
    match method {
        "auth" => auth(shared, session, p).await,
        "ping" => {
            p.finish(&[])?;
            Ok(json!({ "pong": true }))
        }
        "status" => {
            p.finish(&[])?;
            let mut v = views::status(&shared.telemetry.latest(), &shared.info, &shared.catalog);
            v["driver"] = views::driver(shared.driver.driver(now).as_ref());
            v["record"] = shared.record();
            Ok(v)
        }
        "gait.stop" | "gait.resume" => {
            let (min, max) = STOP_TIME_RANGE_S;
            let within_s = p
                .take_f64_in("within_s", min, max)?
                .unwrap_or(DEFAULT_STOP_S);
            p.finish(&["within_s"])?;
            let request = if method == "gait.stop" {
                LoopRequest::StopGait { within_s }
            } else {
                LoopRequest::ResumeGait { within_s }
            };
            shared.router.call(request).await?;
            Ok(
                json!({ "motion": if method == "gait.stop" { "stopping" } else { "starting" }, "within_s": within_s }),
            )
        }
        "take_over" => {
            p.finish(&[])?;
            let from = shared.driver.take_over(session.who(), now);
            if let Some(from) = &from {
                tracing::warn!("{} took the drive over from {from}", session.who());
            }
            navigate::operator_takes_over(shared);
            Ok(json!({ "driver": session.who(), "taken_from": from }))
        }
        "gait.list" => {
            p.finish(&[])?;
            Ok(views::gait_list(&shared.telemetry.latest()))
        }
        "gait.set" => {
            let gait = p.take_gait("gait")?.ok_or_else(|| missing("gait"))?;
            p.finish(&["gait"])?;
            shared.router.call(LoopRequest::SetGait { gait }).await?;
            Ok(json!({ "gait": gait }))
        }
        "params.get" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            let s = shared.telemetry.latest();
            Ok(views::params(&s.params, s.blend_time_s, gait))
        }
        "params.set" => params_set(shared, p).await,
        "controller.list" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            Ok(controllers::list(shared, gait))
        }
        "controller.get" => {
            let gait = p.take_gait("gait")?;
            p.finish(&["gait"])?;
            Ok(controllers::get(shared, gait))
        }
        "controller.set" => {
            let (gait, sel) = controller_set_params(p)?;
            controllers::set(shared, gait, sel).await
        }
        "controller.calibrate" => {
            let gait = p.take_gait("gait")?;
            let (min, max) = (0.1, controllers::CALIBRATION_MAX_S);
            let seconds = p.take_f64_in("seconds", min, max)?;
            let clear = take_flag(&mut p, "clear")?;
            p.finish(&["gait", "seconds", "clear"])?;
            let what = match (clear, seconds) {
                (true, Some(_)) => {
                    return Err(RpcError::invalid_params(
                        "give `seconds` to calibrate or `clear`, not both",
                    ));
                }
                (true, None) => controllers::Calibration::Clear,
                (false, s) => controllers::Calibration::Run(s),
            };
            controllers::calibrate(shared, session, gait, what).await
        }
        "controller.heading" => {
            let gait = p.take_gait("gait")?;
            let lim = 2.0 * std::f64::consts::PI;
            let heading = p.take_f64_in("heading_rad", -lim, lim)?;
            let here = take_flag(&mut p, "here")?;
            p.finish(&["gait", "heading_rad", "here"])?;
            let heading = match (heading, here) {
                (Some(h), false) => Some(h),
                (None, true) => None,
                _ => {
                    return Err(RpcError::invalid_params(
                        "give `heading_rad` (rad, in the pose estimate's world) or `here: true`",
                    ));
                }
            };
            controllers::set_heading(shared, gait, heading).await
        }
        "navigate" => navigate::navigate(shared, p).await,
        "hold" => act(shared, p, LoopRequest::Hold).await,
        "limp" => act(shared, p, LoopRequest::Limp).await,
        "estop" => act(shared, p, LoopRequest::EStop).await,
        "arm" => act(shared, p, LoopRequest::Arm).await,
        "stats" => {
            p.finish(&[])?;
            let mut v = views::stats(&shared.telemetry.latest());
            v["record"] = shared.record();
            Ok(v)
        }
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
        _ => Err(RpcError::new(
            code::METHOD_NOT_FOUND,
            format!("unknown method `{method}` (known: {})", METHODS.join(", ")),
        )),
    }
}

/// `controller.set`'s params read and checked: the gait and the selection to build for
/// it (building it, which checks the configuration, needs no loop: `registry::build`).
pub fn controller_set_params(mut p: Params) -> Result<(GaitKind, Selection), RpcError> {
    let gait = p.take_gait("gait")?.ok_or_else(|| missing("gait"))?;
    let controller = p
        .take_str("controller")?
        .ok_or_else(|| missing("controller"))?;
    let preset = p.take_str("preset")?;
    let config = p.take_json("config")?;
    p.finish(&["gait", "controller", "preset", "config"])?;
    let sel = Selection {
        controller,
        preset,
        config,
    };
    Ok((gait, sel))
}

/// A wrong token is answered after this long, and the connection closed after
/// [`MAX_FAILED_AUTHS`] of them: guessing costs a connection a second a try.
pub const AUTH_FAILURE_DELAY: std::time::Duration = std::time::Duration::from_secs(1);
pub const MAX_FAILED_AUTHS: u32 = 3;

async fn auth(shared: &Shared, session: &mut Session, mut p: Params) -> Result<Value, RpcError> {
    let token = p.take_str("token")?.ok_or_else(|| missing("token"))?;
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
        return Err(RpcError::new(
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

fn missing(field: &str) -> RpcError {
    RpcError::invalid_params(format!("missing `{field}`"))
}

/// A parameterless request to the loop.
async fn act(shared: &Shared, p: Params, request: LoopRequest) -> Result<Value, RpcError> {
    p.finish(&[])?;
    shared.router.call(request).await?;
    Ok(json!({ "ok": true }))
}

/// `params.set`: either `{"blend_time_s": x}` or `{"gait": name, <field>: x, ...}`;
/// for slithering also the old `"compliance": {...}` (now `controller.set`).
async fn params_set(shared: &Shared, mut p: Params) -> Result<Value, RpcError> {
    if p.contains("blend_time_s") {
        let (min, max) = BLEND_TIME_RANGE_S;
        let t = p
            .take_f64_in("blend_time_s", min, max)?
            .expect("checked present above");
        if !p.is_empty() {
            return Err(RpcError::invalid_params(
                "`blend_time_s` is set on its own: send gait params in a separate request",
            ));
        }
        shared
            .router
            .call(LoopRequest::SetBlendTime { blend_time_s: t })
            .await?;
        return Ok(json!({ "blend_time_s": t }));
    }
    let gait = p
        .take_gait("gait")?
        .ok_or_else(|| RpcError::invalid_params("missing `gait` (or `blend_time_s`)"))?;
    let patch = p.take_patch()?;
    let compliance = p.take_json("compliance")?;
    let mut expected = vec!["gait"];
    expected.extend(PATCH_FIELDS);
    expected.push("compliance");
    p.finish(&expected)?;
    if compliance.is_some() && gait != GaitKind::Slithering {
        return Err(RpcError::invalid_params(format!(
            "`compliance` was slithering's controller; every gait's controller is now set \
             with controller.set (gait {})",
            gait.name()
        )));
    }
    if patch == ParamPatch::default() && compliance.is_none() {
        return Err(RpcError::invalid_params(format!(
            "nothing to change: give at least one of {}",
            PATCH_FIELDS.join(", ")
        )));
    }
    if let Some(c) = compliance {
        return controllers::set_compliance(shared, gait, patch, c, &shared.layout).await;
    }
    // Validated against the table the loop published last; the loop checks again, also
    // against the gait's controller.
    let current = *shared.telemetry.latest().params.get(gait);
    let new = current
        .patched_for(gait, &patch, shared.layout.module_length_m)
        .map_err(|e| RpcError::invalid_params(format!("{}: {e}", gait.name())))?;
    let continuity = shared
        .router
        .call(LoopRequest::SetParams { gait, patch })
        .await?;
    Ok(json!({ "gait": gait, "params": new, "controller": continuity }))
}

/// An optional boolean param (absent: false).
fn take_flag(p: &mut Params, name: &str) -> Result<bool, RpcError> {
    match p.take_json(name)? {
        None | Some(Value::Bool(false)) => Ok(false),
        Some(Value::Bool(true)) => Ok(true),
        Some(_) => Err(RpcError::invalid_params(format!(
            "`{name}` must be true or false"
        ))),
    }
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
