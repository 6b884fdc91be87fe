//! Compliant slithering in the daemon: which controller runs slithering (the
//! [`ComplianceSetting`]), how a built controller travels to the loop
//! ([`ControllerChange`], attached to a request's envelope), and what the loop reports
//! about it ([`ComplianceTelemetry`]).
//!
//! Building a controller allocates, so it never happens in the loop thread: the control
//! side builds it ([`ComplianceSetting::build`]) and sends it with the request; the loop
//! sends the controller it replaces back through a bounded "retired" channel for the
//! control side to free (see [`super::slithering_driver`]).
use std::fmt;

use serde::Serialize;

use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD};
use crate::shape::slithering_shape::Param;
use crate::shape::{
    ComplianceReport, CompliantSlithering, JointController, SLITHERING_CONTROLLERS,
    SlitheringCompliance, slithering_controller,
};

/// The controller that runs slithering when none is set: the selector's serpenoid.
pub const OPEN_LOOP: &str = "open_loop";

/// Which controller runs slithering, and the compliance of a shape-based one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComplianceSetting {
    /// One of [`SLITHERING_CONTROLLERS`].
    pub controller: &'static str,
    /// The compliance of a shape-based controller (its preset, possibly with
    /// overrides); `None` for open loop and the CPG.
    pub config: Option<SlitheringCompliance>,
}

impl ComplianceSetting {
    pub const OPEN_LOOP: ComplianceSetting = ComplianceSetting {
        controller: OPEN_LOOP,
        config: None,
    };

    /// The controller called `name` with its preset compliance.
    pub fn named(name: &str) -> Result<Self, String> {
        let controller = SLITHERING_CONTROLLERS
            .iter()
            .copied()
            .find(|n| *n == name)
            .ok_or_else(|| {
                format!(
                    "unknown slithering controller `{name}` (known: {})",
                    SLITHERING_CONTROLLERS.join(", ")
                )
            })?;
        Ok(Self {
            controller,
            config: SlitheringCompliance::preset(name),
        })
    }

    pub fn is_open_loop(&self) -> bool {
        self.controller == OPEN_LOOP
    }

    /// Whether the slithering nominal `params` suit this compliance: each compliant
    /// parameter's nominal value lies in its range (else the controller would clamp it
    /// at its first step and the wave would jump), the amplitude's range stays within
    /// the joint range with the lateral offset, and the temporal phase (whose nominal
    /// grows with time) is unbounded.
    pub fn check(&self, params: &GaitParams) -> Result<(), String> {
        let Some(config) = &self.config else {
            return Ok(());
        };
        config.validate().map_err(|e| format!("compliance.{e}"))?;
        for (p, nominal, field) in [
            (
                Param::Amplitude,
                params.amplitude_lat_rad,
                "amplitude_lat_rad",
            ),
            (
                Param::SpatialFreq,
                params.spatial_freq_rad,
                "spatial_freq_rad",
            ),
        ] {
            let pc = config.param(p);
            let (min, max) = (pc.gains.min, pc.gains.max);
            if pc.enabled && !(min..=max).contains(&nominal) {
                return Err(format!(
                    "compliance.{}: the nominal {field} = {nominal} is outside the compliance \
                     range [{min}, {max}]",
                    p.name()
                ));
            }
        }
        let amplitude = &config.amplitude;
        let reach = params.offset_lat_rad.abs() + amplitude.gains.max;
        if amplitude.enabled && reach > JOINT_LIMIT_RAD + 1e-12 {
            return Err(format!(
                "compliance.amplitude.gains.max = {} with offset_lat_rad = {} would bend \
                 joints to {reach:.3} rad, beyond the joint range of {JOINT_LIMIT_RAD:.3} rad",
                amplitude.gains.max, params.offset_lat_rad
            ));
        }
        let phase = &config.phase;
        if phase.enabled && (phase.gains.min.is_finite() || phase.gains.max.is_finite()) {
            return Err(
                "compliance.phase.gains: the temporal phase grows with time; its min and max \
                 must be unbounded (null)"
                    .into(),
            );
        }
        Ok(())
    }

    /// Builds the controller for `layout` with nominal `params` (allocates: never in
    /// the loop thread). Open loop is [`ControllerChange::OpenLoop`].
    pub fn build(
        &self,
        layout: &BodyLayout,
        params: &GaitParams,
    ) -> Result<ControllerChange, String> {
        self.check(params)?;
        if self.is_open_loop() {
            return Ok(ControllerChange::OpenLoop);
        }
        Ok(ControllerChange::Install(InstalledController {
            controller: self.controller(layout, params)?,
            setting: *self,
        }))
    }

    /// The controller itself, open loop included (allocates). The lab runs these.
    pub fn controller(
        &self,
        layout: &BodyLayout,
        params: &GaitParams,
    ) -> Result<Box<dyn JointController>, String> {
        self.check(params)?;
        match self.config {
            Some(config) => Ok(Box::new(CompliantSlithering::new(
                self.controller,
                layout,
                params,
                config,
            )?)),
            None => slithering_controller(self.controller, layout, params),
        }
    }
}

/// A built controller and the setting it was built from.
pub struct InstalledController {
    pub controller: Box<dyn JointController>,
    pub setting: ComplianceSetting,
}

/// A change of slithering controller, attached to a request for the loop.
// Moved through the bounded request channel as it is: boxing the setting would give
// the loop one more allocation to hand back.
#[allow(clippy::large_enum_variant)]
pub enum ControllerChange {
    /// Back to the selector's open-loop serpenoid.
    OpenLoop,
    /// Run slithering with this controller.
    Install(InstalledController),
}

impl ControllerChange {
    /// The setting after the change.
    pub fn setting(&self) -> ComplianceSetting {
        match self {
            ControllerChange::OpenLoop => ComplianceSetting::OPEN_LOOP,
            ControllerChange::Install(c) => c.setting,
        }
    }
}

impl fmt::Debug for ControllerChange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ControllerChange::OpenLoop => write!(f, "OpenLoop"),
            ControllerChange::Install(c) => write!(f, "Install({})", c.setting.controller),
        }
    }
}

/// Whether the slithering controller drives the joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Engagement {
    /// No controller: slithering is the selector's open-loop serpenoid.
    Off,
    /// A controller is set but the selector drives: another gait is active, a blend
    /// into slithering is running, or the loop holds.
    Waiting,
    /// The controller drives slithering.
    Engaged,
}

/// What the loop publishes about compliant slithering every cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComplianceTelemetry {
    pub setting: ComplianceSetting,
    pub engagement: Engagement,
    /// The controller's report after its last step (`available` false unless engaged).
    pub report: ComplianceReport,
    /// Windows born and dropped since this controller was installed.
    pub windows_born: u64,
    pub windows_dropped: u64,
    /// Times this controller took over from the selector.
    pub takeovers: u64,
    /// Replaced controllers the loop had to free itself because the retired channel was
    /// full (an allocator call in the loop; stays 0 when the control side drains it).
    pub freed_in_loop: u64,
}

impl Default for ComplianceTelemetry {
    fn default() -> Self {
        Self {
            setting: ComplianceSetting::OPEN_LOOP,
            engagement: Engagement::Off,
            report: ComplianceReport::EMPTY,
            windows_born: 0,
            windows_dropped: 0,
            takeovers: 0,
            freed_in_loop: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::{GaitKind, Plane};

    fn slithering() -> GaitParams {
        GaitParams::default_for(GaitKind::Slithering)
    }

    #[test]
    fn every_controller_builds_and_open_loop_is_no_controller() {
        let layout = BodyLayout::alternating(18, Plane::Lateral, 0.064);
        for name in SLITHERING_CONTROLLERS {
            let s = ComplianceSetting::named(name).unwrap();
            let change = s.build(&layout, &slithering()).unwrap();
            match change {
                ControllerChange::OpenLoop => assert_eq!(*name, OPEN_LOOP),
                ControllerChange::Install(c) => assert_eq!(c.controller.name(), *name),
            }
        }
        let e = ComplianceSetting::named("fast").unwrap_err();
        assert!(e.contains("fast") && e.contains("a_ws_omega"), "{e}");
    }

    #[test]
    fn nominal_params_outside_a_compliant_range_are_refused() {
        let s = ComplianceSetting::named("a_ws").unwrap();
        let mut p = slithering();
        p.spatial_freq_rad = 5.0 * std::f64::consts::PI;
        let e = s.check(&p).unwrap_err();
        assert!(
            e.contains("spatial_freq_rad") && e.contains("compliance"),
            "{e}"
        );
        // `a` leaves ωS alone, so any ωS is fine.
        assert!(ComplianceSetting::named("a").unwrap().check(&p).is_ok());
        let mut p = slithering();
        p.offset_lat_rad = 0.5;
        let e = s.check(&p).unwrap_err();
        assert!(e.contains("joint range"), "{e}");
        let mut bounded = ComplianceSetting::named("a_ws_omega").unwrap();
        if let Some(c) = &mut bounded.config {
            c.phase.gains.max = 100.0;
        }
        assert!(bounded.check(&slithering()).unwrap_err().contains("phase"));
    }
}
