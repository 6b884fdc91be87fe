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

use std::path::{Path, PathBuf};

use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::{MODULE_LENGTH_M, WorldScenario};
use crate::gait::GaitKind;
use crate::lab::LabError;
use crate::lab::experiment::{Defaults, Experiment};
use crate::lab::file_stem;
use crate::lab::layout::Layout;
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord};
pub use field::FieldEdge;
use metrics::{DisplacementMetrics, displacement_metrics};

/// The peg array's scenario (`scenarios/peg-array.toml`), built in.
pub const PEG_ARRAY_TOML: &str = include_str!("../../../scenarios/peg-array.toml");
/// The rock pile's scenario (`scenarios/rock-pile-3d.toml`), built in.
pub const ROCK_PILE_TOML: &str = include_str!("../../../scenarios/rock-pile-3d.toml");

/// The paper's robot: sixteen modules.
pub const MODULES: usize = 16;

/// Which of the paper's environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Terrain {
    /// Planar: the lateral wave only, three windows (odd modules active).
    PegArray,
    /// Three-dimensional: a dorsal and a lateral wave, three windows per plane.
    RockPile,
}

/// The experiment of one terrain.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Displacement {
    pub terrain: Terrain,
}

/// Their own options: which layouts, and the body. The defaults are the paper's
/// protocol: one layout, 5 random poses, 4 trials per pose, 2 minutes each.
#[derive(Debug, Clone, clap::Args)]
pub struct DisplacementArgs {
    /// Seeded layouts: the scenario with master seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 1)]
    pub layouts: usize,
    /// Master seed of the first layout (default: the scenario's own).
    #[arg(long)]
    pub seed_base: Option<u64>,
    /// World scenario the layouts come from (default: the built-in
    /// scenarios/peg-array.toml or scenarios/rock-pile-3d.toml).
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// Modules of the snake (the paper's robot has 16).
    #[arg(long, default_value_t = MODULES)]
    pub modules: usize,
}

/// The paper's four controllers on each terrain, in its order.
pub const PEG_ARRAY_CONTROLLERS: &[&str] = &["dc_nc", "dc_ndc", "dc_pdc", "dc_switching"];
pub const ROCK_PILE_CONTROLLERS: &[&str] = &["dc3d_nc", "dc3d_ndc", "dc3d_pdc", "dc3d_switching"];

impl Displacement {
    pub const PEG_ARRAY: Displacement = Displacement {
        terrain: Terrain::PegArray,
    };
    pub const ROCK_PILE: Displacement = Displacement {
        terrain: Terrain::RockPile,
    };

    /// The terrain's built-in scenario.
    pub fn scenario_toml(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => PEG_ARRAY_TOML,
            Terrain::RockPile => ROCK_PILE_TOML,
        }
    }
}

impl Experiment for Displacement {
    type Goal = FieldEdge;
    type Metrics = DisplacementMetrics;
    type Args = DisplacementArgs;

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
    fn title(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => "Directional compliance on the peg array (SPEC §8, planar)",
            Terrain::RockPile => "Directional compliance on the rock pile (SPEC §8, 3-D)",
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
    fn variant_base(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => "dc_switching",
            Terrain::RockPile => "dc3d_switching",
        }
    }
    fn defaults(&self) -> Defaults {
        Defaults {
            starts: 5,
            repeats: 4,
            seconds: 120.0,
        }
    }

    fn configure(
        &self,
        args: &DisplacementArgs,
        trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        if !(2..=64).contains(&args.modules) {
            return Err(LabError::BadValue(format!(
                "--modules must be 2 ..= 64, not {}",
                args.modules
            )));
        }
        trial.modules = args.modules;
        let base = match &args.scenario {
            Some(path) => WorldScenario::load(path)?,
            None => WorldScenario::parse(self.scenario_toml())?,
        };
        let seed_base = args.seed_base.unwrap_or(base.seed);
        let layouts = (0..args.layouts as u64)
            .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
            .collect();
        Ok((*self, layouts))
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

    fn csv_keys(&self) -> [&'static str; 4] {
        ["controller", "layout", "pose", "repeat"]
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
        (world, _, rec): (&WorldSpec, &FieldEdge, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        use crate::lab::plots::{path_plot, signals_plot};
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, pose {}", r.controller, r.layout, r.start);
        let path = dir.join(format!("path-{stem}.png"));
        path_plot(&path, &title, world, None, rec)?;
        let signals = dir.join(format!("signals-{stem}.png"));
        signals_plot(&signals, &title, rec)?;
        let absitions = dir.join(format!("absitions-{stem}.png"));
        plots::absition_plot(&absitions, &title, rec)?;
        Ok(vec![path, signals, absitions])
    }
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join("velocity.png");
        let title = format!(
            "{}: velocity per pose (black) and overall (red, ± sd)",
            self.name()
        );
        plots::velocity_plot(&p, &title, results)?;
        Ok(vec![p])
    }
}
