//! JSON views of controllers for the socket's answers, `status` and telemetry, read
//! from the registry with no per-gait code: `controller.list` (what each gait can run),
//! `controller.get` (what it runs), a controller's info with what became of it, and the
//! `controller` part of `status` and telemetry. Also the old `params.set` `compliance`
//! object of slithering, translated into a selection.

use serde_json::{Map, Value, json};

use super::api::OperatorError;
use crate::controller_interface::catalog::{Catalog, ControllerInfo, NO_CONTROLLER};
use crate::controller_interface::config::merge;
use crate::controller_interface::registry::{self, BuildContext, Selection};
use crate::controllers::REGISTRY;
use crate::gait::GaitKind;
use crate::operator::Operator;
use crate::rt::controller_slots::ControllerTelemetry;
use crate::rt::messages::Continuity;

/// `controller.list`: per gait, every controller that runs it with its presets,
/// default configuration and report names, and which one is installed.
pub(crate) fn list(op: &Operator, gait: Option<GaitKind>) -> Value {
    let snap = op.snapshot();
    let gaits: Map<String, Value> = GaitKind::ALL
        .into_iter()
        .filter(|g| gait.is_none_or(|only| only == *g))
        .map(|g| {
            let ctx = BuildContext {
                gait: g,
                layout: op.layout(),
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
            let installed = installed(op.catalog(), snap.controller.installed[g.index()]);
            (
                g.name().to_owned(),
                json!({"installed": installed, "controllers": controllers}),
            )
        })
        .collect();
    json!({ "gaits": gaits })
}

/// `controller.get`: what each gait (or one) runs.
pub(crate) fn get(op: &Operator, gait: Option<GaitKind>) -> Value {
    let snap = op.snapshot();
    let one = |g: GaitKind| installed(op.catalog(), snap.controller.installed[g.index()]);
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

/// `params.set` of slithering with the old `compliance` object (docs/control-socket.md,
/// "Changes"): `controller` names a preset (or `open_loop`, `cpg`); the other keys
/// override its configuration; without `controller` they override what is installed.
/// The selection it names (new parameters go with it: `Act::SetController`).
pub(crate) fn compliance_selection(
    op: &Operator,
    gait: GaitKind,
    compliance: Value,
) -> Result<Selection, OperatorError> {
    let bad = |m: String| OperatorError::invalid_params(format!("`compliance`: {m}"));
    let Value::Object(mut map) = compliance else {
        return Err(bad("must be an object".into()));
    };
    let current = op.installed(gait);
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
    Ok(sel)
}

/// A controller's view with what became of it (`continuity`, and `why` where it
/// could not take the change in place).
pub(crate) fn with_continuity(mut view: Value, continuity: Option<Continuity>) -> Value {
    if let (Value::Object(map), Ok(Value::Object(c))) =
        (&mut view, serde_json::to_value(continuity))
    {
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
