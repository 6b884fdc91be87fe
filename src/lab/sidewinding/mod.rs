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

use super::LabError;
use super::board::Layout;
use super::experiment::ExperimentModule;
use super::trial::TrialRecord;
use crate::emu::world::WorldSpec;
use crate::gait::GaitKind;
use fence::Fence;
use metrics::{SidewindingMetrics, sidewinding_metrics};

/// The experiment's scenario (`scenarios/sidewinding-pegs.toml`), built in.
pub const SIDEWINDING_PEGS_TOML: &str = include_str!("../../../scenarios/sidewinding-pegs.toml");

/// The thesis's four controllers, in its order: AC-SFC, AC, SFC, open loop.
pub const CONTROLLERS: &[&str] = &["ac_sfc", "ac", "sfc", "sw_open_loop"];

/// The experiment's entry.
#[derive(Debug, Clone, Copy, Default)]
pub struct SidewindingPegs;

impl ExperimentModule for SidewindingPegs {
    type Goal = Fence;
    type Metrics = SidewindingMetrics;

    fn name(&self) -> &'static str {
        "sidewinding"
    }
    fn summary(&self) -> &'static str {
        "anti-compliant sidewinding through an irregular peg array (SPEC §7)"
    }
    fn gait(&self) -> GaitKind {
        GaitKind::Sidewinding
    }
    fn controllers(&self) -> &'static [&'static str] {
        CONTROLLERS
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
}

/// Writes `results.csv`, `summary.md`, `metrics.png` and per controller its first
/// trial's `trial-*.png` (path, headings, β) and `signals-*.png` into `dir` (created if
/// missing); returns the files.
pub fn write_report(
    dir: &std::path::Path,
    results: &[super::runner::TrialResult<SidewindingPegs>],
    ctx: &super::report::SummaryContext,
) -> Result<Vec<std::path::PathBuf>, LabError> {
    use super::{file_stem, plots as common};
    std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    let csv = dir.join("results.csv");
    super::report::write_text(&csv, &report::results_csv(results))?;
    written.push(csv);
    let p = dir.join("metrics.png");
    plots::metrics_plot(&p, results)?;
    written.push(p);
    let tau = crate::controllers::sidewinding::SidewindingConfig::full().heading_filter_s;
    for r in results {
        let Some((world, _, rec)) = &r.plotted else {
            continue;
        };
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, start {}", r.controller, r.layout, r.start);
        let p = dir.join(format!("trial-{stem}.png"));
        plots::trial_plot(&p, &title, world, rec, tau)?;
        written.push(p);
        let p = dir.join(format!("signals-{stem}.png"));
        common::signals_plot(&p, &title, rec)?;
        written.push(p);
    }
    let mut ctx = ctx.clone();
    ctx.plots = written[1..]
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let md = dir.join("summary.md");
    super::report::write_text(&md, &report::summary_markdown(results, &ctx))?;
    written.push(md);
    Ok(written)
}
