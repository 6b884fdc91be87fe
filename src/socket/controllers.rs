//! The controller methods on the socket, read from the registry with no per-gait code:
//! `controller.list` (what each gait can run), `controller.get` (what it runs),
//! `controller.set` (build off the loop, then install), and the `controller` part of
//! `status` and telemetry. Also the old `params.set` `compliance` object of
//! slithering, translated into a selection.
use serde_json::{Map, Value, json};

use super::api::{RpcError, code};
use super::session::Session;
use super::shared::Shared;
use crate::controller_interface::{CalibrationState, ControllerCommand};
use crate::controller_interface::catalog::{Catalog, ControllerInfo, NO_CONTROLLER};
use crate::controller_interface::config::merge;
use crate::controller_interface::registry::{self, BuildContext, Selection};
use crate::controllers::REGISTRY;
use crate::gait::{BodyLayout, GaitKind, GaitParams, ParamPatch};
use crate::rt::controller_slots::Engagement;
use crate::rt::controller_slots::{ControllerTelemetry, Installed};
use crate::rt::messages::{Continuity, LoopRequest, Refusal, Rejection};
use crate::rt::telemetry::Snapshot;
use crate::safety::failsafe::Reason;

/// `controller.list`: per gait, every controller that runs it with its presets,
/// default configuration and report names, and which one is installed.
pub(crate) fn list(shared: &Shared, gait: Option<GaitKind>) -> Value {
    let snap = shared.telemetry.latest();
    let gaits: Map<String, Value> = GaitKind::ALL
        .into_iter()
        .filter(|g| gait.is_none_or(|only| only == *g))
        .map(|g| {
            let ctx = BuildContext {
                gait: g,
                layout: &shared.layout,
                params: snap.params.get(g),
            };
            let controllers: Vec<Value> = registry::for_gait(REGISTRY, g)
                .map(|f| {
                    let default = f.presets()[0].0;
                    json!({
                        "name": f.name(),
                        "summary": f.summary(),
                        "default_preset": default,
                        "presets": f.presets().iter()
                            .map(|(name, summary)| json!({"name": name, "summary": summary}))
                            .collect::<Vec<_>>(),
                        "default_config": f.preset_config(default),
                        "report": f.preset_report(default, &ctx),
                    })
                })
                .collect();
            let installed = installed(&shared.catalog, snap.controller.installed[g.index()]);
            (
                g.name().to_owned(),
                json!({"installed": installed, "controllers": controllers}),
            )
        })
        .collect();
    json!({ "gaits": gaits })
}

/// `controller.get`: what each gait (or one) runs.
pub(crate) fn get(shared: &Shared, gait: Option<GaitKind>) -> Value {
    let snap = shared.telemetry.latest();
    let one = |g: GaitKind| installed(&shared.catalog, snap.controller.installed[g.index()]);
    match gait {
        Some(g) => json!({ "gait": g, "controller": one(g) }),
        None => {
            let all: Map<String, Value> = GaitKind::ALL
                .into_iter()
                .map(|g| (g.name().to_owned(), one(g)))
                .collect();
            json!({ "gaits": all })
        }
    }
}

fn installed(catalog: &Catalog, id: u64) -> Value {
    match (id, catalog.get(id)) {
        (NO_CONTROLLER, _) => Value::Null,
        (_, Some(info)) => info_view(&info),
        (_, None) => json!({ "id": id }),
    }
}

/// A controller's name, preset, configuration and report names.
pub(crate) fn info_view(info: &ControllerInfo) -> Value {
    json!({
        "id": info.id,
        "gait": info.gait,
        "controller": info.controller,
        "preset": info.preset,
        "config": info.config,
        "report": info.report,
    })
}

/// Builds `sel` for `gait` with the gait's nominal parameters after `patch` (off the
/// loop) and records it in the catalog.
fn build(
    shared: &Shared,
    gait: GaitKind,
    params: &GaitParams,
    sel: &Selection,
) -> Result<(Installed, ControllerInfo), RpcError> {
    let ctx = BuildContext {
        gait,
        layout: &shared.layout,
        params,
    };
    let built = registry::build(REGISTRY, sel, &ctx)
        .map_err(|e| RpcError::invalid_params(format!("{}: {e}", gait.name())))?;
    let info = shared.catalog.insert(built.info);
    let installed = Installed {
        id: info.id,
        controller: built.controller,
    };
    Ok((installed, (*info).clone()))
}

/// `controller.set`: build the selection and install it for `gait`.
pub(crate) async fn set(
    shared: &Shared,
    gait: GaitKind,
    sel: Selection,
) -> Result<Value, RpcError> {
    let _one_at_a_time = shared.controller_change.lock().await;
    shared.free_retired();
    let params = *shared.telemetry.latest().params.get(gait);
    let (installed, info) = build(shared, gait, &params, &sel)?;
    let result = shared
        .router
        .call_with(LoopRequest::SetController { gait }, Some(installed))
        .await;
    shared.free_retired();
    let continuity = result?;
    Ok(json!({ "gait": gait, "controller": with_continuity(info_view(&info), continuity) }))
}

/// Longest calibration the socket starts, s.
pub const CALIBRATION_MAX_S: f64 = 600.0;
/// Default calibration length, in the gait's nominal cycles (SPEC §8: "a few").
pub const CALIBRATION_DEFAULT_CYCLES: f64 = 3.0;

/// What `controller.calibrate` asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Calibration {
    /// Measure over this many seconds (`None`: over the default cycles of the gait).
    Run(Option<f64>),
    Clear,
}

/// `controller.calibrate`: starts `gait`'s controller's calibration and answers when it
/// has finished (its `calibration` signal reads 2) with the controller's signals, or
/// clears it. The controller measures only while it drives, so the gait must be the
/// one running; the answer says so when it is not, and when the daemon shuts down
/// meanwhile (`session`: the server's shutdown).
pub(crate) async fn calibrate(
    shared: &Shared,
    session: &Session,
    gait: Option<GaitKind>,
    what: Calibration,
) -> Result<Value, RpcError> {
    let (snap, gait, id, info) = installed_controller(shared, gait)?;
    let seconds = match what {
        Calibration::Clear => {
            let cmd = LoopRequest::ControllerCommand {
                gait,
                command: ControllerCommand::ClearCalibration,
            };
            shared.router.call(cmd).await?;
            return Ok(
                json!({ "gait": gait, "controller": info.controller, "calibration": "none" }),
            );
        }
        Calibration::Run(Some(s)) => s,
        Calibration::Run(None) => {
            let w = snap.params.get(gait).temporal_freq_rad_s.abs();
            if w < 1e-6 {
                return Err(RpcError::invalid_params(
                    "the gait does not move (temporal_freq_rad_s = 0): give `seconds`",
                ));
            }
            (CALIBRATION_DEFAULT_CYCLES * std::f64::consts::TAU / w).min(CALIBRATION_MAX_S)
        }
    };
    let cmd = ControllerCommand::Calibrate {
        duration_s: seconds,
    };
    shared
        .router
        .call(LoopRequest::ControllerCommand { gait, command: cmd })
        .await?;
    // Whether it reports a calibration to wait for: its declared capabilities.
    let declared = shared.telemetry.latest().controller;
    let driving = declared.active_id == id && declared.engagement == Engagement::Engaged;
    if driving && declared.capabilities.calibration.is_none() {
        return Ok(json!({ "gait": gait, "controller": info.controller, "seconds": seconds }));
    }
    // Wall time: the loop runs in real time; a held loop or another gait makes no progress.
    let deadline =
        tokio::time::Instant::now() + std::time::Duration::from_secs_f64(seconds * 1.5 + 5.0);
    let shutting_down = || {
        RpcError::new(
            code::REFUSED,
            format!(
                "refused: {} (the calibration of {} did not finish)",
                Rejection::Failsafe(Refusal::ShuttingDown),
                gait.name()
            ),
        )
    };
    loop {
        tokio::select! {
            () = tokio::time::sleep(std::time::Duration::from_millis(50)) => {}
            () = session.closing() => return Err(shutting_down()),
        }
        let snap = shared.telemetry.latest();
        if snap.reason == Reason::Shutdown {
            return Err(shutting_down());
        }
        let c = &snap.controller;
        if c.installed[gait.index()] != id {
            return Err(RpcError::new(
                code::REFUSED,
                "the controller was replaced during its calibration",
            ));
        }
        let driving = c.active_id == id && c.engagement == Engagement::Engaged;
        if driving && c.capabilities.calibration == Some(CalibrationState::Calibrated) {
            let view = telemetry_view(c, &shared.catalog);
            return Ok(json!({
                "gait": gait,
                "controller": info.controller,
                "seconds": seconds,
                "signals": view["signals"],
                "fields": view["fields"],
            }));
        }
        if tokio::time::Instant::now() > deadline {
            let why = if driving {
                "it did not finish in time"
            } else {
                "the controller is not driving (its gait must be running, not held)"
            };
            return Err(RpcError::new(
                code::LOOP_TIMEOUT,
                format!("calibration of {} not finished: {why}", gait.name()),
            ));
        }
    }
}

/// `params.set` of slithering with the old `compliance` object (docs/control-socket.md,
/// "Changes"): `controller` names a preset (or `open_loop`, `cpg`); the other keys
/// override its configuration; without `controller` they override what is installed.
/// New parameters in `patch` go with the controller, checked against it.
pub(crate) async fn set_compliance(
    shared: &Shared,
    gait: GaitKind,
    patch: ParamPatch,
    compliance: Value,
    layout: &BodyLayout,
) -> Result<Value, RpcError> {
    let bad = |m: String| RpcError::invalid_params(format!("`compliance`: {m}"));
    let Value::Object(mut map) = compliance else {
        return Err(bad("must be an object".into()));
    };
    let _one_at_a_time = shared.controller_change.lock().await;
    shared.free_retired();
    let snap = shared.telemetry.latest();
    let current = shared.catalog.get(snap.controller.installed[gait.index()]);
    let sel = match map.remove("controller") {
        Some(Value::String(name)) => Selection {
            controller: name,
            preset: None,
            config: None,
        },
        Some(_) => return Err(bad("`controller` must be a string".into())),
        None => match &current {
            Some(info) => Selection {
                controller: info.controller.to_owned(),
                preset: Some(info.preset.to_owned()),
                config: Some(info.config.clone()),
            },
            None => return Err(bad("give `controller`".into())),
        },
    };
    // The admittance's sign was called `compliance`; it is `sign` now.
    if let Some(sign) = map.remove("compliance") {
        map.insert("sign".into(), sign);
    }
    let mut sel = sel;
    if !map.is_empty() {
        let mut config = sel.config.take().unwrap_or_else(|| json!({}));
        merge(&mut config, &Value::Object(map));
        sel.config = Some(config);
    }
    let params = if patch == ParamPatch::default() {
        *snap.params.get(gait)
    } else {
        snap.params
            .get(gait)
            .patched_for(gait, &patch, layout.module_length_m)
            .map_err(|e| RpcError::invalid_params(format!("{}: {e}", gait.name())))?
    };
    let (installed, info) = build(shared, gait, &params, &sel)?;
    let request = if patch == ParamPatch::default() {
        LoopRequest::SetController { gait }
    } else {
        LoopRequest::SetParams { gait, patch }
    };
    let result = shared.router.call_with(request, Some(installed)).await;
    shared.free_retired();
    let continuity = result?;
    Ok(json!({
        "gait": gait,
        "params": params,
        "controller": with_continuity(info_view(&info), continuity),
    }))
}

/// A controller's view with what became of it (`continuity`, and `why` where it
/// could not take the change in place).
fn with_continuity(mut view: Value, continuity: Option<Continuity>) -> Value {
    if let (Value::Object(map), Ok(Value::Object(c))) = (&mut view, serde_json::to_value(continuity)) {
        map.extend(c);
    }
    view
}

/// The `controller` part of `status` and telemetry: the active gait's controller,
/// whether it drives, and its report by name.
pub(crate) fn telemetry_view(c: &ControllerTelemetry, catalog: &Catalog) -> Value {
    let info = catalog.get(c.active_id);
    let mut v = json!({
        "id": c.active_id,
        "controller": info.as_ref().map(|i| i.controller),
        "preset": info.as_ref().map(|i| i.preset),
        "state": c.engagement,
        "takeovers": c.takeovers,
        "freed_in_loop": c.freed_in_loop,
        "capabilities": c.capabilities,
    });
    let Some(info) = info else {
        return v;
    };
    if c.engagement != crate::rt::controller_slots::Engagement::Engaged {
        return v;
    }
    let r = &c.report;
    let signals: Map<String, Value> = info
        .report
        .signals
        .iter()
        .zip(&r.signals)
        .map(|(spec, &x)| (spec.name.clone(), json!(x)))
        .collect();
    v["signals"] = Value::Object(signals);
    let fields: Vec<Value> = info
        .report
        .fields
        .iter()
        .zip(&r.fields)
        .map(|(spec, f)| {
            let windows: Vec<Value> = (0..f.len())
                .map(|k| {
                    let mut w = json!({ "a": f.a[k], "b": f.b[k] });
                    for (col, values) in spec.columns.iter().zip(&f.columns) {
                        w[&col.name] = json!(values[k]);
                    }
                    w
                })
                .collect();
            json!({
                "name": spec.name,
                "centralization": spec.centralization,
                "enabled": spec.enabled,
                "count": f.count,
                "windows": windows,
            })
        })
        .collect();
    v["fields"] = Value::Array(fields);
    v
}

/// The latest snapshot, `gait` (the running one by default), its installed
/// controller's id and info; an error naming the gait when it has none.
fn installed_controller(
    shared: &Shared,
    gait: Option<GaitKind>,
) -> Result<(Snapshot, GaitKind, u64, std::sync::Arc<ControllerInfo>), RpcError> {
    let snap = shared.telemetry.latest();
    let gait = gait.unwrap_or(snap.gait);
    let id = snap.controller.installed[gait.index()];
    let info = shared.catalog.get(id).ok_or_else(|| {
        RpcError::invalid_params(format!(
            "{} has no controller installed: controller.set one first",
            gait.name()
        ))
    })?;
    Ok((snap, gait, id, info))
}

/// `controller.heading`: the nominal heading of `gait`'s controller (the running gait's
/// by default), rad in the pose estimate's world, or (`None`) the heading now. The loop
/// refuses it, saying why, when that controller does not steer by a heading.
pub(crate) async fn set_heading(
    shared: &Shared,
    gait: Option<GaitKind>,
    heading_rad: Option<f64>,
) -> Result<Value, RpcError> {
    let (_, gait, _, info) = installed_controller(shared, gait)?;
    let cmd = ControllerCommand::SetHeading { heading_rad };
    shared
        .router
        .call(LoopRequest::ControllerCommand { gait, command: cmd })
        .await?;
    Ok(json!({
        "gait": gait,
        "controller": info.controller,
        "heading_rad": heading_rad.map_or(json!("here"), |h| json!(h)),
    }))
}
