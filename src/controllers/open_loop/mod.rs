//! The open-loop serpenoid of any gait (SPEC §2): what the selector blends into,
//! continued from its phase. The default controller of every gait. Slithering may
//! hold a heading by its lateral offset (`steering`, see `controllers::steering`).

use serde::{Deserialize, Serialize};

use crate::controller_interface::nominal::Nominal;
use crate::controller_interface::report::{ControllerReport, ReportSpec, SignalSpec};
use crate::controller_interface::{
    BuildContext, CannotFollow, Capabilities, CommandRefused, ConfigError, Controller,
    ControllerCommand, ControllerKind, Handover, NominalMismatch, Observation, Tick, same_kind,
};
use crate::controllers::steering::{HeadingHold, SteeringConfig};
use crate::gait::{BodyLayout, GaitKind, GaitParams, Serpenoid};

/// Only slithering's heading hold (off until given a heading).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpenLoopConfig {
    #[serde(default)]
    pub steering: SteeringConfig,
}

/// The registry's entry.
pub struct OpenLoopKind;

impl ControllerKind for OpenLoopKind {
    type Config = OpenLoopConfig;
    const NAME: &'static str = "open_loop";
    const SUMMARY: &'static str = "the gait's serpenoid, no feedback";
    const GAITS: &'static [GaitKind] = &GaitKind::ALL;
    const PRESETS: &'static [(&'static str, &'static str)] =
        &[("default", "the gait's nominal parameters")];

    fn preset(name: &str) -> Option<Self::Config> {
        (name == "default").then_some(OpenLoopConfig::default())
    }

    fn check(config: &Self::Config, ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.steering.check().map_err(|e| e.under("steering"))?;
        if config.steering.hold_at_engage && ctx.gait != GaitKind::Slithering {
            return Err(ConfigError::invalid(
                "steering.hold_at_engage",
                "only slithering steers by its lateral offset",
            ));
        }
        Ok(())
    }

    fn report_spec(_config: &Self::Config, ctx: &BuildContext<'_>) -> ReportSpec {
        let mut signals = vec![SignalSpec::new("phase_rad", "rad")];
        if ctx.gait == GaitKind::Slithering {
            signals.extend(HeadingHold::SIGNALS.map(|(n, u)| SignalSpec::new(n, u)));
        }
        ReportSpec {
            signals,
            fields: Vec::new(),
        }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        let mut c = OpenLoop::new(ctx.gait, ctx.layout, ctx.params);
        if ctx.gait == GaitKind::Slithering {
            c.heading = Some(HeadingHold::new(config.steering));
        }
        Box::new(c)
    }
}

/// The serpenoid of `kind`, its phase `ψ₀ + ∫ωT dt` from the handover.
pub struct OpenLoop {
    kind: GaitKind,
    layout: BodyLayout,
    nominal: Nominal,
    wave: Serpenoid,
    phase: f64,
    /// Slithering's heading hold.
    heading: Option<HeadingHold>,
}

impl OpenLoop {
    pub fn new(kind: GaitKind, layout: &BodyLayout, params: &GaitParams) -> Self {
        Self {
            kind,
            layout: layout.clone(),
            nominal: Nominal::new(params),
            wave: Serpenoid::for_layout(kind, params, layout),
            phase: 0.0,
            heading: None,
        }
    }
}

impl Controller for OpenLoop {
    /// The selector has validated the gait's parameters; the serpenoid runs any.
    fn accepts(&self, _params: &GaitParams) -> Result<(), NominalMismatch> {
        Ok(())
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.nominal = Nominal::engaged(h);
        self.wave = Serpenoid::for_layout(self.kind, h.params, &self.layout);
        self.phase = h.phase_rad;
        if let Some(heading) = &mut self.heading {
            heading.engage(h.params);
        }
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let t_s = tick.t_s;
        if self.nominal.ramping(t_s) || self.nominal.params != *self.nominal.target() {
            self.nominal.advance(t_s);
            self.wave = Serpenoid::for_layout(self.kind, &self.nominal.params, &self.layout);
        }
        self.phase = self.nominal.phase_at(t_s);
        self.wave.evaluate(&self.layout, self.phase, set_points_rad);
        if let Some(heading) = &mut self.heading {
            heading.set_nominal_offset(self.nominal.params.offset_lat_rad);
            heading.step(tick, obs.body, self.wave.lateral.amplitude_rad.abs());
            heading.add_to(&self.layout, set_points_rad);
        }
    }

    /// Any change: the serpenoid ramps to it (`Nominal::follow`).
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        self.nominal.follow(t_s, params);
        if let Some(heading) = &mut self.heading {
            heading.follow(params);
        }
        Ok(())
    }

    /// Only the steering has settings: in place.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        match (&mut self.heading, &new.heading) {
            (Some(mine), Some(theirs)) => mine.set_config(*theirs.config()),
            (None, None) => {}
            _ => return Err(CannotFollow("another gait")),
        }
        Ok(())
    }

    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        out.signals[0] = self.phase;
        if let Some(heading) = &self.heading {
            out.signals[1..5].copy_from_slice(&heading.signals());
        }
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            steers_by_heading: self.heading.as_ref().is_some_and(|h| h.holds_heading()),
            calibration: None,
        }
    }

    /// `SetHeading` while slithering: the direction the steering holds.
    fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        match &mut self.heading {
            Some(heading) => heading.command(command),
            None => Err(CommandRefused::unsupported(command)),
        }
    }
}
