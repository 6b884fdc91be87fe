//! `snake-lab`: controller comparisons in simulation, in-process and in lockstep.
//!
//! The peg-board experiment of SPEC §5 (thesis §4.1, Fig. 4.6): slithering controllers
//! from the registry ([`crate::controllers::REGISTRY`]) on seeded random peg boards and on
//! explicit layouts, several starts each. One concern per file:
//! - [`experiment`]: what an experiment module names (gait, controllers, the goal
//!   that ends a trial); [`pegboard`] is the peg-board experiment's.
//! - [`board`]: the layouts (seeded boards, explicit scenario files), the board's region,
//!   when a trial has crossed it.
//! - [`controllers`]: the compared controllers, named ones and `--variant`s.
//! - [`trial`]: one trial through the daemon's `ControlLoop` over a `SimBus`, in
//!   lockstep at 1 ms, recorded at 20 Hz.
//! - [`metrics`]: pure functions from a recorded path to the experiment's figures.
//! - [`runner`]: the trial plan and its execution across threads, with a progress bar.
//! - [`report`]: `results.csv` and `summary.md`.
//! - [`plots`]: PNG figures.
//!
//! Definitions and the command line are in `docs/lab.md`.

pub mod board;
pub mod calibration;
pub mod controllers;
pub mod displacement;
pub mod experiment;
pub mod metrics;
pub mod pegboard;
pub mod plots;
pub mod pole;
pub mod report;
pub mod runner;
pub mod sidewinding;
pub mod strain;
pub mod trial;

pub use pegboard::CONTROLLERS as PEGBOARD_CONTROLLERS;

use std::path::{Path, PathBuf};

use crate::emu::world::physics::PhysicsError;
use crate::emu::world::scenario::ScenarioError;

/// Everything the lab can fail on. [`LabError::is_bad_input`] separates what the user
/// asked for wrongly (the binary exits 2) from failures while running (exit 1).
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    #[error("unknown controller {name:?}; known: {known}")]
    UnknownController { name: String, known: String },
    #[error("no controllers chosen; known: {known}")]
    NoControllers { known: String },
    #[error("no layouts: give --layouts N > 0 or at least one --scenario FILE")]
    NoLayouts,
    #[error("--starts must be at least 1")]
    NoStarts,
    #[error("{0}")]
    BadValue(String),
    #[error("layout {layout}: no pegs, so there is no board to cross")]
    NoBoard { layout: String },
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error("trial {trial}: {source}")]
    Physics {
        trial: String,
        #[source]
        source: PhysicsError,
    },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("recording {}: {source}", path.display())]
    Record {
        path: PathBuf,
        #[source]
        source: crate::record::RecordError,
    },
    #[error("plot {}: {msg}", path.display())]
    Plot { path: PathBuf, msg: String },
}

impl LabError {
    /// True when the error is in what was asked (names, files, counts), not in the run.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            Self::UnknownController { .. }
                | Self::NoControllers { .. }
                | Self::NoLayouts
                | Self::NoStarts
                | Self::BadValue(_)
                | Self::NoBoard { .. }
                | Self::Scenario(_)
        )
    }
}

/// Writes `results.csv`, the plots and `summary.md` into `dir` (created if missing) and
/// returns the files written. Plots: `path-<controller>.png` and
/// `signals-<controller>.png` for each controller's first trial, `cycles_per_m.png`.
pub fn write_report(
    dir: &Path,
    results: &[runner::TrialResult],
    ctx: &report::SummaryContext,
) -> Result<Vec<PathBuf>, LabError> {
    std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    let csv = dir.join("results.csv");
    report::write_text(&csv, &report::results_csv(results))?;
    written.push(csv);
    let mut ctx = ctx.clone();
    for r in results {
        let Some((world, board, rec)) = &r.plotted else {
            continue;
        };
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, start {}", r.controller, r.layout, r.start);
        let p = dir.join(format!("path-{stem}.png"));
        plots::path_plot(&p, &title, world, Some(&board.region), rec)?;
        written.push(p);
        let p = dir.join(format!("signals-{stem}.png"));
        plots::signals_plot(&p, &title, rec)?;
        written.push(p);
    }
    let p = dir.join("cycles_per_m.png");
    plots::results_plot(&p, results)?;
    written.push(p);
    ctx.plots = written[1..]
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let md = dir.join("summary.md");
    report::write_text(&md, &report::summary_markdown(results, &ctx))?;
    written.push(md);
    Ok(written)
}

/// `name` with anything but ASCII letters, digits, `-` and `_` replaced by `_`.
pub(crate) fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
