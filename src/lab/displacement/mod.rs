//! The directional-compliance paper's experiments (reference 001 §IV, SPEC §8): a
//! controller runs for a fixed time from a pose (position and heading) among the
//! obstacles, or until its body's centre leaves them ([`field::FieldEdge`]), and is
//! scored by how far that centre was displaced, in body lengths per minute. Two terrains: the planar peg array and the rock pile
//! (3-D). Every pose is run several times, the trials differing only in their
//! sensor-noise seed (the paper: 5 poses × 4 trials). Definitions: docs/lab.md.

pub mod field;
pub mod metrics;
pub mod plots;
pub mod report;

use super::LabError;
use super::board::Layout;
use super::experiment::ExperimentModule;
use super::trial::TrialRecord;
use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::MODULE_LENGTH_M;
use crate::gait::GaitKind;
pub use field::FieldEdge;
use metrics::{DisplacementMetrics, displacement_metrics};

/// The peg array's scenario (`scenarios/peg-array.toml`), built in.
pub const PEG_ARRAY_TOML: &str = include_str!("../../../scenarios/peg-array.toml");
/// The rock pile's scenario (`scenarios/rock-pile-3d.toml`), built in.
pub const ROCK_PILE_TOML: &str = include_str!("../../../scenarios/rock-pile-3d.toml");

/// The paper's robot: sixteen modules.
pub const MODULES: usize = 16;

/// Which of the paper's environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Terrain {
    /// Planar: the lateral wave only, three windows (odd modules active).
    PegArray,
    /// Three-dimensional: a dorsal and a lateral wave, three windows per plane.
    RockPile,
}

/// The experiment module of one terrain.
#[derive(Debug, Clone, Copy)]
pub struct Displacement {
    pub terrain: Terrain,
}

/// The paper's four controllers on each terrain, in its order.
pub const PEG_ARRAY_CONTROLLERS: &[&str] = &["dc_nc", "dc_ndc", "dc_pdc", "dc_switching"];
pub const ROCK_PILE_CONTROLLERS: &[&str] = &["dc3d_nc", "dc3d_ndc", "dc3d_pdc", "dc3d_switching"];

impl Displacement {
    /// The terrain's built-in scenario.
    pub fn scenario_toml(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => PEG_ARRAY_TOML,
            Terrain::RockPile => ROCK_PILE_TOML,
        }
    }
}

impl ExperimentModule for Displacement {
    type Goal = FieldEdge;
    type Metrics = DisplacementMetrics;

    fn name(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => "peg-array",
            Terrain::RockPile => "rock-pile",
        }
    }
    fn summary(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => {
                "directional compliance on a planar peg array (SPEC §8): body lengths per minute"
            }
            Terrain::RockPile => {
                "directional compliance in 3-D over a rock pile (SPEC §8): body lengths per minute"
            }
        }
    }
    fn gait(&self) -> GaitKind {
        GaitKind::Slithering
    }
    fn controllers(&self) -> &'static [&'static str] {
        match self.terrain {
            Terrain::PegArray => PEG_ARRAY_CONTROLLERS,
            Terrain::RockPile => ROCK_PILE_CONTROLLERS,
        }
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, FieldEdge), LabError> {
        let world = layout.scenario.generate_trial(modules, start)?;
        let edge = FieldEdge::of(&world);
        Ok((world, edge))
    }

    fn metrics(&self, _goal: &FieldEdge, rec: &TrialRecord) -> DisplacementMetrics {
        let modules = rec.start_links_m.len().saturating_sub(1).max(1);
        displacement_metrics(rec, modules as f64 * MODULE_LENGTH_M)
    }
}

/// Writes `results.csv`, the plots and `summary.md` into `dir` (created if missing) and
/// returns the files written: per controller its first trial's `path-*.png`,
/// `signals-*.png` and `absitions-*.png`; `velocity.png` over all.
pub fn write_report(
    module: &Displacement,
    dir: &std::path::Path,
    results: &[super::runner::TrialResult<Displacement>],
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
    for r in results {
        let Some((world, _, rec)) = &r.plotted else {
            continue;
        };
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, pose {}", r.controller, r.layout, r.start);
        let p = dir.join(format!("path-{stem}.png"));
        common::path_plot(&p, &title, world, None, rec)?;
        written.push(p);
        let p = dir.join(format!("signals-{stem}.png"));
        common::signals_plot(&p, &title, rec)?;
        written.push(p);
        let p = dir.join(format!("absitions-{stem}.png"));
        plots::absition_plot(&p, &title, rec)?;
        written.push(p);
    }
    let p = dir.join("velocity.png");
    let title = format!(
        "{}: velocity per pose (black) and overall (red, ± sd)",
        module.name()
    );
    plots::velocity_plot(&p, &title, results)?;
    written.push(p);
    let mut ctx = ctx.clone();
    ctx.plots = written[1..]
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let md = dir.join("summary.md");
    let title = match module.terrain {
        Terrain::PegArray => "Directional compliance on the peg array (SPEC §8, planar)",
        Terrain::RockPile => "Directional compliance on the rock pile (SPEC §8, 3-D)",
    };
    super::report::write_text(&md, &report::summary_markdown(title, results, &ctx))?;
    written.push(md);
    Ok(written)
}
