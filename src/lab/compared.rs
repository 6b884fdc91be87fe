//! The controllers a lab experiment compares: named ones (any name the registry
//! resolves for the experiment's gait: a controller or a preset) and variants with
//! their own configuration, `LABEL=JSON` on the command line.

use serde_json::Value;

use super::LabError;
use crate::controller_interface::config::merge;
use crate::controller_interface::registry::{self, BuildContext, Built, Selection};
use crate::controllers::REGISTRY;
use crate::gait::{BodyLayout, GaitKind, GaitParams};
use crate::navigation::navigator::{Choice, NavigatorConfig};

/// The controller a variant's overrides apply to when it names none.
pub const VARIANT_BASE: &str = "a_ws_omega";

/// One compared controller: its label in the report and what to build.
#[derive(Debug, Clone, PartialEq)]
pub struct LabController {
    pub label: String,
    pub gait: GaitKind,
    pub selection: Selection,
    /// Run by the navigator (`navigator`): the selection is its first choice's, and it
    /// changes gaits and controllers as it goes (lab::trial_navigator).
    pub navigator: Option<NavigatorConfig>,
}

/// The name that makes the navigator a compared "controller".
pub const NAVIGATOR: &str = "navigator";
/// The navigator that never slithers (only sidewinding, its turns and backing off).
pub const NAVIGATOR_SIDEWIND_ONLY: &str = "navigator_sidewind_only";
/// The navigator that only turns the body across, then sidewinds (no slithering, no
/// backing off).
pub const NAVIGATOR_TURN_ONLY: &str = "navigator_turn_only";
/// Every name that runs the navigator, as an experiment that compares gaits takes them.
pub const NAVIGATORS: &[&str] = &[NAVIGATOR, NAVIGATOR_SIDEWIND_ONLY, NAVIGATOR_TURN_ONLY];

impl LabController {
    /// For an experiment that compares gaits (`Experiment::any_gait`): the navigator,
    /// or a controller named in `gait` or else in the first other gait that has it.
    pub fn named_any(gait: GaitKind, name: &str) -> Result<Self, LabError> {
        let navigator = match name {
            NAVIGATOR => Some(NavigatorConfig::DEFAULT),
            NAVIGATOR_SIDEWIND_ONLY => Some(NavigatorConfig {
                slither: false,
                ..NavigatorConfig::DEFAULT
            }),
            NAVIGATOR_TURN_ONLY => Some(NavigatorConfig {
                slither: false,
                back_off: false,
                ..NavigatorConfig::DEFAULT
            }),
            _ => None,
        };
        if navigator.is_some() {
            // Installed first; its first decision may slither instead.
            let first = Choice::Sidewind;
            return Ok(Self {
                navigator,
                label: name.to_owned(),
                ..Self::named(first.gait(), first.controller())?
            });
        }
        let selection = Selection::named(name);
        let found = std::iter::once(gait)
            .chain(GaitKind::ALL)
            .find(|&g| registry::resolve(REGISTRY, g, &selection).is_ok());
        Self::named(found.unwrap_or(gait), name)
    }

    /// A named controller of `gait`, labelled by its name.
    pub fn named(gait: GaitKind, name: &str) -> Result<Self, LabError> {
        let selection = Selection::named(name);
        registry::resolve(REGISTRY, gait, &selection).map_err(|_| LabError::UnknownController {
            name: name.to_owned(),
            known: registry::known_names(REGISTRY, gait),
        })?;
        Ok(Self {
            label: name.to_owned(),
            gait,
            selection,
            navigator: None,
        })
    }

    /// `LABEL=JSON`: a variant. JSON is a selection (`{"controller": .., "preset": ..,
    /// "config": {..}}`, the controller [`VARIANT_BASE`] when not named); any other key
    /// overrides the configuration too, e.g. `soft={"amplitude":{"gains":{"stiffness":2}}}`.
    pub fn variant(gait: GaitKind, spec: &str) -> Result<Self, LabError> {
        Self::variant_on(gait, spec, VARIANT_BASE)
    }

    /// [`Self::variant`] over `base` when the JSON names no controller.
    pub fn variant_on(gait: GaitKind, spec: &str, base: &str) -> Result<Self, LabError> {
        Self::variant_in(&[gait], spec, base)
    }

    /// For an experiment that compares gaits: [`Self::variant_on`] in `gait` or else in
    /// the first other gait whose controllers the JSON's selection names.
    pub fn variant_any(gait: GaitKind, spec: &str, base: &str) -> Result<Self, LabError> {
        let mut gaits = vec![gait];
        gaits.extend(GaitKind::ALL.into_iter().filter(|&g| g != gait));
        Self::variant_in(&gaits, spec, base)
    }

    /// A variant in the first of `gaits` (not empty) that resolves its selection.
    fn variant_in(gaits: &[GaitKind], spec: &str, base: &str) -> Result<Self, LabError> {
        let gait = gaits[0];
        let bad = |msg: String| LabError::BadValue(format!("--variant {spec:?}: {msg}"));
        let (label, json) = spec
            .split_once('=')
            .ok_or_else(|| bad("expected LABEL=JSON".into()))?;
        let label = label.trim();
        let label_ok = !label.is_empty()
            && label
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !label_ok {
            return Err(bad(
                "the label must be non-empty letters, digits, `_` or `-` (it names files)".into(),
            ));
        }
        if registry::resolve(REGISTRY, gait, &Selection::named(label)).is_ok() {
            return Err(bad(format!("the label {label:?} is a named controller's")));
        }
        let value: Value = serde_json::from_str(json).map_err(|e| bad(format!("not JSON: {e}")))?;
        let Value::Object(mut map) = value else {
            return Err(bad("the JSON must be an object".into()));
        };
        let text = |v: Option<Value>, key: &str| match v {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(_) => Err(bad(format!("`{key}` must be a string"))),
        };
        let controller =
            text(map.remove("controller"), "controller")?.unwrap_or_else(|| base.into());
        let preset = text(map.remove("preset"), "preset")?;
        let mut config = map.remove("config");
        if !map.is_empty() {
            let c = config.get_or_insert_with(|| Value::Object(Default::default()));
            merge(c, &Value::Object(map));
        }
        if controller == NAVIGATOR {
            // The navigator's settings (docs/navigation.md), as `navigate` takes them.
            let cfg: NavigatorConfig = match config {
                None => NavigatorConfig::DEFAULT,
                Some(v) => serde_json::from_value(v).map_err(|e| bad(e.to_string()))?,
            };
            cfg.check().map_err(|e| bad(e.to_string()))?;
            let first = Choice::Sidewind;
            return Ok(Self {
                navigator: Some(cfg),
                label: label.to_owned(),
                ..Self::named(first.gait(), first.controller())?
            });
        }
        let selection = Selection {
            controller,
            preset,
            config,
        };
        let gait = gaits
            .iter()
            .copied()
            .find(|&g| registry::resolve(REGISTRY, g, &selection).is_ok())
            .map_or_else(
                || {
                    registry::resolve(REGISTRY, gait, &selection)
                        .map(|_| gait)
                        .map_err(|e| bad(e.to_string()))
                },
                Ok,
            )?;
        Ok(Self {
            label: label.to_owned(),
            gait,
            selection,
            navigator: None,
        })
    }

    /// Builds the controller (allocates; once per trial).
    pub fn build(&self, layout: &BodyLayout, params: &GaitParams) -> Result<Built, LabError> {
        let ctx = BuildContext {
            gait: self.gait,
            layout,
            params,
        };
        registry::build(REGISTRY, &self.selection, &ctx)
            .map_err(|e| LabError::BadValue(format!("controller {}: {e}", self.label)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::trial::slithering_setup;

    const G: GaitKind = GaitKind::Slithering;

    #[test]
    fn a_variant_overrides_the_full_controller() {
        let v =
            LabController::variant(G, r#"stiff={"amplitude":{"gains":{"stiffness":9}}}"#).unwrap();
        assert_eq!(v.label, "stiff");
        assert_eq!(v.selection.controller, VARIANT_BASE);
        let (layout, params) = slithering_setup(18);
        let built = v.build(&layout, &params).unwrap();
        assert_eq!(built.info.config["amplitude"]["gains"]["stiffness"], 9.0);
        assert_eq!(built.info.config["spatial_freq"]["gains"]["stiffness"], 0.3);
    }

    #[test]
    fn a_variant_can_start_from_another_preset() {
        let v =
            LabController::variant(G, r#"a2={"controller":"a","torque_deadband_nm":0.5}"#).unwrap();
        let (layout, params) = slithering_setup(18);
        let built = v.build(&layout, &params).unwrap();
        assert_eq!(built.info.preset, "a");
        assert_eq!(built.info.config["spatial_freq"]["enabled"], false);
        assert_eq!(built.info.config["torque_deadband_nm"], 0.5);
    }

    #[test]
    fn bad_variants_say_what_is_wrong() {
        let err = |s: &str| LabController::variant(G, s).unwrap_err().to_string();
        assert!(err("noequals").contains("LABEL=JSON"));
        assert!(err("={}").contains("label"));
        assert!(err("a b={}").contains("label"));
        assert!(err("a={}").contains("named controller"));
        assert!(err("x={").contains("not JSON"));
        assert!(err(r#"x={"controller":"fast"}"#).contains("unknown controller"));
        // Checked against the configuration's type and the gait's parameters when built.
        let (layout, params) = slithering_setup(18);
        let v = LabController::variant(G, r#"x={"amplitude":{"gain":{}}}"#).unwrap();
        let e = v.build(&layout, &params).err().unwrap().to_string();
        assert!(e.contains("config.amplitude"), "{e}");
        let v = LabController::variant(G, r#"x={"amplitude":{"gains":{"min":0.9,"max":1.0}}}"#)
            .unwrap();
        let e = v.build(&layout, &params).err().unwrap().to_string();
        assert!(e.contains("outside the controller's range"), "{e}");
        assert!(LabController::named(G, "nope").is_err());
        assert!(LabController::named(G, "a_ws").is_ok());
    }

    #[test]
    fn a_navigator_variant_takes_the_navigator_s_settings() {
        let v = LabController::variant_any(
            G,
            r#"nav7={"controller":"navigator","back_off":false}"#,
            VARIANT_BASE,
        )
        .unwrap();
        let cfg = v.navigator.unwrap();
        assert!(!cfg.back_off);
        assert_eq!(cfg.settle_s, NavigatorConfig::DEFAULT.settle_s);
        assert_eq!(v.label, "nav7");
        let e = LabController::variant_any(G, r#"n={"controller":"navigator","nope":1}"#, "a")
            .unwrap_err()
            .to_string();
        assert!(e.contains("nope"), "{e}");
        let e = LabController::variant_any(G, r#"n={"controller":"navigator","settle_s":-1}"#, "a")
            .unwrap_err()
            .to_string();
        assert!(e.contains("settle_s"), "{e}");
    }
}
