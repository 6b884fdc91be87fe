//! What makes an experiment, separate from the machinery every experiment shares (the
//! trial through the daemon's loop, the runner across threads and shards, the report
//! writer, the command line): its gait, the controllers it compares, its own options
//! and layouts, its worlds, the goal that ends a trial, its metrics, its CSV columns,
//! its summary tables and its plots. An experiment is one folder implementing
//! [`Experiment`] plus one line in [`crate::lab::registry::EXPERIMENTS`].

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::LabError;
use super::layout::Layout;
use super::report::SummaryContext;
use super::runner::TrialResult;
use super::trial::{TrialConfig, TrialRecord};
use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::gait::GaitKind;

/// The condition that ends a trial early, read from the ground truth.
pub trait Goal: Sync {
    fn reached(&self, plant: &dyn Plant) -> bool;
}

/// The defaults of the options every experiment has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defaults {
    /// Starts (poses) per layout.
    pub starts: usize,
    /// Trials per start, differing only in their sensor-noise seed.
    pub repeats: usize,
    /// Time limit of a trial, simulated s.
    pub seconds: f64,
}

/// One experiment (serialisable: a shard file carries it as configured). The runner (`lab::runner`) plans its worlds, runs every controller
/// on each through the daemon's loop until the goal or the time limit, and hands each
/// trial's record back for its metrics; `lab::report` writes its CSV, summary and
/// plots from the pieces below.
pub trait Experiment: Sync + Sized + Serialize + DeserializeOwned + 'static {
    /// What ends one world's trials (kept with the plotted trial, so serialisable).
    type Goal: Goal + Clone + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned;
    /// One trial's figures.
    type Metrics: Clone + Send + PartialEq + std::fmt::Debug + Serialize + DeserializeOwned;
    /// Its own command-line options, beside the common ones (`lab::cli::CommonArgs`).
    type Args: clap::Args + clap::FromArgMatches + std::fmt::Debug;

    /// Its `snake-lab` subcommand.
    fn name(&self) -> &'static str;
    /// One line for `snake-lab list` and `--help`.
    fn summary(&self) -> &'static str;
    /// The heading of its `summary.md`.
    fn title(&self) -> &'static str;
    /// The gait its controllers run.
    fn gait(&self) -> GaitKind;
    /// The controllers it compares by default, in report order (registry names).
    fn controllers(&self) -> &'static [&'static str];
    /// Whether it compares gaits: a controller name not in its gait is looked up in the
    /// others, and `navigator` runs the navigator (default: its gait's controllers only).
    fn any_gait(&self) -> bool {
        false
    }
    /// The controller a `--variant` overrides unless its JSON names another.
    fn variant_base(&self) -> &'static str;
    /// Its defaults for the common options.
    fn defaults(&self) -> Defaults;

    /// The experiment as its options configure it (its gait included), and its
    /// layouts; may adjust the trials' configuration (the body's module count). The
    /// gaits' nominal parameters are set after, for the configured gait.
    fn configure(
        &self,
        args: &Self::Args,
        trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError>;

    /// The protocol its configuration came with (a scenario file's `[protocol]`,
    /// `lab::protocol`): the nominal, layouts, starts, repeats and time limit the run
    /// takes where the command line gives none, over [`Experiment::defaults`].
    fn protocol(&self) -> Option<&super::protocol::Protocol> {
        None
    }

    /// The experiment once the trials' configuration is final (the gaits' nominal
    /// parameters, the module count): for figures computed from them.
    fn with_trial(self, _trial: &TrialConfig) -> Self {
        self
    }

    /// The world of start `start` of `layout` for a body of `modules`, and its goal.
    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, Self::Goal), LabError>;
    /// How a trial runs on the world whose goal is `goal`: the experiment's unless the
    /// world needs its own (the nominal parameters an operator would set for it).
    fn trial_config(&self, base: &TrialConfig, _goal: &Self::Goal) -> TrialConfig {
        *base
    }
    /// The figures of a finished trial on the world whose goal was `goal`.
    fn metrics(&self, goal: &Self::Goal, rec: &TrialRecord) -> Self::Metrics;

    /// The names of a trial's key columns: controller, layout, start, repeat.
    fn csv_keys(&self) -> [&'static str; 4] {
        ["controller", "layout", "start", "repeat"]
    }
    /// Its own CSV columns, after the keys (the writer appends the strain's).
    fn csv_header(&self) -> &'static str;
    /// One trial's own columns under [`Experiment::csv_header`], without a newline.
    fn csv_row(&self, result: &TrialResult<Self>) -> String;
    /// Its summary's tables and their definitions, between the run's description and
    /// the common sections (calibrations, strain, plots).
    fn summary_tables(&self, results: &[TrialResult<Self>], ctx: &SummaryContext) -> String;
    /// Plots of one controller's plotted trial (its first layout, start and repeat).
    fn trial_plots(
        &self,
        dir: &Path,
        result: &TrialResult<Self>,
        plotted: (&WorldSpec, &Self::Goal, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError>;
    /// Plots over every trial.
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError>;
}
