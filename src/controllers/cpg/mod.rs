//! The thesis's baseline (SPEC §5): a distributed-feedback central pattern generator.

mod controller;

pub use controller::{Cpg, CpgGains};

use crate::controller_interface::report::{ReportSpec, SignalSpec};
use crate::controller_interface::{BuildContext, ConfigError, Controller, ControllerKind};
use crate::gait::GaitKind;

/// The registry's entry.
pub struct CpgKind;

impl ControllerKind for CpgKind {
    type Config = CpgGains;
    const NAME: &'static str = "cpg";
    const SUMMARY: &'static str =
        "phase oscillators per lateral joint, neighbour coupling, local torque feedback";
    const GAITS: &'static [GaitKind] = &[GaitKind::Slithering];
    const PRESETS: &'static [(&'static str, &'static str)] =
        &[("default", "the gains compared in the lab")];

    fn preset(name: &str) -> Option<Self::Config> {
        (name == "default").then(CpgGains::default)
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(_config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        ReportSpec {
            signals: vec![
                SignalSpec::new("amplitude_mean_rad", "rad"),
                SignalSpec::new("phase_lag_rad", "rad"),
                SignalSpec::new("phase_spread_rad", "rad"),
            ],
            fields: Vec::new(),
        }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(Cpg::new(ctx.layout, ctx.params, *config))
    }
}
