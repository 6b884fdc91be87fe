//! Getting across (issue 28, point 4): trials start inside or at the edge of a board of
//! obstacles, lying along the direction of travel (+x) or across it, and must leave by
//! the far edge within the time limit. Boards come from generator families
//! (`scenarios/crossing/`), at the skin's friction or the sleeve's. Any controller of
//! any gait is compared, each aimed across (`controller.heading`: a slithering body
//! heads +x, a sidewinding one lies across +x so that it travels +x). Definitions:
//! docs/lab.md, "Crossing".

pub mod metrics;
pub mod plot;
pub mod report;
pub mod starts;

#[cfg(test)]
mod drift_tests;

use std::path::{Path, PathBuf};

use metrics::{CrossingMetrics, crossing_metrics};
use starts::StartKind;

use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::{FrictionSpec, WorldScenario};
use crate::gait::GaitKind;
use crate::lab::LabError;
use crate::lab::aim::Aim;
use crate::lab::experiment::{About, Defaults, Experiment, Goal};
use crate::lab::layout::Layout;
use crate::lab::pegboard::board::{Board, board_region};
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord, front_half_centre};

/// The generator families, built in: (name, scenario).
pub const FAMILIES: &[(&str, &str)] = &[
    (
        "thesis",
        include_str!("../../../scenarios/crossing/thesis.toml"),
    ),
    (
        "mixed",
        include_str!("../../../scenarios/crossing/mixed.toml"),
    ),
    (
        "rocks",
        include_str!("../../../scenarios/crossing/rocks.toml"),
    ),
];

/// The skin's friction (bare modules, floor and obstacles alike) and the sleeve's
/// (the thesis's braided polyester sleeve, SPEC §5).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
pub enum Skin {
    /// µ 0.5 on the floor and the obstacles.
    Bare,
    /// µ 0.2 on the floor and the obstacles.
    Sleeve,
}

impl Skin {
    pub fn mu(self) -> f64 {
        match self {
            Skin::Bare => 0.5,
            Skin::Sleeve => 0.2,
        }
    }
}

/// The experiment as configured.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Crossing {
    pub skin: Skin,
    /// The start kinds cycled through: start `k` is `kinds[k % kinds_len]`.
    pub kinds: [StartKind; 4],
    pub kinds_len: usize,
    /// How sidewinding is aimed: its bend to the left made up for, rad.
    pub sidewind_drift_rad: f64,
}

impl Crossing {
    pub const UNCONFIGURED: Crossing = Crossing {
        skin: Skin::Bare,
        kinds: StartKind::ALL,
        kinds_len: 4,
        sidewind_drift_rad: crate::navigation::SIDEWINDING_DRIFT_RAD,
    };

    /// The kind of start `start`.
    pub fn kind(&self, start: u64) -> StartKind {
        self.kinds[(start % self.kinds_len.max(1) as u64) as usize]
    }
}

/// Its own options: which boards, which skin.
#[derive(Debug, Clone, clap::Args)]
pub struct CrossingArgs {
    /// The generator family of the boards: thesis, mixed or rocks (scenarios/crossing/).
    #[arg(long, default_value = "thesis")]
    pub family: String,
    /// A scenario file instead of a family (its [[peg_board]] regions make the board).
    #[arg(long, value_name = "FILE", conflicts_with = "family")]
    pub board: Option<PathBuf>,
    /// The skin's friction on the floor and the obstacles.
    #[arg(long, value_enum, default_value = "bare")]
    pub skin: Skin,
    /// Seeded layouts: the scenario with master seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 10)]
    pub layouts: usize,
    /// Master seed of the first layout (default: the scenario's own).
    #[arg(long)]
    pub seed_base: Option<u64>,
    /// The start kinds, cycled through by the starts (default: all four, so
    /// `--starts 4` runs each once).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub kinds: Vec<StartKind>,
    /// Aim sidewinding (a single controller and the navigator's) this much to the right
    /// of its plain heading, rad, because among obstacles it bends left (default: the
    /// daemon's, docs/navigation.md).
    #[arg(long, allow_hyphen_values = true)]
    pub sidewind_drift_rad: Option<f64>,
}

/// Its default controllers: open-loop slithering, the best compliant slithering,
/// switching directional compliance, anti-compliant sidewinding.
pub const CONTROLLERS: &[&str] = &["open_loop", "a_ws_omega", "dc_switching", "ac_sfc"];

/// With a position source the navigator steers to the far edge's middle, this far
/// beyond it, m (the trial ends when the front half crosses the edge).
pub const GOAL_BEYOND_M: f64 = 1.0;

/// What ends a trial and what it was aimed at.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CrossingGoal {
    /// The board: entered by x_min, crossed by x_max.
    pub board: Board,
    pub kind: StartKind,
}

impl Goal for CrossingGoal {
    fn reached(&self, plant: &dyn Plant) -> bool {
        self.board.crossed(front_half_centre(plant))
    }
}

impl Experiment for Crossing {
    type Goal = CrossingGoal;
    type Metrics = CrossingMetrics;
    type Args = CrossingArgs;

    fn about(&self) -> About {
        About {
            name: "crossing",
            summary: "getting across boards of obstacles from inside and the edge, any gait (issue 28)",
            title: "Crossing boards of obstacles (issue 28)",
            gait: GaitKind::Slithering,
            controllers: CONTROLLERS,
            any_gait: true,
            variant_base: crate::lab::compared::VARIANT_BASE,
            defaults: {
                Defaults {
                    starts: StartKind::ALL.len(),
                    repeats: 1,
                    seconds: 180.0,
                }
            },
        }
    }

    fn configure(
        &self,
        args: &CrossingArgs,
        _trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        let mut base = match &args.board {
            Some(path) => WorldScenario::load(path)?,
            None => {
                let (_, toml) = FAMILIES
                    .iter()
                    .find(|(n, _)| *n == args.family)
                    .ok_or_else(|| {
                        let known: Vec<&str> = FAMILIES.iter().map(|(n, _)| *n).collect();
                        LabError::BadValue(format!(
                            "--family {:?}: not one of {}",
                            args.family,
                            known.join(", ")
                        ))
                    })?;
                WorldScenario::parse(toml)?
            }
        };
        if base.peg_boards.is_empty() {
            return Err(LabError::BadValue(
                "the scenario has no [[peg_board]]: its regions make the board to cross".into(),
            ));
        }
        base.friction = FrictionSpec {
            mu: args.skin.mu(),
            anisotropic: None,
            peg_mu: Some(args.skin.mu()),
        };
        let seed_base = args.seed_base.unwrap_or(base.seed);
        let layouts = (0..args.layouts as u64)
            .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
            .collect();
        let mut exp = Crossing {
            skin: args.skin,
            ..Crossing::UNCONFIGURED
        };
        if let Some(d) = args.sidewind_drift_rad {
            if !(d.is_finite() && d.abs() <= std::f64::consts::FRAC_PI_2) {
                return Err(LabError::BadValue(format!(
                    "--sidewind-drift-rad {d}: a finite angle within ±π/2"
                )));
            }
            exp.sidewind_drift_rad = d;
        }
        if !args.kinds.is_empty() {
            if args.kinds.len() > 4 {
                return Err(LabError::BadValue("--kinds: at most four".into()));
            }
            exp.kinds_len = args.kinds.len();
            exp.kinds[..args.kinds.len()].copy_from_slice(&args.kinds);
        }
        Ok((exp, layouts))
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, CrossingGoal), LabError> {
        let mut scenario = layout.scenario.clone();
        let region = scenario
            .peg_boards
            .iter()
            .map(|b| b.region)
            .reduce(|a, b| crate::emu::world::scenario::Region {
                x_m: [a.x_m[0].min(b.x_m[0]), a.x_m[1].max(b.x_m[1])],
                y_m: [a.y_m[0].min(b.y_m[0]), a.y_m[1].max(b.y_m[1])],
            })
            .ok_or_else(|| LabError::NoBoard {
                layout: layout.name.clone(),
            })?;
        let kind = self.kind(start);
        scenario.start = kind.start_gen(&region, modules);
        let world = scenario.generate_trial(modules, start)?;
        let region = board_region(&scenario, &world).unwrap_or(region);
        // Entered by x_min whatever way the body lies: travel is +x.
        let board = Board::new(region, std::f64::consts::PI);
        Ok((world, CrossingGoal { board, kind }))
    }

    fn trial_config(&self, base: &TrialConfig, goal: &CrossingGoal) -> TrialConfig {
        let r = &goal.board.region;
        TrialConfig {
            aim: Some(Aim {
                travel_rad: 0.0,
                sidewind_drift_rad: self.sidewind_drift_rad,
                // The far edge's middle, beyond it: the most room on either side.
                goal_m: Some([r.x_m[1] + GOAL_BEYOND_M, 0.5 * (r.y_m[0] + r.y_m[1])]),
            }),
            ..*base
        }
    }

    fn metrics(&self, goal: &CrossingGoal, rec: &TrialRecord) -> CrossingMetrics {
        crossing_metrics(goal, rec)
    }

    fn csv_header(&self) -> &'static str {
        report::CSV_HEADER
    }
    fn csv_row(&self, result: &TrialResult<Self>) -> String {
        report::csv_row(result)
    }
    fn summary_tables(&self, results: &[TrialResult<Self>], _ctx: &SummaryContext) -> String {
        report::summary_tables(self, results)
    }
    fn trial_plots(
        &self,
        dir: &Path,
        r: &TrialResult<Self>,
        (world, goal, rec): (&WorldSpec, &CrossingGoal, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        let title = format!(
            "{}: layout {}, start {} ({})",
            r.controller,
            r.layout,
            r.start,
            goal.kind.name()
        );
        let region = Some(&goal.board.region);
        if rec.signal_names.iter().any(|n| n == plot::CHOICE_SIGNAL) {
            let stem = crate::lab::file_stem(&r.controller);
            let path = dir.join(format!("path-{stem}.png"));
            plot::choice_path_plot(&path, &title, world, region, rec)?;
            let signals = dir.join(format!("signals-{stem}.png"));
            crate::lab::plots::signals_plot(&signals, &title, rec)?;
            return Ok(vec![path, signals]);
        }
        crate::lab::plots::path_and_signals(dir, &r.controller, &title, world, region, rec)
    }
    fn run_plots(
        &self,
        _dir: &Path,
        _results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        Ok(Vec::new())
    }
}
