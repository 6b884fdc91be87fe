//! Slithering's controller on the socket: the `compliance` object of `params.set`
//! (parsed and validated here, the controller built here, off the loop), and its
//! views in `params.get`, `status` and telemetry.
use serde_json::{Map, Value, json};

use super::api::RpcError;
use super::server::Shared;
use crate::gait::{GaitKind, ParamPatch};
use crate::rt::compliance::{ComplianceSetting, ComplianceTelemetry};
use crate::rt::messages::LoopRequest;
use crate::shape::FieldReport;
use crate::shape::slithering_shape::Param;

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

/// The `compliance` object of `params.set`, over the `current` setting
/// ([`crate::rt::compliance_json::parse`]).
pub(crate) fn parse(v: &Value, current: &ComplianceSetting) -> Result<ComplianceSetting, RpcError> {
    crate::rt::compliance_json::parse(v, current).map_err(RpcError::invalid_params)
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
