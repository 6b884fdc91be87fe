//! The controllers a lab experiment compares: the named ones
//! ([`crate::shape::SLITHERING_CONTROLLERS`]) and variants with their own gains,
//! `LABEL=JSON` on the command line, where JSON is the `compliance` object of the
//! daemon's `params.set` (docs/control-socket.md) over the full controller.

use super::LabError;
use crate::gait::GaitParams;
use crate::gait::layout::BodyLayout;
use crate::rt::compliance::ComplianceSetting;
use crate::rt::compliance_json;
use crate::shape::{JointController, SLITHERING_CONTROLLERS};

/// The controller a variant's overrides apply to when it names none.
pub const VARIANT_BASE: &str = "a_ws_omega";

/// One compared controller: its label in the report and how to build it.
#[derive(Debug, Clone, PartialEq)]
pub struct LabController {
    pub label: String,
    pub setting: ComplianceSetting,
}

impl LabController {
    /// A named controller, labelled by its name.
    pub fn named(name: &str) -> Result<Self, LabError> {
        let setting = ComplianceSetting::named(name).map_err(|_| LabError::UnknownController {
            name: name.to_owned(),
            known: SLITHERING_CONTROLLERS.join(", "),
        })?;
        Ok(Self {
            label: name.to_owned(),
            setting,
        })
    }

    /// `LABEL=JSON`: a variant (e.g. `soft_a={"amplitude":{"gains":{"stiffness":2}}}`).
    pub fn variant(spec: &str) -> Result<Self, LabError> {
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
        if SLITHERING_CONTROLLERS.contains(&label) {
            return Err(bad(format!("the label {label:?} is a named controller's")));
        }
        let value: serde_json::Value =
            serde_json::from_str(json).map_err(|e| bad(format!("not JSON: {e}")))?;
        let base = ComplianceSetting::named(VARIANT_BASE).expect("the base is a named controller");
        let setting = compliance_json::parse(&value, &base).map_err(bad)?;
        Ok(Self {
            label: label.to_owned(),
            setting,
        })
    }

    /// Builds the controller (allocates; once per trial).
    pub fn build(
        &self,
        layout: &BodyLayout,
        params: &GaitParams,
    ) -> Result<Box<dyn JointController>, LabError> {
        self.setting
            .controller(layout, params)
            .map_err(|e| LabError::BadValue(format!("controller {}: {e}", self.label)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::trial::slithering_setup;

    #[test]
    fn a_variant_overrides_the_full_controller() {
        let v = LabController::variant(r#"stiff={"amplitude":{"gains":{"stiffness":9}}}"#).unwrap();
        assert_eq!(v.label, "stiff");
        assert_eq!(v.setting.controller, VARIANT_BASE);
        let config = v.setting.config.unwrap();
        assert_eq!(config.amplitude.gains.stiffness, 9.0);
        let full = ComplianceSetting::named(VARIANT_BASE)
            .unwrap()
            .config
            .unwrap();
        assert_eq!(config.spatial_freq, full.spatial_freq);
        let (layout, params) = slithering_setup(18);
        assert!(v.build(&layout, &params).is_ok());
    }

    #[test]
    fn a_variant_can_start_from_another_preset() {
        let v =
            LabController::variant(r#"a2={"controller":"a","torque_deadband_nm":0.5}"#).unwrap();
        assert_eq!(v.setting.controller, "a");
        assert!(!v.setting.config.unwrap().spatial_freq.enabled);
    }

    #[test]
    fn bad_variants_say_what_is_wrong() {
        let err = |s: &str| LabController::variant(s).unwrap_err().to_string();
        assert!(err("noequals").contains("LABEL=JSON"));
        assert!(err("={}").contains("label"));
        assert!(err("a b={}").contains("label"));
        assert!(err("a={}").contains("named controller"));
        assert!(err("x={").contains("not JSON"));
        assert!(err(r#"x={"amplitude":{"gain":{}}}"#).contains("compliance.amplitude.gain"));
        // Checked against the gait's nominal parameters when built.
        let v = LabController::variant(r#"x={"amplitude":{"gains":{"min":2,"max":3}}}"#).unwrap();
        let (layout, params) = slithering_setup(18);
        let e = v.build(&layout, &params).err().unwrap().to_string();
        assert!(e.contains("outside the compliance range"), "{e}");
        assert!(LabController::named("nope").is_err());
    }
}
