//! Compliant slithering (thesis §4.1, SPEC §5): amplitude, spatial frequency and
//! temporal phase follow shape-space admittance, each central, windowed or per joint.

mod config;
mod controller;

pub use config::{Centralization, CompliantSlitheringConfig, ParamConfig, SPATIAL_FREQ_GAINS};
pub use controller::CompliantSlithering;

use crate::controller_interface::report::{FieldSpec, ReportSpec, SignalSpec};
use crate::controller_interface::{BuildContext, ConfigError, Controller, ControllerKind};
use crate::controllers::steering::HeadingHold;
use crate::gait::GaitKind;
use crate::shape::slithering_shape::Param;

/// The registry's entry.
pub struct CompliantSlitheringKind;

impl ControllerKind for CompliantSlitheringKind {
    type Config = CompliantSlitheringConfig;
    const NAME: &'static str = "compliant_slithering";
    const SUMMARY: &'static str =
        "shape-based compliance: amplitude, spatial frequency and phase follow the torques";
    const GAITS: &'static [GaitKind] = &[GaitKind::Slithering];
    const PRESETS: &'static [(&'static str, &'static str)] = CompliantSlitheringConfig::PRESETS;

    fn preset(name: &str) -> Option<Self::Config> {
        CompliantSlitheringConfig::preset(name)
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        let s = SignalSpec::new;
        let mut signals = vec![
            s("amplitude_mean_rad", "rad"),
            s("spatial_freq_mean_rad", "rad/body length"),
            s("phase_lag_rad", "rad"),
            s("windows", "count"),
            s("windows_born", "count"),
            s("windows_dropped", "count"),
            s("force_amplitude_peak", "N·m"),
            s("force_spatial_freq_peak", "N·m·body length"),
            s("force_phase_peak", "N·m"),
        ];
        signals.extend(HeadingHold::SIGNALS.map(|(name, unit)| s(name, unit)));
        debug_assert_eq!(signals.len(), controller::SIGNALS);
        let units = [
            ("rad", "N·m"),
            ("rad/body length", "N·m·body length"),
            ("rad", "N·m"),
        ];
        let fields = Param::ALL
            .iter()
            .zip(units)
            .map(|(&p, (value, force))| {
                let pc = config.param(p);
                let value_name = if p == Param::Phase { "lag" } else { "value" };
                FieldSpec {
                    name: p.name().to_owned(),
                    centralization: pc.centralization.name().to_owned(),
                    enabled: pc.enabled,
                    columns: vec![s(value_name, value), s("force", force)],
                }
            })
            .collect();
        ReportSpec { signals, fields }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(CompliantSlithering::new(ctx.layout, ctx.params, *config))
    }
}
