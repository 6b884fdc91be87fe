//! The JSON mapping of the operator API's acts at the socket's edge (also the station
//! services'): each acting method's params read completely into an [`Act`], an act
//! written back as its method's params (what the station records of its own acts), and
//! a [`Done`] written as the method's answer.
use serde_json::{Value, json};

use super::api::{OperatorError, PATCH_FIELDS, Params, code};
use super::controller_views::{self, info_view, telemetry_view, with_continuity};
use super::methods::METHODS;
use crate::controller_interface::Selection;
use crate::gait::{BLEND_TIME_RANGE_S, GaitKind, ParamPatch};
use crate::navigation::navigator::{NavigatorConfig, Target};
use crate::operator::{Act, CALIBRATION_MAX_S, Calibrated, Calibration, Done, Operator};
use crate::rt::gait_clock::{DEFAULT_STOP_S, STOP_TIME_RANGE_S};

/// An acting method's params, read into the API's typed request.
pub(crate) fn parse_act(op: &Operator, method: &str, mut p: Params) -> Result<Act, OperatorError> {
    let act = match method {
        "gait.set" => {
            let gait = p.take_gait("gait")?.ok_or_else(|| missing("gait"))?;
            p.finish(&["gait"])?;
            Act::SetGait { gait }
        }
        "gait.stop" | "gait.resume" => {
            let (min, max) = STOP_TIME_RANGE_S;
            let within_s = p
                .take_f64_in("within_s", min, max)?
                .unwrap_or(DEFAULT_STOP_S);
            p.finish(&["within_s"])?;
            if method == "gait.stop" {
                Act::StopGait { within_s }
            } else {
                Act::ResumeGait { within_s }
            }
        }
        "take_over" => {
            p.finish(&[])?;
            Act::TakeOver
        }
        "params.set" => params_set(op, p)?,
        "controller.set" => {
            let (gait, selection) = controller_set_params(p)?;
            Act::SetController {
                gait,
                selection,
                patch: ParamPatch::default(),
            }
        }
        "controller.calibrate" => {
            let gait = p.take_gait("gait")?;
            let (min, max) = (0.1, CALIBRATION_MAX_S);
            let seconds = p.take_f64_in("seconds", min, max)?;
            let clear = take_flag(&mut p, "clear")?;
            p.finish(&["gait", "seconds", "clear"])?;
            let what = match (clear, seconds) {
                (true, Some(_)) => {
                    return Err(OperatorError::invalid_params(
                        "give `seconds` to calibrate or `clear`, not both",
                    ));
                }
                (true, None) => Calibration::Clear,
                (false, s) => Calibration::Run(s),
            };
            Act::Calibrate { gait, what }
        }
        "controller.heading" => {
            let gait = p.take_gait("gait")?;
            let lim = 2.0 * std::f64::consts::PI;
            let heading = p.take_f64_in("heading_rad", -lim, lim)?;
            let here = take_flag(&mut p, "here")?;
            p.finish(&["gait", "heading_rad", "here"])?;
            let heading_rad = match (heading, here) {
                (Some(h), false) => Some(h),
                (None, true) => None,
                _ => {
                    return Err(OperatorError::invalid_params(
                        "give `heading_rad` (rad, in the pose estimate's world) or `here: true`",
                    ));
                }
            };
            Act::SetHeading { gait, heading_rad }
        }
        "navigate" => navigate(p)?,
        "hold" | "limp" | "estop" | "arm" => {
            p.finish(&[])?;
            match method {
                "hold" => Act::Hold,
                "limp" => Act::Limp,
                "estop" => Act::EStop,
                _ => Act::Arm,
            }
        }
        _ => {
            return Err(OperatorError::new(
                code::METHOD_NOT_FOUND,
                format!("unknown method `{method}` (known: {})", METHODS.join(", ")),
            ));
        }
    };
    Ok(act)
}

/// An act as the socket's params of its method (`Act::method`): what the station
/// records of an act it made itself (teleop).
pub fn act_params(act: &Act) -> Value {
    match act {
        Act::SetGait { gait } => json!({ "gait": gait }),
        Act::StopGait { within_s } | Act::ResumeGait { within_s } => {
            json!({ "within_s": within_s })
        }
        Act::SetParams { gait, patch } => {
            let mut v = serde_json::to_value(patch).unwrap_or_default();
            if let Some(o) = v.as_object_mut() {
                o.retain(|_, x| !x.is_null());
                o.insert("gait".into(), json!(gait));
            }
            v
        }
        Act::SetBlendTime { blend_time_s } => json!({ "blend_time_s": blend_time_s }),
        Act::SetController {
            gait, selection, ..
        } => json!({
            "gait": gait,
            "controller": selection.controller,
            "preset": selection.preset,
            "config": selection.config,
        }),
        Act::Calibrate { gait, what } => match what {
            Calibration::Clear => json!({ "gait": gait, "clear": true }),
            Calibration::Run(s) => json!({ "gait": gait, "seconds": s }),
        },
        Act::SetHeading { gait, heading_rad } => match heading_rad {
            Some(h) => json!({ "gait": gait, "heading_rad": h }),
            None => json!({ "gait": gait, "here": true }),
        },
        Act::Navigate {
            target: Target::Heading(h),
            config,
        } => json!({ "heading_rad": h, "config": config }),
        Act::Navigate {
            target: Target::Goal(g),
            config,
        } => json!({ "goal_m": g, "config": config }),
        Act::NavigateOff => json!({ "off": true }),
        Act::TakeOver | Act::Hold | Act::Limp | Act::EStop | Act::Arm => json!({}),
    }
}

/// What was done, as the socket answers it.
pub fn answer_json(op: &Operator, done: Done) -> Value {
    match done {
        Done::Gait { gait } => json!({ "gait": gait }),
        Done::Motion { stopping, within_s } => {
            let motion = if stopping { "stopping" } else { "starting" };
            json!({ "motion": motion, "within_s": within_s })
        }
        Done::Params {
            gait,
            params,
            continuity,
        } => json!({ "gait": gait, "params": params, "controller": continuity }),
        Done::BlendTime { blend_time_s } => json!({ "blend_time_s": blend_time_s }),
        Done::Controller {
            gait,
            info,
            params,
            continuity,
        } => {
            let controller = with_continuity(info_view(&info), continuity);
            match params {
                Some(params) => json!({ "gait": gait, "params": params, "controller": controller }),
                None => json!({ "gait": gait, "controller": controller }),
            }
        }
        Done::Calibration {
            gait,
            controller,
            outcome,
        } => match outcome {
            Calibrated::Cleared => {
                json!({ "gait": gait, "controller": controller, "calibration": "none" })
            }
            Calibrated::Started { seconds } => {
                json!({ "gait": gait, "controller": controller, "seconds": seconds })
            }
            Calibrated::Finished {
                seconds,
                controller: report,
            } => {
                let view = telemetry_view(&report, op.catalog());
                json!({
                    "gait": gait,
                    "controller": controller,
                    "seconds": seconds,
                    "signals": view["signals"],
                    "fields": view["fields"],
                })
            }
        },
        Done::Heading {
            gait,
            controller,
            heading_rad,
        } => json!({
            "gait": gait,
            "controller": controller,
            "heading_rad": heading_rad.map_or(json!("here"), |h| json!(h)),
        }),
        Done::Navigating {
            travel_rad,
            goal_m,
            config,
        } => {
            json!({ "navigating": true, "travel_rad": travel_rad, "goal_m": goal_m, "config": config })
        }
        Done::NavigationOff { was_navigating } => {
            json!({ "navigating": false, "was_navigating": was_navigating })
        }
        Done::TookOver { driver, taken_from } => {
            json!({ "driver": driver, "taken_from": taken_from })
        }
        Done::Ok => json!({ "ok": true }),
    }
}

/// `controller.set`'s params read and checked: the gait and the selection to build for
/// it (building it, which checks the configuration, needs no loop: `registry::build`).
pub fn controller_set_params(mut p: Params) -> Result<(GaitKind, Selection), OperatorError> {
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

pub(crate) fn missing(field: &str) -> OperatorError {
    OperatorError::invalid_params(format!("missing `{field}`"))
}

/// `params.set`: either `{"blend_time_s": x}` or `{"gait": name, <field>: x, ...}`;
/// for slithering also the old `"compliance": {...}` (now `controller.set`).
fn params_set(op: &Operator, mut p: Params) -> Result<Act, OperatorError> {
    if p.contains("blend_time_s") {
        let (min, max) = BLEND_TIME_RANGE_S;
        let t = p
            .take_f64_in("blend_time_s", min, max)?
            .expect("checked present above");
        if !p.is_empty() {
            return Err(OperatorError::invalid_params(
                "`blend_time_s` is set on its own: send gait params in a separate request",
            ));
        }
        return Ok(Act::SetBlendTime { blend_time_s: t });
    }
    let gait = p
        .take_gait("gait")?
        .ok_or_else(|| OperatorError::invalid_params("missing `gait` (or `blend_time_s`)"))?;
    let patch = p.take_patch()?;
    let compliance = p.take_json("compliance")?;
    let mut expected = vec!["gait"];
    expected.extend(PATCH_FIELDS);
    expected.push("compliance");
    p.finish(&expected)?;
    if compliance.is_some() && gait != GaitKind::Slithering {
        return Err(OperatorError::invalid_params(format!(
            "`compliance` was slithering's controller; every gait's controller is now set \
             with controller.set (gait {})",
            gait.name()
        )));
    }
    if patch == ParamPatch::default() && compliance.is_none() {
        return Err(OperatorError::invalid_params(format!(
            "nothing to change: give at least one of {}",
            PATCH_FIELDS.join(", ")
        )));
    }
    Ok(match compliance {
        Some(c) => Act::SetController {
            gait,
            selection: controller_views::compliance_selection(op, gait, c)?,
            patch,
        },
        None => Act::SetParams { gait, patch },
    })
}

/// `navigate`: `{"heading_rad": h, "config": {..}}` (a direction, the pose estimate's
/// world) or `{"goal_m": [x, y], ..}` (a goal, the position source's world) starts, or
/// restarts towards a new target; `{"off": true}` stops.
fn navigate(mut p: Params) -> Result<Act, OperatorError> {
    let lim = 2.0 * std::f64::consts::PI;
    let heading = p.take_f64_in("heading_rad", -lim, lim)?;
    let goal = super::pose_method::numbers::<2>("goal_m", p.take_json("goal_m")?)?;
    let off = take_flag(&mut p, "off")?;
    let config = p.take_json("config")?;
    p.finish(&["heading_rad", "goal_m", "off", "config"])?;
    let target = match (heading, goal, off) {
        (None, None, true) if config.is_none() => return Ok(Act::NavigateOff),
        (Some(h), None, false) => Target::Heading(h),
        (None, Some(g), false) => {
            if g.iter().any(|v| v.abs() > GOAL_LIMIT_M) {
                return Err(OperatorError::invalid_params(format!(
                    "`goal_m` {g:?}: each coordinate within ±{GOAL_LIMIT_M} m"
                )));
            }
            Target::Goal(g)
        }
        _ => {
            return Err(OperatorError::invalid_params(
                "give one of `heading_rad` (the direction of travel, rad, in the pose \
                 estimate's world) or `goal_m` ([x, y], m, in the position source's world), \
                 optionally with `config`; or `off: true`",
            ));
        }
    };
    let config: NavigatorConfig = match config {
        None => NavigatorConfig::DEFAULT,
        // serde would read a struct from an array too (`[]`: every default).
        Some(v) if !v.is_object() => {
            return Err(OperatorError::invalid_params(
                "config: an object of the navigator's settings, e.g. {\"slither_max_s\": 60}",
            ));
        }
        Some(v) => serde_json::from_value(v)
            .map_err(|e| OperatorError::invalid_params(format!("config: {e}")))?,
    };
    config
        .check()
        .map_err(|e| OperatorError::invalid_params(format!("config: {e}")))?;
    Ok(Act::Navigate { target, config })
}

/// A goal further than this from the source's origin is refused, m.
const GOAL_LIMIT_M: f64 = 10_000.0;

/// An optional boolean param (absent: false).
fn take_flag(p: &mut Params, name: &str) -> Result<bool, OperatorError> {
    match p.take_json(name)? {
        None | Some(Value::Bool(false)) => Ok(false),
        Some(Value::Bool(true)) => Ok(true),
        Some(_) => Err(OperatorError::invalid_params(format!(
            "`{name}` must be true or false"
        ))),
    }
}
