//! The peg-board experiment (SPEC §5, thesis Fig. 4.6): slithering controllers on
//! seeded irregular peg boards, a trial ending when the front half of the body leaves
//! the board (as the thesis's did); success = it left across, by the far edge (a side
//! exit is counted apart); time to traverse in body-wave cycles per metre, and the
//! centre's signed progress across the board.

pub mod board;
pub mod metrics;
pub mod plots;
pub mod report;

use std::path::{Path, PathBuf};

use board::{Board, Exit, PEG_BOARD_TOML, board_world};
use metrics::{TrialMetrics, trial_metrics};

use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::WorldScenario;
use crate::gait::GaitKind;
use crate::lab::LabError;
use crate::lab::aim::Aim;
use crate::lab::experiment::{About, Defaults, Experiment, Goal};
use crate::lab::layout::Layout;
use crate::lab::metrics::MetricsConfig;
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord, front_half_centre, front_half_of};

/// The experiment.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct Pegboard {
    /// Every controller aimed across the board (`controller.heading`), as an operator
    /// would; off: each holds what its own configuration says.
    pub aim: bool,
}

impl Pegboard {
    /// As registered: not aimed until `--aim` says so.
    pub const UNCONFIGURED: Pegboard = Pegboard { aim: false };
}

/// Its own options: which boards.
#[derive(Debug, Clone, clap::Args)]
pub struct PegboardArgs {
    /// Seeded random layouts of the board: seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 20)]
    pub layouts: usize,
    /// Master seed of the first seeded layout.
    #[arg(long, default_value_t = 1000)]
    pub seed_base: u64,
    /// World scenario the seeded layouts come from (default: the built-in
    /// scenarios/peg-board-40-inside.toml, starts among the pegs as in the thesis;
    /// scenarios/peg-board-40.toml starts at the board's edge).
    #[arg(long, value_name = "FILE")]
    pub board: Option<PathBuf>,
    /// An explicit layout: a world scenario file, run as is (repeatable).
    #[arg(long = "scenario", value_name = "FILE")]
    pub scenarios: Vec<PathBuf>,
    /// Aim every controller across the board, as an operator would (`controller.heading`
    /// at the takeover: the controllers that steer hold that heading; the others
    /// refuse it and run as they are).
    #[arg(long)]
    pub aim: bool,
}

/// Its controllers, in report order: open loop, the ablations (each adds a compliant
/// parameter), the centralisation variants of the full controller, the CPG baseline,
/// and switching directional compliance (SPEC §8, calibrated on open ground first).
pub const CONTROLLERS: &[&str] = &[
    "open_loop",
    "a",
    "a_ws",
    "a_ws_omega",
    "a_ws_omega_central",
    "a_ws_omega_per_joint",
    "a_ws_omega_windowed_phase",
    "cpg",
    "dc_switching",
];

impl Experiment for Pegboard {
    type Goal = Board;
    type Metrics = TrialMetrics;
    type Args = PegboardArgs;

    fn about(&self) -> About {
        About {
            name: "pegboard",
            summary: "slithering through seeded peg boards (SPEC §5): cycles per metre, success, time stuck",
            title: "Peg-board experiment (SPEC §5)",
            gait: GaitKind::Slithering,
            controllers: CONTROLLERS,
            any_gait: false,
            variant_base: crate::lab::compared::VARIANT_BASE,
            defaults: {
                Defaults {
                    starts: 3,
                    repeats: 1,
                    seconds: 120.0,
                }
            },
        }
    }

    fn configure(
        &self,
        args: &PegboardArgs,
        _trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        let base = match &args.board {
            Some(path) => WorldScenario::load(path)?,
            None => WorldScenario::parse(PEG_BOARD_TOML)?,
        };
        let mut layouts: Vec<Layout> = (0..args.layouts as u64)
            .map(|k| Layout::seeded(&base, args.seed_base.wrapping_add(k)))
            .collect();
        for path in &args.scenarios {
            layouts.push(Layout::from_file(path)?);
        }
        Ok((Pegboard { aim: args.aim }, layouts))
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, Board), LabError> {
        board_world(layout, modules, start)
    }

    fn trial_config(&self, base: &TrialConfig, board: &Board) -> TrialConfig {
        let f = board.forward();
        TrialConfig {
            aim: self.aim.then(|| Aim {
                travel_rad: f[1].atan2(f[0]),
                sidewind_drift_rad: 0.0,
                goal_m: None,
            }),
            ..*base
        }
    }

    fn metrics(&self, board: &Board, rec: &TrialRecord) -> TrialMetrics {
        // The trial ended at the sample it left the board: where the front half was then.
        let exit = if rec.success {
            board.exit(front_half_of(rec.end_links_m.iter().copied()))
        } else {
            None
        };
        let m = trial_metrics(
            &rec.centre_m,
            rec.sample_dt_s,
            rec.seconds,
            exit == Some(Exit::Far),
            rec.temporal_freq_rad_s,
            &MetricsConfig::for_wave(rec.temporal_freq_rad_s),
        );
        let progress_m = match (rec.centre_m.first(), rec.centre_m.last()) {
            (Some(a), Some(b)) => {
                let f = board.forward();
                (b[0] - a[0]) * f[0] + (b[1] - a[1]) * f[1]
            }
            _ => 0.0,
        };
        TrialMetrics {
            self_contacts: rec.self_contacts,
            side_exit: exit == Some(Exit::Side),
            progress_m,
            ..m
        }
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
        (world, board, rec): (&WorldSpec, &Board, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        let title = format!("{}: layout {}, start {}", r.controller, r.layout, r.start);
        let region = Some(&board.region);
        crate::lab::plots::path_and_signals(dir, &r.controller, &title, world, region, rec)
    }
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join("cycles_per_m.png");
        plots::results_plot(&p, results)?;
        Ok(vec![p])
    }
}

/// A trial is over when the front half of the body has crossed the board.
impl Goal for Board {
    fn reached(&self, plant: &dyn Plant) -> bool {
        self.crossed(front_half_centre(plant))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::scenario::Region;

    #[test]
    fn aimed_trials_travel_across_the_board_from_their_entry_edge() {
        let region = Region {
            x_m: [0.0, 2.0],
            y_m: [-0.6, 0.6],
        };
        let base = TrialConfig::default();
        // Tail towards −x: entered by x_min, across is +x; tail towards +x: across is −x.
        for (tail_yaw, travel) in [(std::f64::consts::PI, 0.0), (0.0, std::f64::consts::PI)] {
            let board = Board::new(region, tail_yaw);
            let aimed = Pegboard { aim: true }.trial_config(&base, &board);
            let a = aimed.aim.expect("aimed");
            assert!((crate::num::wrap_pi(a.travel_rad - travel)).abs() < 1e-12);
            assert_eq!(a.sidewind_drift_rad, 0.0);
            // The start's head faces across, so slithering's nominal heading is 0.
            let h = a.nominal_heading(GaitKind::Slithering, tail_yaw).unwrap();
            assert!(h.abs() < 1e-12, "{h}");
            let plain = Pegboard::UNCONFIGURED.trial_config(&base, &board);
            assert!(plain.aim.is_none());
        }
    }
}
