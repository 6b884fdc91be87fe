//! The `compliance` object of `params.set` (docs/control-socket.md) and of
//! `snake-lab --variant` (docs/lab.md): a preset and / or overrides of its gains,
//! parsed and validated into a [`ComplianceSetting`]. Off the loop (allocates).
use serde_json::{Map, Value};

use crate::rt::compliance::ComplianceSetting;
use crate::shape::admittance::{AdmittanceGains, Compliance};
use crate::shape::slithering_config::ParamCompliance;
use crate::shape::slithering_shape::Param;
use crate::shape::{Centralization, SlitheringCompliance};

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

fn object<'a>(v: &'a Value, path: &str, known: &[&str]) -> Result<&'a Map<String, Value>, String> {
    let map = v
        .as_object()
        .ok_or_else(|| format!("`{path}` must be an object, got {}", kind_of(v)))?;
    if let Some(extra) = map.keys().find(|k| !known.contains(&k.as_str())) {
        return Err(format!(
            "unknown field `{path}.{extra}` (expected one of: {})",
            known.join(", ")
        ));
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

fn number(v: &Value, path: &str) -> Result<f64, String> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("`{path}` must be a finite number, got {}", kind_of(v)))
}

/// One of `options` named by a string.
fn choice<T: Copy>(v: &Value, path: &str, options: &[(&str, T)]) -> Result<T, String> {
    let names = || options.iter().map(|o| o.0).collect::<Vec<_>>().join(", ");
    let s = v
        .as_str()
        .ok_or_else(|| format!("`{path}` must be a string ({})", names()))?;
    options
        .iter()
        .find(|o| o.0 == s)
        .map(|o| o.1)
        .ok_or_else(|| format!("`{path}`: unknown value `{s}` (known: {})", names()))
}

/// The `compliance` object of `params.set`: `controller` (a preset, whose compliance
/// the other fields override) or, without it, overrides of the current setting.
pub fn parse(v: &Value, current: &ComplianceSetting) -> Result<ComplianceSetting, String> {
    let map = object(v, "compliance", &FIELDS)?;
    let mut setting = match map.get("controller") {
        Some(Value::String(name)) => {
            ComplianceSetting::named(name).map_err(|e| format!("`compliance.controller`: {e}"))?
        }
        Some(other) => {
            return Err(format!(
                "`compliance.controller` must be a string, got {}",
                kind_of(other)
            ));
        }
        None => *current,
    };
    if map.keys().all(|k| k == "controller") {
        if map.is_empty() {
            return Err("`compliance`: give `controller` and / or fields to change".into());
        }
        return Ok(setting);
    }
    let controller = setting.controller;
    let Some(config) = setting.config.as_mut() else {
        return Err(format!(
            "`compliance`: controller {controller} has no compliance to override (the \
             shape-based ones do: {})",
            SlitheringCompliance::PRESETS.join(", ")
        ));
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
    config.validate().map_err(|e| format!("`compliance.{e}`"))?;
    Ok(setting)
}

fn param(v: &Value, path: &str, out: &mut ParamCompliance) -> Result<(), String> {
    let map = object(v, path, &PARAM_FIELDS)?;
    if let Some(v) = map.get("enabled") {
        out.enabled = v
            .as_bool()
            .ok_or_else(|| format!("`{path}.enabled` must be a boolean"))?;
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

fn gains(v: &Value, path: &str, out: &mut AdmittanceGains) -> Result<(), String> {
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
        return Err(format!(
            "`{path}`: mass must be > 0, damping and stiffness >= 0 (got mass {mass}, \
             damping {damping}, stiffness {stiffness})"
        ));
    }
    if out.min > out.max {
        return Err(format!(
            "`{path}`: min {} is above max {}",
            out.min, out.max
        ));
    }
    Ok(())
}
