//! The open-loop serpenoid of any gait (SPEC §2): what the selector blends into,
//! continued from its phase. The default controller of every gait.

use serde::{Deserialize, Serialize};

use crate::controller_interface::report::{ControllerReport, ReportSpec, SignalSpec};
use crate::controller_interface::{
    BuildContext, ConfigError, Controller, ControllerKind, Handover, NominalMismatch, Observation,
    Tick,
};
use crate::gait::{BodyLayout, GaitKind, GaitParams, Serpenoid};

/// It has nothing to configure.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpenLoopConfig {}

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
        (name == "default").then_some(OpenLoopConfig {})
    }

    fn check(_config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        Ok(())
    }

    fn report_spec(_config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        ReportSpec {
            signals: vec![SignalSpec::new("phase_rad", "rad")],
            fields: Vec::new(),
        }
    }

    fn build(_config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(OpenLoop::new(ctx.gait, ctx.layout, ctx.params))
    }
}

/// The serpenoid of `kind`, its phase `ψ₀ + ωT·(t − t₀)` from the handover.
pub struct OpenLoop {
    kind: GaitKind,
    layout: BodyLayout,
    wave: Serpenoid,
    phase0: f64,
    t0: f64,
    phase: f64,
}

impl OpenLoop {
    pub fn new(kind: GaitKind, layout: &BodyLayout, params: &GaitParams) -> Self {
        Self {
            kind,
            layout: layout.clone(),
            wave: Serpenoid::for_layout(kind, params, layout),
            phase0: 0.0,
            t0: 0.0,
            phase: 0.0,
        }
    }
}

impl Controller for OpenLoop {
    /// The selector has validated the gait's parameters; the serpenoid runs any.
    fn accepts(&self, _params: &GaitParams) -> Result<(), NominalMismatch> {
        Ok(())
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.wave = Serpenoid::for_layout(self.kind, h.params, &self.layout);
        self.phase0 = h.phase_rad;
        self.t0 = h.t_s;
        self.phase = h.phase_rad;
    }

    fn step(&mut self, tick: Tick, _obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let t_s = tick.t_s;
        self.phase = self.phase0 + self.wave.temporal_freq_rad_s * (t_s - self.t0);
        self.wave.evaluate(&self.layout, self.phase, set_points_rad);
    }

    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        out.signals[0] = self.phase;
    }
}
