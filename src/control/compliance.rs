//! Slithering's controller on the socket: the `compliance` object of `params.set`
//! (parsed and validated here, the controller built here, off the loop), and its
//! views in `params.get`, `status` and telemetry.
use serde_json::{Map, Value, json};

use super::api::RpcError;
use super::server::Shared;
use crate::gait::{GaitKind, ParamPatch};
use crate::rt::compliance::{ComplianceSetting, ComplianceTelemetry};
use crate::rt::messages::LoopRequest;
use crate::shape::admittance::{AdmittanceGains, Compliance};
use crate::shape::slithering_config::ParamCompliance;
use crate::shape::slithering_shape::Param;
use crate::shape::{Centralization, FieldReport, SlitheringCompliance};

/// Fields of the `compliance` object.
const FIELDS: [&str; 8] = [
    "controller",
    "amplitude",
    "spatial_freq",
    "phase",
    "compliance",
    "torque_cutoff_hz",
    "torque_deadband_nm",
    "edge_width_modules",
];
const PARAM_FIELDS: [&str; 3] = ["enabled", "centralization", "gains"];
const GAIN_FIELDS: [&str; 6] = ["mass", "damping", "stiffness", "min", "max", "bias_force"];

/// `params.set` of slithering: new nominal parameters (`patch`, may be empty) and / or
/// a new `compliance`. While a controller is set, new parameters come with a
/// controller rebuilt for them. Replaced controllers are freed here.
pub(crate) async fn set_slithering(
    shared: &Shared,
    patch: ParamPatch,
    compliance: Option<Value>,
) -> Result<Value, RpcError> {
    let kind = GaitKind::Slithering;
    let _one_at_a_time = shared.slithering.lock().await;
    free_retired(shared);
    let snap = shared.telemetry.latest();
    let current = *snap.params.get(kind);
    let params = if patch == ParamPatch::default() {
        current
    } else {
        current
            .patched(kind, &patch)
            .map_err(|e| RpcError::invalid_params(format!("{}: {e}", kind.name())))?
    };
    let setting = match &compliance {
        Some(v) => parse(v, &snap.compliance.setting)?,
        None => snap.compliance.setting,
    };
    let change = if compliance.is_some() || !setting.is_open_loop() {
        let built = setting
            .build(&shared.layout, &params)
            .map_err(|e| RpcError::invalid_params(format!("slithering: {e}")))?;
        Some(built)
    } else {
        None
    };
    let request = if patch == ParamPatch::default() {
        LoopRequest::SetCompliance
    } else {
        LoopRequest::SetParams(kind, patch)
    };
    let result = shared.router.call_with(request, change).await;
    free_retired(shared);
    result?;
    Ok(json!({
        "gait": kind,
        "params": params,
        "compliance": setting_view(&setting),
    }))
}

/// Drops the controllers the loop replaced (freeing is off the loop's thread).
fn free_retired(shared: &Shared) {
    while let Ok(old) = shared.retired.try_recv() {
        drop(old);
    }
}

fn invalid(message: String) -> RpcError {
    RpcError::invalid_params(message)
}

fn object<'a>(
    v: &'a Value,
    path: &str,
    known: &[&str],
) -> Result<&'a Map<String, Value>, RpcError> {
    let map = v
        .as_object()
        .ok_or_else(|| invalid(format!("`{path}` must be an object, got {}", kind_of(v))))?;
    if let Some(extra) = map.keys().find(|k| !known.contains(&k.as_str())) {
        return Err(invalid(format!(
            "unknown field `{path}.{extra}` (expected one of: {})",
            known.join(", ")
        )));
    }
    Ok(map)
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn number(v: &Value, path: &str) -> Result<f64, RpcError> {
    v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
        invalid(format!(
            "`{path}` must be a finite number, got {}",
            kind_of(v)
        ))
    })
}

/// One of `options` named by a string.
fn choice<T: Copy>(v: &Value, path: &str, options: &[(&str, T)]) -> Result<T, RpcError> {
    let names = || options.iter().map(|o| o.0).collect::<Vec<_>>().join(", ");
    let s = v
        .as_str()
        .ok_or_else(|| invalid(format!("`{path}` must be a string ({})", names())))?;
    options
        .iter()
        .find(|o| o.0 == s)
        .map(|o| o.1)
        .ok_or_else(|| {
            invalid(format!(
                "`{path}`: unknown value `{s}` (known: {})",
                names()
            ))
        })
}

/// The `compliance` object of `params.set`: `controller` (a preset, whose compliance
/// the other fields override) or, without it, overrides of the current setting.
pub(crate) fn parse(v: &Value, current: &ComplianceSetting) -> Result<ComplianceSetting, RpcError> {
    let map = object(v, "compliance", &FIELDS)?;
    let mut setting = match map.get("controller") {
        Some(Value::String(name)) => ComplianceSetting::named(name)
            .map_err(|e| invalid(format!("`compliance.controller`: {e}")))?,
        Some(other) => {
            return Err(invalid(format!(
                "`compliance.controller` must be a string, got {}",
                kind_of(other)
            )));
        }
        None => *current,
    };
    if map.keys().all(|k| k == "controller") {
        if map.is_empty() {
            return Err(invalid(
                "`compliance`: give `controller` and / or fields to change".into(),
            ));
        }
        return Ok(setting);
    }
    let controller = setting.controller;
    let Some(config) = setting.config.as_mut() else {
        return Err(invalid(format!(
            "`compliance`: controller {controller} has no compliance to override (the \
             shape-based ones do: {})",
            SlitheringCompliance::PRESETS.join(", ")
        )));
    };
    for p in Param::ALL {
        if let Some(v) = map.get(p.name()) {
            param(v, &format!("compliance.{}", p.name()), config.param_mut(p))?;
        }
    }
    if let Some(v) = map.get("compliance") {
        config.compliance = choice(
            v,
            "compliance.compliance",
            &[
                ("compliant", Compliance::Compliant),
                ("anti_compliant", Compliance::AntiCompliant),
            ],
        )?;
    }
    for (name, slot) in [
        ("torque_cutoff_hz", &mut config.torque_cutoff_hz),
        ("torque_deadband_nm", &mut config.torque_deadband_nm),
        ("edge_width_modules", &mut config.edge_width_modules),
    ] {
        if let Some(v) = map.get(name) {
            *slot = number(v, &format!("compliance.{name}"))?;
        }
    }
    config
        .validate()
        .map_err(|e| invalid(format!("`compliance.{e}`")))?;
    Ok(setting)
}

fn param(v: &Value, path: &str, out: &mut ParamCompliance) -> Result<(), RpcError> {
    let map = object(v, path, &PARAM_FIELDS)?;
    if let Some(v) = map.get("enabled") {
        out.enabled = v
            .as_bool()
            .ok_or_else(|| invalid(format!("`{path}.enabled` must be a boolean")))?;
    }
    if let Some(v) = map.get("centralization") {
        out.centralization = choice(
            v,
            &format!("{path}.centralization"),
            &[
                ("central", Centralization::Central),
                ("windowed", Centralization::Windowed),
                ("per_joint", Centralization::PerJoint),
            ],
        )?;
    }
    if let Some(v) = map.get("gains") {
        gains(v, &format!("{path}.gains"), &mut out.gains)?;
    }
    Ok(())
}

fn gains(v: &Value, path: &str, out: &mut AdmittanceGains) -> Result<(), RpcError> {
    let map = object(v, path, &GAIN_FIELDS)?;
    for (name, slot, unbounded) in [
        ("mass", &mut out.mass, None),
        ("damping", &mut out.damping, None),
        ("stiffness", &mut out.stiffness, None),
        ("min", &mut out.min, Some(f64::NEG_INFINITY)),
        ("max", &mut out.max, Some(f64::INFINITY)),
        ("bias_force", &mut out.bias_force, None),
    ] {
        match (map.get(name), unbounded) {
            (None, _) => {}
            // A range bound may be null: unbounded (as `params.get` shows it).
            (Some(Value::Null), Some(inf)) => *slot = inf,
            (Some(v), _) => *slot = number(v, &format!("{path}.{name}"))?,
        }
    }
    let (mass, damping, stiffness) = (out.mass, out.damping, out.stiffness);
    if mass <= 0.0 || damping < 0.0 || stiffness < 0.0 {
        return Err(invalid(format!(
            "`{path}`: mass must be > 0, damping and stiffness >= 0 (got mass {mass}, \
             damping {damping}, stiffness {stiffness})"
        )));
    }
    if out.min > out.max {
        return Err(invalid(format!(
            "`{path}`: min {} is above max {}",
            out.min, out.max
        )));
    }
    Ok(())
}

/// A setting as `params.get` / `params.set` show it: the controller and its
/// compliance (`null` for open loop and the CPG; unbounded ranges are `null`).
pub(crate) fn setting_view(s: &ComplianceSetting) -> Value {
    json!({ "controller": s.controller, "config": s.config })
}

/// The `compliance` part of `status` and telemetry.
pub(crate) fn telemetry_view(c: &ComplianceTelemetry) -> Value {
    let mut v = json!({
        "controller": c.setting.controller,
        "state": c.engagement,
        "takeovers": c.takeovers,
        "windows_born": c.windows_born,
        "windows_dropped": c.windows_dropped,
        "freed_in_loop": c.freed_in_loop,
    });
    let r = &c.report;
    if r.available {
        v["phase_lag_rad"] = json!(r.phase_lag_rad);
        v["amplitude_mean_rad"] = json!(r.amplitude_mean_rad);
        v["spatial_freq_mean_rad"] = json!(r.spatial_freq_mean_rad);
        v["windows"] = json!(r.travelling_windows);
        let fields: Map<String, Value> = Param::ALL
            .iter()
            .map(|p| (p.name().to_owned(), field_view(&r.fields[p.index()])))
            .filter(|(_, f)| !f.is_null())
            .collect();
        v["fields"] = Value::Object(fields);
    }
    v
}

/// One field's windows: edges (normalised arc length, `null` when open), value and
/// shape force.
fn field_view(f: &FieldReport) -> Value {
    if f.is_empty() {
        return Value::Null;
    }
    let windows: Vec<Value> = (0..f.len())
        .map(|k| json!({ "a": f.a[k], "b": f.b[k], "value": f.value[k], "force": f.force[k] }))
        .collect();
    json!({
        "enabled": f.enabled,
        "centralization": f.centralization,
        "count": f.count,
        "windows": windows,
    })
}

#[cfg(test)]
#[path = "compliance_tests.rs"]
mod tests;
