//! The thesis's sidewinding experiment (§4.3.7, SPEC §7): the snake sidewinds at an
//! irregular row of pegs (`[[peg_fence]]`), must get its body through one of the
//! openings, is turned round by the pegs on the way and reverses (β) to go on in the
//! nominal direction. Starts are random poses before the array; each is run several
//! times, the trials differing only in their sensor-noise seed (the thesis: 7 × 3).
//! A trial ends when the body has passed the array, went round an end of it or back,
//! or at the time limit. Definitions: docs/lab.md.

pub mod fence;
pub mod metrics;
pub mod plots;
pub mod report;

use std::path::{Path, PathBuf};

use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::WorldScenario;
use crate::gait::GaitKind;
use crate::lab::LabError;
use crate::lab::experiment::{About, Defaults, Experiment};
use crate::lab::file_stem;
use crate::lab::layout::Layout;
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord};
use fence::Fence;
use metrics::{SidewindingMetrics, sidewinding_metrics};

/// The experiment's scenario (`scenarios/sidewinding-pegs.toml`), built in.
pub const SIDEWINDING_PEGS_TOML: &str = include_str!("../../../scenarios/sidewinding-pegs.toml");

/// The thesis's four controllers, in its order: AC-SFC, AC, SFC, open loop.
pub const CONTROLLERS: &[&str] = &["ac_sfc", "ac", "sfc", "sw_open_loop"];

/// The experiment.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub struct SidewindingPegs;

/// Its own options: which layouts. The defaults are the thesis's protocol: one array,
/// 7 starts, 3 trials each, up to 300 s.
#[derive(Debug, Clone, clap::Args)]
pub struct SidewindingArgs {
    /// Seeded layouts: the scenario with master seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 1)]
    pub layouts: usize,
    /// Master seed of the first layout (default: the scenario's own).
    #[arg(long)]
    pub seed_base: Option<u64>,
    /// World scenario the layouts come from; it needs a [[peg_fence]] (default: the
    /// built-in scenarios/sidewinding-pegs.toml).
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
}

impl Experiment for SidewindingPegs {
    type Goal = Fence;
    type Metrics = SidewindingMetrics;
    type Args = SidewindingArgs;

    fn about(&self) -> About {
        About {
            name: "sidewinding",
            summary: "anti-compliant sidewinding through an irregular peg array (SPEC §7)",
            title: "Sidewinding through an irregular peg array (SPEC §7, thesis §4.3.7)",
            gait: GaitKind::Sidewinding,
            controllers: CONTROLLERS,
            any_gait: false,
            variant_base: "ac_sfc",
            defaults: {
                Defaults {
                    starts: 7,
                    repeats: 3,
                    seconds: 300.0,
                }
            },
        }
    }

    fn configure(
        &self,
        args: &SidewindingArgs,
        _trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        let base = match &args.scenario {
            Some(path) => WorldScenario::load(path)?,
            None => WorldScenario::parse(SIDEWINDING_PEGS_TOML)?,
        };
        if base.peg_fences.is_empty() {
            return Err(LabError::BadValue(
                "the scenario has no [[peg_fence]]: the experiment needs a peg array".into(),
            ));
        }
        let seed_base = args.seed_base.unwrap_or(base.seed);
        let layouts = (0..args.layouts as u64)
            .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
            .collect();
        Ok((SidewindingPegs, layouts))
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, Fence), LabError> {
        let s = &layout.scenario;
        let fence = s.peg_fences.first().ok_or_else(|| LabError::NoBoard {
            layout: layout.name.clone(),
        })?;
        let world = s.generate_trial(modules, start)?;
        let goal = Fence::new(fence, &world, modules);
        Ok((world, goal))
    }

    fn metrics(&self, fence: &Fence, rec: &TrialRecord) -> SidewindingMetrics {
        // The controller's default heading low-pass (the true heading is filtered alike).
        let tau = crate::controllers::sidewinding::SidewindingConfig::full().heading_filter_s;
        sidewinding_metrics(fence, rec, tau)
    }

    fn csv_header(&self) -> &'static str {
        report::CSV_HEADER
    }
    fn csv_row(&self, result: &TrialResult<Self>) -> String {
        report::csv_row(result)
    }
    fn summary_tables(&self, results: &[TrialResult<Self>], _ctx: &SummaryContext) -> String {
        report::summary_tables(results)
    }
    fn trial_plots(
        &self,
        dir: &Path,
        r: &TrialResult<Self>,
        (world, _, rec): (&WorldSpec, &Fence, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        let tau = crate::controllers::sidewinding::SidewindingConfig::full().heading_filter_s;
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, start {}", r.controller, r.layout, r.start);
        let trial = dir.join(format!("trial-{stem}.png"));
        plots::trial_plot(&trial, &title, world, rec, tau)?;
        let signals = dir.join(format!("signals-{stem}.png"));
        crate::lab::plots::signals_plot(&signals, &title, rec)?;
        Ok(vec![trial, signals])
    }
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join("metrics.png");
        plots::metrics_plot(&p, results)?;
        Ok(vec![p])
    }
}
