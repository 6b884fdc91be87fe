//! The operator's parameters, named alike on every edge (Foxglove's Parameters panel,
//! ROS 2's parameter services): the active gait, its parameters and its controller's
//! configuration, read live from the loop's snapshot, set through the typed acts
//! (`Act::SetGait`, `Act::SetParams`, `Act::SetController`) with their checks.
//!
//! Names: `gait` (string), `params.<field>` (the active gait's, numbers),
//! `controller.name`, `controller.preset` (strings) and `controller.config.<path>` (the
//! configuration's numbers, booleans and strings, dotted).

use serde_json::{Map, Value, json};

use super::{Act, Operator};
use crate::controller_interface::Selection;
use crate::gait::params::Field;
use crate::gait::{GaitKind, ParamPatch};

/// What the parameters are read from.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveParameters {
    pub gait: GaitKind,
    pub params: Map<String, Value>,
    /// The gait's controller: `controller`, `preset`, `config` (null without one).
    pub controller: Value,
}

impl LiveParameters {
    /// The active gait, its parameters and its controller, from the loop's snapshot.
    pub fn read(api: &Operator) -> Self {
        let s = api.snapshot();
        let gait = s.gait;
        let params = match serde_json::to_value(s.params.get(gait)) {
            Ok(Value::Object(m)) => m,
            _ => Map::new(),
        };
        let controller = match api.installed(gait) {
            Some(i) => {
                json!({ "controller": i.controller, "preset": i.preset, "config": i.config })
            }
            None => Value::Null,
        };
        Self {
            gait,
            params,
            controller,
        }
    }

    /// Every parameter, named, in order: its value a JSON number, boolean or string.
    pub fn all(&self) -> Vec<(String, Value)> {
        let mut out = vec![("gait".to_owned(), json!(self.gait.name()))];
        for (k, v) in &self.params {
            leaf(format!("params.{k}"), v, &mut out);
        }
        if self.controller.is_object() {
            leaf(
                "controller.name".into(),
                &self.controller["controller"],
                &mut out,
            );
            leaf(
                "controller.preset".into(),
                &self.controller["preset"],
                &mut out,
            );
            flatten("controller.config", &self.controller["config"], &mut out);
        }
        out
    }

    /// The act setting parameter `name` to `value`.
    pub fn act_for(&self, name: &str, value: Value) -> Result<Act, String> {
        if name == "gait" {
            let gait = value
                .as_str()
                .and_then(GaitKind::from_name)
                .ok_or_else(|| format!("gait: not a gait: {value}"))?;
            return Ok(Act::SetGait { gait });
        }
        if let Some(field) = name.strip_prefix("params.") {
            let field = Field::ALL
                .into_iter()
                .find(|f| f.name() == field)
                .ok_or_else(|| format!("no parameter {name:?}"))?;
            let x = value
                .as_f64()
                .ok_or_else(|| format!("{name} must be a number, not {value}"))?;
            let mut patch = ParamPatch::default();
            field.set_in_patch(&mut patch, x);
            return Ok(Act::SetParams {
                gait: self.gait,
                patch,
            });
        }
        let c = &self.controller;
        if !c.is_object() {
            return Err(format!(
                "{name}: the {} gait has no controller",
                self.gait.name()
            ));
        }
        let text = |v: &Value| v.as_str().map(str::to_owned);
        let mut sel = Selection {
            controller: text(&c["controller"]).unwrap_or_default(),
            preset: text(&c["preset"]),
            config: None,
        };
        match name {
            "controller.name" => {
                sel.controller = text(&value).ok_or_else(|| format!("{name} must be a string"))?;
                sel.preset = None;
            }
            "controller.preset" => {
                sel.preset = Some(text(&value).ok_or_else(|| format!("{name} must be a string"))?);
            }
            _ => {
                let path = name
                    .strip_prefix("controller.config.")
                    .ok_or_else(|| format!("no parameter {name:?}"))?;
                let mut config = c["config"].clone();
                let mut at = &mut config;
                for key in path.split('.') {
                    at = at.get_mut(key).ok_or_else(|| {
                        format!("no parameter {name:?} in the controller's configuration")
                    })?;
                }
                *at = value;
                sel.config = Some(config);
            }
        }
        Ok(Act::SetController {
            gait: self.gait,
            selection: sel,
            patch: ParamPatch::default(),
        })
    }
}

/// A leaf worth naming: numbers, booleans, strings (null and arrays are not parameters).
fn leaf(name: String, v: &Value, out: &mut Vec<(String, Value)>) {
    if v.is_number() || v.is_boolean() || v.is_string() {
        out.push((name, v.clone()));
    }
}

/// `config`'s leaves as dotted names under `prefix`.
fn flatten(prefix: &str, v: &Value, out: &mut Vec<(String, Value)>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                flatten(&format!("{prefix}.{k}"), x, out);
            }
        }
        other => leaf(prefix.to_owned(), other, out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn live() -> LiveParameters {
        LiveParameters {
            gait: GaitKind::Slithering,
            params: json!({"temporal_freq_rad_s": 1.0})
                .as_object()
                .cloned()
                .unwrap(),
            controller: json!({"controller": "compliant_slithering", "preset": "a_ws_omega",
                "config": {"amplitude": {"enabled": true, "gains": {"min": 0.2}}}}),
        }
    }

    /// An act as the socket's method and params.
    fn request_for(
        l: &LiveParameters,
        name: &str,
        value: Value,
    ) -> Result<(&'static str, Value), String> {
        l.act_for(name, value)
            .map(|a| (a.method(), crate::socket::act_params(&a)))
    }

    #[test]
    fn parameters_are_named_and_set_through_the_operator_s_acts() {
        let l = live();
        let names: Vec<String> = l.all().into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            [
                "gait",
                "params.temporal_freq_rad_s",
                "controller.name",
                "controller.preset",
                "controller.config.amplitude.enabled",
                "controller.config.amplitude.gains.min",
            ]
        );
        assert_eq!(
            request_for(&l, "gait", json!("rolling")).unwrap(),
            ("gait.set", json!({"gait": "rolling"}))
        );
        let (m, p) = request_for(&l, "params.temporal_freq_rad_s", json!(0.5)).unwrap();
        assert_eq!(
            (m, p),
            (
                "params.set",
                json!({"gait": "slithering", "temporal_freq_rad_s": 0.5})
            )
        );
        let (m, p) = request_for(&l, "controller.config.amplitude.gains.min", json!(0.3)).unwrap();
        assert_eq!(m, "controller.set");
        assert_eq!(p["config"]["amplitude"]["gains"]["min"], 0.3);
        assert_eq!(p["config"]["amplitude"]["enabled"], true, "the rest kept");
        assert_eq!(p["preset"], "a_ws_omega");
        let (_, p) = request_for(&l, "controller.name", json!("open_loop")).unwrap();
        assert_eq!(
            p,
            json!({"gait": "slithering", "controller": "open_loop", "preset": null, "config": null})
        );
        assert!(request_for(&l, "controller.config.nope", json!(1)).is_err());
        assert!(request_for(&l, "whatever", json!(1)).is_err());
        assert!(request_for(&l, "params.temporal_freq_rad_s", json!("fast")).is_err());
    }
}
