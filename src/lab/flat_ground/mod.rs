//! The gaits on flat ground against the no-slip bound (`snake-lab flat-ground --gait
//! G`): each controller runs from random headings on open, flat ground; a trial is
//! scored by how far the body's centre travels per gait cycle once the selector's
//! blend is over, against how far the commanded shape could carry the body per cycle
//! without its skin slipping (`emu::world::physics::no_slip_bound`). A share of the
//! bound above 1 means the physics lets the body travel further than its shape can:
//! a check of the emulator and of a gait's parameters before any obstacle.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::no_slip_bound::no_slip;
use crate::emu::world::scenario::WorldScenario;
use crate::gait::{BodyLayout, GaitKind, Plane};
use crate::lab::LabError;
use crate::lab::experiment::{About, Defaults, Experiment, Goal};
use crate::lab::layout::Layout;
use crate::lab::metrics::mean_sd_median;
use crate::lab::report::SummaryContext;
use crate::lab::runner::{TrialResult, controller_names};
use crate::lab::trial::{TrialConfig, TrialRecord};
use crate::module::{MODULE_DIAMETER_M, MODULE_LENGTH_M};

/// Open flat ground, the start anywhere near the origin, any heading.
const FLAT_TOML: &str = "seed = 1\n[start.random]\n\
    region = { x_m = [-0.5, 0.5], y_m = [-0.5, 0.5] }\n\
    yaw_range_rad = [0.0, 6.283185307179586]\n";

/// The experiment: one gait, and (once configured) its no-slip bound.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct FlatGround {
    pub gait: GaitKind,
    /// Travel per cycle the commanded shape allows without slipping, m.
    pub bound_m: f64,
    /// The selector's blend into the gait, s: travel is counted after it.
    pub blend_s: f64,
    /// Body length, m.
    pub body_m: f64,
}

impl FlatGround {
    pub const UNCONFIGURED: FlatGround = FlatGround {
        gait: GaitKind::Slithering,
        bound_m: f64::NAN,
        blend_s: 0.0,
        body_m: f64::NAN,
    };
}

/// Its own options.
#[derive(Debug, Clone, clap::Args)]
pub struct FlatGroundArgs {
    /// The gait (linear_progression, slithering, sidewinding, rolling, rolling_helix,
    /// conical_sidewinding).
    #[arg(long, default_value = "slithering")]
    pub gait: String,
}

/// Flat ground has nothing to reach: a trial runs its whole time.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Never;

impl Goal for Never {
    fn reached(&self, _plant: &dyn Plant) -> bool {
        false
    }
}

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlatMetrics {
    /// Gait cycles after the blend.
    pub cycles: f64,
    /// The centre's straight travel after the blend, m.
    pub travel_m: f64,
    pub per_cycle_m: f64,
    /// `per_cycle_m` over the no-slip bound.
    pub share_of_bound: f64,
}

impl Experiment for FlatGround {
    type Goal = Never;
    type Metrics = FlatMetrics;
    type Args = FlatGroundArgs;

    fn about(&self) -> About {
        About {
            name: "flat-ground",
            summary: "a gait on flat ground against its no-slip bound: metres per cycle",
            title: "A gait on flat ground against the no-slip bound",
            gait: self.gait,
            controllers: &["open_loop"],
            any_gait: false,
            variant_base: "open_loop",
            defaults: {
                Defaults {
                    starts: 3,
                    repeats: 1,
                    seconds: 40.0,
                }
            },
        }
    }

    fn configure(
        &self,
        args: &FlatGroundArgs,
        _trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        let gait = GaitKind::from_name(&args.gait)
            .ok_or_else(|| LabError::BadValue(format!("--gait: no gait {:?}", args.gait)))?;
        let layouts = vec![Layout::seeded(&WorldScenario::parse(FLAT_TOML)?, 1)];
        Ok((FlatGround { gait, ..*self }, layouts))
    }

    fn with_trial(self, trial: &TrialConfig) -> Self {
        let layout = BodyLayout::alternating(trial.modules, Plane::Lateral, MODULE_LENGTH_M);
        let params = trial.gaits.get(self.gait);
        FlatGround {
            bound_m: no_slip(self.gait, params, &layout, 0.5 * MODULE_DIAMETER_M).bound_m,
            blend_s: trial.blend_time_s,
            body_m: trial.modules as f64 * MODULE_LENGTH_M,
            ..self
        }
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, Never), LabError> {
        Ok((layout.scenario.generate_trial(modules, start)?, Never))
    }

    fn metrics(&self, _goal: &Never, rec: &TrialRecord) -> FlatMetrics {
        let k0 = ((self.blend_s / rec.sample_dt_s).ceil() as usize).min(rec.centre_m.len());
        let (a, b) = match (rec.centre_m.get(k0), rec.centre_m.last()) {
            (Some(a), Some(b)) => (*a, *b),
            _ => ([0.0; 2], [0.0; 2]),
        };
        let travel_m = (b[0] - a[0]).hypot(b[1] - a[1]);
        let seconds = (rec.seconds - k0 as f64 * rec.sample_dt_s).max(0.0);
        let cycles = rec.temporal_freq_rad_s.abs() * seconds / std::f64::consts::TAU;
        let per_cycle_m = if cycles > 0.0 {
            travel_m / cycles
        } else {
            f64::NAN
        };
        FlatMetrics {
            cycles,
            travel_m,
            per_cycle_m,
            share_of_bound: per_cycle_m / self.bound_m,
        }
    }

    fn csv_header(&self) -> &'static str {
        "gait,cycles,travel_m,per_cycle_m,no_slip_bound_m,share_of_bound"
    }
    fn csv_row(&self, r: &TrialResult<Self>) -> String {
        let m = &r.metrics;
        format!(
            "{},{:.3},{:.4},{:.4},{:.4},{:.3}",
            self.gait.name(),
            m.cycles,
            m.travel_m,
            m.per_cycle_m,
            self.bound_m,
            m.share_of_bound
        )
    }

    fn summary_tables(&self, results: &[TrialResult<Self>], _ctx: &SummaryContext) -> String {
        let mut s = format!(
            "Gait {}; no-slip bound {:.3} m per cycle ({:.3} body lengths).\n\n\
             | controller | trials | m per cycle mean ± sd | body lengths per cycle | share of the bound (max) |\n\
             | --- | ---: | ---: | ---: | ---: |\n",
            self.gait.name(),
            self.bound_m,
            self.bound_m / self.body_m
        );
        for name in controller_names(results) {
            let mine: Vec<&FlatMetrics> = results
                .iter()
                .filter(|r| r.controller == name)
                .map(|r| &r.metrics)
                .collect();
            let per: Vec<f64> = mine.iter().map(|m| m.per_cycle_m).collect();
            let (mean, sd, _) = mean_sd_median(&per).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            let max = mine
                .iter()
                .map(|m| m.share_of_bound)
                .fold(f64::NAN, f64::max);
            let _ = writeln!(
                s,
                "| {name} | {} | {mean:.3} ± {sd:.3} | {:.3} | {:.2} ({max:.2}) |",
                mine.len(),
                mean / self.body_m,
                mean / self.bound_m
            );
        }
        s.push_str(
            "\nTravel = the body centre's straight displacement from the end of the \
             selector's blend to the end of the trial, per nominal gait cycle (2π/ωT). \
             No-slip bound = how far the commanded shape can carry the body per cycle \
             without its skin slipping (docs/emulator.md); a share above 1 is travel the \
             shape cannot explain.\n",
        );
        s
    }

    fn trial_plots(
        &self,
        dir: &Path,
        r: &TrialResult<Self>,
        (world, _, rec): (&WorldSpec, &Never, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join(format!("path-{}.png", crate::lab::file_stem(&r.controller)));
        let title = format!("{} ({}): start {}", r.controller, self.gait.name(), r.start);
        crate::lab::plots::path_plot(&p, &title, world, None, rec)?;
        Ok(vec![p])
    }

    fn run_plots(&self, _dir: &Path, _r: &[TrialResult<Self>]) -> Result<Vec<PathBuf>, LabError> {
        Ok(Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn travel_is_counted_per_cycle_after_the_blend() {
        let e = FlatGround {
            gait: GaitKind::Sidewinding,
            bound_m: 0.5,
            blend_s: 1.0,
            body_m: 1.0,
        };
        // 20 Hz for 11 s; still during the blend, then 0.1 m/s along x.
        let centre_m: Vec<[f64; 2]> = (0..=220)
            .map(|k| [(0.05 * k as f64 - 1.0).max(0.0) * 0.1, 0.0])
            .collect();
        let rec = TrialRecord {
            sample_dt_s: 0.05,
            centre_m,
            seconds: 11.0,
            temporal_freq_rad_s: std::f64::consts::TAU / 5.0,
            start_links_m: Vec::new(),
            links_m: Vec::new(),
            end_links_m: Vec::new(),
            signal_names: Vec::new(),
            signals: Vec::new(),
            success: false,
            cycles_not_running: 0,
            self_contacts: 0,
            heights_m: Vec::new(),
            windows: Vec::new(),
            strain: Default::default(),
            stuck_reported: Vec::new(),
            estimate: Vec::new(),
            position_error_m: Vec::new(),
            gait_switches: 0,
        };
        let m = e.metrics(&Never, &rec);
        assert!((m.cycles - 2.0).abs() < 1e-9, "{m:?}");
        assert!((m.travel_m - 1.0).abs() < 1e-9, "{m:?}");
        assert!((m.per_cycle_m - 0.5).abs() < 1e-9);
        assert!((m.share_of_bound - 1.0).abs() < 1e-9);
    }
}
