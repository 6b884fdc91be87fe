//! The pole-climbing experiment (issue 12, thesis §4.2, SPEC §6): poles whose diameter
//! steps or tapers by up to ±30 % along their height; the body starts straight on the
//! ground beside one in the rolling gait, the rolling helix is selected after a lead-in
//! (as an operator would), and each controller gets on, winds up and climbs. The
//! nominal helix is set per pole from its foot's diameter (an operator measures the
//! foot). A trial ends when the body's centre reaches the top or at the time limit.
//! Definitions: docs/lab.md.

pub mod metrics;
pub mod plots;
pub mod poles;
pub mod report;

use super::LabError;
use super::board::Layout;
use super::experiment::{ExperimentModule, Goal};
use super::trial::{TrialConfig, TrialRecord};
use crate::emu::Plant;
use crate::emu::world::physics::build::MODULE_DIAMETER_M;
use crate::emu::world::scenario::WorldScenario;
use crate::emu::world::{PoleSection, WorldSpec};
use crate::gait::{GaitKind, GaitParams};
use metrics::{PoleMetrics, pole_metrics};
use poles::PoleDesign;

/// The compared controllers, in report order: the open-loop helix (its radius fixed at
/// the nominal), central radius compliance, windowed, windowed with the adaptive set
/// point (the full controller).
pub const CONTROLLERS: &[&str] = &["fixed", "central", "windowed", "windowed_adaptive"];

/// How the experiment sets up its trials.
#[derive(Debug, Clone, PartialEq)]
pub struct PoleClimb {
    /// The poles, by layout name.
    pub designs: Vec<PoleDesign>,
    /// Skin–pole friction.
    pub mu: f64,
    /// Seconds in the rolling gait before the helix is selected.
    pub lead_in_s: f64,
    /// The nominal coil's centre line this much inside the foot's surface, m (the
    /// fixed coil's only grip; the compliant ones squeeze).
    pub grip_margin_m: f64,
}

impl Default for PoleClimb {
    fn default() -> Self {
        Self {
            designs: poles::named_set(),
            mu: 0.6,
            lead_in_s: 0.2,
            grip_margin_m: 0.003,
        }
    }
}

impl PoleClimb {
    /// The layouts of the designs: each named as its pole, its identity (its trials'
    /// start and noise seeds) taken from the pole's own description, so a pole keeps
    /// its starts whichever list it is run in.
    pub fn layouts(&self) -> Result<Vec<Layout>, LabError> {
        self.designs
            .iter()
            .map(|d| {
                Ok(Layout {
                    name: d.name.clone(),
                    scenario: WorldScenario::parse("")?,
                    identity: d.identity(),
                })
            })
            .collect()
    }

    /// The nominal helix radius for a pole whose foot is `foot_m` across: its centre
    /// line `grip_margin_m` inside the foot's skin, m.
    pub fn nominal_radius(&self, foot_m: f64) -> f64 {
        0.5 * foot_m + 0.5 * MODULE_DIAMETER_M - self.grip_margin_m
    }

    /// `base` with the nominal helix of radius `r`, the pitch in the daemon's default
    /// ratio to the radius.
    pub fn nominal_for(&self, base: &GaitParams, r: f64) -> GaitParams {
        let d = GaitParams::default_for(GaitKind::RollingHelix);
        GaitParams {
            helix_radius_m: r,
            helix_pitch_m: r * d.helix_pitch_m / d.helix_radius_m,
            ..*base
        }
    }
}

/// A pole's goal: its top, and what the metrics need of it.
#[derive(Debug, Clone, PartialEq)]
pub struct PoleGoal {
    pub top_m: f64,
    pub foot_m: f64,
    /// The nominal helix radius set for it, m.
    pub nominal_radius_m: f64,
    /// Heights where the diameter starts to change, m.
    pub changes_m: Vec<f64>,
    pub sections: Vec<PoleSection>,
}

impl Goal for PoleGoal {
    fn reached(&self, plant: &dyn Plant) -> bool {
        let n = plant.link_count().max(1);
        let z: f64 = (0..plant.link_count())
            .map(|k| plant.link_pose(k).position_m[2])
            .sum();
        z / n as f64 >= self.top_m
    }
}

impl ExperimentModule for PoleClimb {
    type Goal = PoleGoal;
    type Metrics = PoleMetrics;

    fn name(&self) -> &'static str {
        "pole"
    }
    fn summary(&self) -> &'static str {
        "rolling helix with radius compliance up poles whose diameter changes (SPEC §6)"
    }
    fn gait(&self) -> GaitKind {
        GaitKind::RollingHelix
    }
    fn controllers(&self) -> &'static [&'static str] {
        CONTROLLERS
    }

    fn world(
        &self,
        layout: &Layout,
        _modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, PoleGoal), LabError> {
        let design = self
            .designs
            .iter()
            .find(|d| d.name == layout.name)
            .ok_or_else(|| LabError::BadValue(format!("no pole named {:?}", layout.name)))?;
        let seed = super::board::trial_seed(layout.identity, start);
        let world = design.world(seed, self.mu);
        let goal = PoleGoal {
            top_m: poles::TOP_M,
            foot_m: design.foot_m,
            nominal_radius_m: self.nominal_radius(design.foot_m),
            changes_m: design.changes.iter().map(|c| c.at_m).collect(),
            sections: world.poles[0].sections.clone(),
        };
        Ok((world, goal))
    }

    fn trial_config(&self, base: &TrialConfig, goal: &PoleGoal) -> TrialConfig {
        let mut t = *base;
        let g = t.gaits.get_mut(GaitKind::RollingHelix);
        *g = self.nominal_for(g, goal.nominal_radius_m);
        t.lead_in = Some((GaitKind::Rolling, self.lead_in_s));
        t
    }

    fn metrics(&self, goal: &PoleGoal, rec: &TrialRecord) -> PoleMetrics {
        pole_metrics(rec, &goal.changes_m, goal.top_m)
    }
}

/// Writes `results.csv`, `summary.md`, `climb.png` (every controller's climb on the
/// first pole) and per controller `windows-*.png` (its half turns' radius and set
/// point against the pole's diameter where they lie) into `dir`; returns the files.
pub fn write_report(
    dir: &std::path::Path,
    module: &PoleClimb,
    results: &[super::runner::TrialResult<PoleClimb>],
    ctx: &super::report::SummaryContext,
) -> Result<Vec<std::path::PathBuf>, LabError> {
    use super::file_stem;
    std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    let csv = dir.join("results.csv");
    super::report::write_text(&csv, &report::results_csv(results))?;
    written.push(csv);
    let p = dir.join("climb.png");
    plots::climb_plot(&p, results)?;
    written.push(p);
    for r in results {
        let Some((_, goal, rec)) = &r.plotted else {
            continue;
        };
        if rec.windows.iter().all(|w| w.is_empty()) {
            continue;
        }
        let p = dir.join(format!("windows-{}.png", file_stem(&r.controller)));
        let title = format!("{}: pole {}, start {}", r.controller, r.layout, r.start);
        plots::windows_plot(&p, &title, goal, rec)?;
        written.push(p);
    }
    let mut ctx = ctx.clone();
    ctx.plots = written[1..]
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let md = dir.join("summary.md");
    super::report::write_text(
        &md,
        &report::summary_markdown(results, &ctx, &module.designs),
    )?;
    written.push(md);
    Ok(written)
}
