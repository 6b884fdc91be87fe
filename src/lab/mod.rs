//! `snake-lab`: controller comparisons in simulation, in-process and in lockstep, each
//! trial through the daemon's own loop.
//!
//! An experiment is a folder implementing [`experiment::Experiment`] and one line in
//! [`registry::EXPERIMENTS`]: [`pegboard`] (SPEC §5), [`displacement`] (the peg array
//! and the rock pile, SPEC §8), [`sidewinding`] (SPEC §7), [`pole`] (SPEC §6).
//!
//! What they share:
//! - [`layout`]: a world scenario per layout, the seeds its trials derive from it;
//!   [`protocol`]: a scenario file's `[protocol]` (nominal, counts), a run's defaults;
//! - [`controllers`]: the compared controllers, named ones and `--variant`s;
//! - [`calibration`]: a controller's friction offsets, measured on open ground;
//! - [`trial`]: one trial through the daemon's `ControlLoop` over a `SimBus`, in
//!   lockstep at 1 ms, recorded at 20 Hz; [`strain`]: what it asked of the actuators;
//! - [`runner`]: the trial plan and its execution across threads, with progress;
//! - [`shard`]: a share of the plan for a cluster's scheduler, and the merge;
//! - [`report`]: `results.csv`, `summary.md` and the plots; [`plots`] and [`metrics`]:
//!   the plot primitives and the path and statistics helpers;
//! - [`cli`]: the options every experiment has, an experiment as a subcommand.
//!
//! Definitions and the command line are in `docs/lab.md`.

pub mod aim;
pub mod calibration;
pub mod cli;
pub mod compared;
pub mod crossing;
pub mod displacement;
pub mod experiment;
pub mod flat_ground;
pub mod layout;
pub mod metrics;
pub mod odometry_check;
pub mod pegboard;
pub mod plots;
pub mod pole;
pub mod pose_source;
pub mod position_check;
pub mod protocol;
pub mod registry;
pub mod report;
pub mod runner;
pub mod shard;
pub mod sidewinding;
pub mod strain;
pub mod stuck_check;
pub mod trial;
pub mod trial_navigator;
pub mod truth;

use std::path::PathBuf;

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
    #[error("shard file {}: {msg}", path.display())]
    Shard { path: PathBuf, msg: String },
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

#[cfg(test)]
mod periodicity_tests;
