//! Directional compliance (reference 001, SPEC §8): windowed amplitudes that comply
//! in one direction only while the body section they are in is obstructed, chosen per
//! section by its absition, planar (the lateral wave) or in 3-D (a dorsal wave on the
//! other joints, each plane complying independently). See docs/compliance.md.

mod absition;
mod calibration;
mod config;
mod controller;
mod report;
mod sections;

pub use absition::{Absition, AmplitudeState, Mode};
pub use calibration::Calibration;
pub use config::{
    DirectionalComplianceConfig, DorsalWave, FrictionOffset, MAX_SECTIONS, PhaseCompliance,
    Reference, SectionValues, SectionsConfig, SpatialFreqCompliance, Strategy, Thresholds,
};
pub use controller::{DirectionalCompliance, WindowState};
pub use sections::{Boxcar, Sections};

use crate::controller_interface::report::{FieldSpec, ReportSpec, SignalSpec};
use crate::controller_interface::{BuildContext, ConfigError, Controller, ControllerKind};
use crate::controllers::steering::HeadingHold;
use crate::gait::GaitKind;

/// The registry's entry.
pub struct DirectionalComplianceKind;

/// Presets: (name, strategy, 3-D, over the full compliance).
const PRESETS: [(&str, Strategy, bool, bool); 10] = [
    ("dc_switching", Strategy::Switching, false, false),
    ("dc_nc", Strategy::Nc, false, false),
    ("dc_pdc", Strategy::Pdc, false, false),
    ("dc_ndc", Strategy::Ndc, false, false),
    ("dc3d_switching", Strategy::Switching, true, false),
    ("dc3d_nc", Strategy::Nc, true, false),
    ("dc3d_pdc", Strategy::Pdc, true, false),
    ("dc3d_ndc", Strategy::Ndc, true, false),
    ("dc_full_switching", Strategy::Switching, false, true),
    ("dc_full_nc", Strategy::Nc, false, true),
];

impl ControllerKind for DirectionalComplianceKind {
    type Config = DirectionalComplianceConfig;
    const NAME: &'static str = "directional_compliance";
    const SUMMARY: &'static str =
        "windowed amplitudes that comply one way when obstructed, switched by their absition";
    const GAITS: &'static [GaitKind] = &[GaitKind::Slithering];
    const PRESETS: &'static [(&'static str, &'static str)] = &[
        (
            "dc_switching",
            "planar; each window switches NC / PDC / NDC by its absition",
        ),
        (
            "dc_nc",
            "planar; nominal compliance (every amplitude rate admitted)",
        ),
        (
            "dc_pdc",
            "planar; every window only lets its amplitude grow",
        ),
        (
            "dc_ndc",
            "planar; every window only lets its amplitude shrink",
        ),
        (
            "dc3d_switching",
            "3-D (dorsal wave too); switching in each plane",
        ),
        ("dc3d_nc", "3-D; nominal compliance in each plane"),
        ("dc3d_pdc", "3-D; amplitudes only grow"),
        ("dc3d_ndc", "3-D; amplitudes only shrink"),
        (
            "dc_full_switching",
            "planar switching with the phase and spatial frequency compliant too",
        ),
        (
            "dc_full_nc",
            "planar nominal compliance of amplitude, spatial frequency and phase",
        ),
    ];

    fn preset(name: &str) -> Option<Self::Config> {
        PRESETS
            .iter()
            .find(|(n, ..)| *n == name)
            .map(|&(_, strategy, three_d, full)| {
                let c = DirectionalComplianceConfig::preset(strategy, three_d);
                if full { c.over_full_compliance() } else { c }
            })
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        let s = SignalSpec::new;
        let mut signals = vec![
            s("amplitude_lat_mean_rad", "rad"),
            s("amplitude_dor_mean_rad", "rad"),
            s("phase_lag_rad", "rad"),
            s("windows", "count"),
            s("threshold_low_rad_s", "rad·s"),
            s("threshold_high_rad_s", "rad·s"),
            s("calibration", ""),
            s("calibration_progress", ""),
            s("windows_pdc", "count"),
            s("windows_ndc", "count"),
            s("sections_pdc", "count"),
            s("sections_ndc", "count"),
            s("mode_switches", "count"),
            s("dorsal_ramp", ""),
        ];
        signals.extend(HeadingHold::SIGNALS.map(|(name, unit)| s(name, unit)));
        debug_assert_eq!(signals.len(), controller::FIXED_SIGNALS);
        let names = section_names(config.sections.count);
        for plane in ["lat", "dor"] {
            for name in &names {
                signals.push(SignalSpec::new(format!("absition_{plane}_{name}"), "rad·s"));
                signals.push(SignalSpec::new(format!("mode_{plane}_{name}"), ""));
            }
        }
        let windows = vec![
            s("amplitude", "rad"),
            s("section", "index"),
            s("mode", ""),
            s("force", "N·m"),
            s("spatial_freq", "rad/body length"),
        ];
        let sections = vec![
            s("mean_deviation", "rad"),
            s("absition", "rad·s"),
            s("mode", ""),
            s("offset", "rad"),
            s("change", "rad"),
            s("still", ""),
        ];
        let field = |name: &str, centralization: &str, columns: &Vec<SignalSpec>| FieldSpec {
            name: name.into(),
            centralization: centralization.into(),
            enabled: true,
            columns: columns.clone(),
        };
        let mut fields = vec![field("amplitude_lateral", "windowed", &windows)];
        if config.dorsal.enabled {
            fields.push(field("amplitude_dorsal", "windowed", &windows));
        }
        fields.push(field("sections_lateral", "sections", &sections));
        if config.dorsal.enabled {
            fields.push(field("sections_dorsal", "sections", &sections));
        }
        ReportSpec { signals, fields }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(DirectionalCompliance::new(ctx.layout, ctx.params, *config))
    }
}

/// The sections' names in signal names: the reference's head, middle and tail for
/// three, `s1`… (head first) otherwise.
pub fn section_names(count: usize) -> Vec<String> {
    if count == 3 {
        ["head", "mid", "tail"].map(String::from).to_vec()
    } else {
        (1..=count).map(|k| format!("s{k}")).collect()
    }
}
