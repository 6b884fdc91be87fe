//! Anti-compliant sidewinding with inertial steering (thesis §4.3, SPEC §7): the lateral
//! amplitude (windowed) and spatial frequency (central) push back against what pushes
//! the body; the dorsal offset β reverses the gait when the pose estimate's heading has
//! been turned round, and an amplitude gradient along the body turns it back to its nominal heading.
//! See docs/compliance.md, "Sidewinding".

mod config;
mod controller;
mod heading;
mod reversal;

pub use config::SidewindingConfig;
pub use controller::AntiCompliantSidewinding;
pub use heading::{HeadingAdjust, HeadingConfig, taper_factor};
pub use reversal::{Reversal, ReversalConfig, wrap_pi};

use crate::controller_interface::report::{ReportSpec, SignalSpec};
use crate::controller_interface::{BuildContext, ConfigError, Controller, ControllerKind};
use crate::controllers::compliant_slithering::CompliantSlitheringKind;
use crate::gait::GaitKind;

/// The registry's entry.
pub struct SidewindingKind;

impl ControllerKind for SidewindingKind {
    type Config = SidewindingConfig;
    const NAME: &'static str = "anti_compliant_sidewinding";
    const SUMMARY: &'static str = "sidewinding that pushes back (amplitude, spatial frequency), \
         reverses when turned round and steers back to its heading";
    const GAITS: &'static [GaitKind] = &[GaitKind::Sidewinding];
    const PRESETS: &'static [(&'static str, &'static str)] = SidewindingConfig::PRESETS;

    fn preset(name: &str) -> Option<Self::Config> {
        SidewindingConfig::preset(name)
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(config: &Self::Config, ctx: &BuildContext<'_>) -> ReportSpec {
        let s = SignalSpec::new;
        let signals = vec![
            s("beta_rad", "rad"),
            s("heading_rad", "rad"),
            s("heading_nominal_rad", "rad"),
            s("heading_error_rad", "rad"),
            s("taper", "1"),
            s("reversals", "count"),
            s("heading_valid", "0/1"),
            s("amplitude_mean_rad", "rad"),
            s("spatial_freq_rad", "rad/body length"),
            s("force_amplitude_peak", "N·m"),
            s("force_spatial_freq_peak", "N·m·body length"),
            s("taper_trim", "1"),
        ];
        debug_assert_eq!(signals.len(), controller::SIGNALS);
        // The windows are the lateral engine's (amplitude, spatial frequency, phase).
        let fields = CompliantSlitheringKind::report_spec(&config.lateral(), ctx).fields;
        ReportSpec { signals, fields }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(AntiCompliantSidewinding::new(
            ctx.layout, ctx.params, *config,
        ))
    }
}
