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

use std::path::{Path, PathBuf};

use crate::emu::Plant;
use crate::emu::world::scenario::WorldScenario;
use crate::emu::world::{PoleSection, WorldSpec};
use crate::gait::{GaitKind, GaitParams};
use crate::lab::LabError;
use crate::lab::experiment::{About, Defaults, Experiment, Goal};
use crate::lab::file_stem;
use crate::lab::layout::Layout;
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord};
use crate::module::MODULE_DIAMETER_M;
use metrics::{PoleMetrics, pole_metrics};
use poles::PoleDesign;

/// The compared controllers, in report order: the open-loop helix (its radius fixed at
/// the nominal), central radius compliance, windowed, windowed with the adaptive set
/// point (the full controller).
pub const CONTROLLERS: &[&str] = &["fixed", "central", "windowed", "windowed_adaptive"];

/// How the experiment sets up its trials.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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
            ..Self::UNCONFIGURED
        }
    }
}

/// Its own options: which poles, the skin's grip and the lead-in.
#[derive(Debug, Clone, clap::Args)]
pub struct PoleArgs {
    /// Named poles to climb, comma-separated (default: the whole named set; `none`
    /// for seeded poles only).
    #[arg(long, value_delimiter = ',')]
    pub poles: Vec<String>,
    /// Seeded random poles, after the named ones: seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 0)]
    pub seeded: usize,
    /// Seed of the first seeded pole.
    #[arg(long, default_value_t = 100)]
    pub seed_base: u64,
    /// Seconds of rolling on the ground before the helix is selected.
    #[arg(long, default_value_t = 0.2)]
    pub lead_in: f64,
    /// Skin-pole friction coefficient.
    #[arg(long, default_value_t = 0.6)]
    pub mu: f64,
}

impl PoleClimb {
    /// The experiment before its options name the poles.
    pub const UNCONFIGURED: PoleClimb = PoleClimb {
        designs: Vec::new(),
        mu: 0.6,
        lead_in_s: 0.2,
        grip_margin_m: 0.003,
    };

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
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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

impl Experiment for PoleClimb {
    type Goal = PoleGoal;
    type Metrics = PoleMetrics;
    type Args = PoleArgs;

    fn about(&self) -> About {
        About {
            name: "pole",
            summary: "rolling helix with radius compliance up poles whose diameter changes (SPEC §6)",
            title: "Pole climbing: rolling helix with radius compliance (SPEC §6, thesis §4.2)",
            gait: GaitKind::RollingHelix,
            controllers: CONTROLLERS,
            any_gait: false,
            variant_base: "windowed_adaptive",
            defaults: {
                Defaults {
                    starts: 3,
                    repeats: 1,
                    seconds: 150.0,
                }
            },
        }
    }

    fn configure(
        &self,
        args: &PoleArgs,
        _trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        let named = poles::named_set();
        let mut designs = Vec::new();
        if args.poles.is_empty() {
            designs.extend(named.iter().cloned());
        } else if args.poles != ["none"] {
            for p in &args.poles {
                let d = named.iter().find(|d| d.name == p.trim()).ok_or_else(|| {
                    let known: Vec<_> = named.iter().map(|d| d.name.as_str()).collect();
                    LabError::BadValue(format!(
                        "no pole {p:?} in the named set; known: {}",
                        known.join(", ")
                    ))
                })?;
                designs.push(d.clone());
            }
        }
        designs.extend((0..args.seeded as u64).map(|k| poles::seeded(args.seed_base + k)));
        if !(args.mu.is_finite() && args.mu > 0.0 && args.mu <= 2.0) {
            return Err(LabError::BadValue(format!(
                "--mu must be in (0, 2], not {}",
                args.mu
            )));
        }
        if !(args.lead_in.is_finite() && (0.0..=60.0).contains(&args.lead_in)) {
            return Err(LabError::BadValue(format!(
                "--lead-in must be 0-60 s, not {}",
                args.lead_in
            )));
        }
        let module = PoleClimb {
            designs,
            mu: args.mu,
            lead_in_s: args.lead_in,
            ..self.clone()
        };
        let layouts = module.layouts()?;
        Ok((module, layouts))
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
        let seed = crate::lab::layout::trial_seed(layout.identity, start);
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

    fn csv_keys(&self) -> [&'static str; 4] {
        ["controller", "pole", "start", "repeat"]
    }
    fn csv_header(&self) -> &'static str {
        report::CSV_HEADER
    }
    fn csv_row(&self, result: &TrialResult<Self>) -> String {
        report::csv_row(result)
    }
    fn summary_tables(&self, results: &[TrialResult<Self>], _ctx: &SummaryContext) -> String {
        report::summary_tables(results, &self.designs)
    }
    fn trial_plots(
        &self,
        dir: &Path,
        r: &TrialResult<Self>,
        (_, goal, rec): (&WorldSpec, &PoleGoal, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        if rec.windows.iter().all(|w| w.is_empty()) {
            return Ok(Vec::new());
        }
        let p = dir.join(format!("windows-{}.png", file_stem(&r.controller)));
        let title = format!("{}: pole {}, start {}", r.controller, r.layout, r.start);
        plots::windows_plot(&p, &title, goal, rec)?;
        Ok(vec![p])
    }
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join("climb.png");
        plots::climb_plot(&p, results)?;
        Ok(vec![p])
    }
}
