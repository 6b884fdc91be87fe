//! What makes an experiment, separate from the machinery every experiment shares (the
//! trial through the daemon's loop, the runner across threads and shards, the report
//! writer, the command line): its gait, the controllers it compares, its own options
//! and layouts, its worlds, the goal that ends a trial, its metrics, its CSV columns,
//! its summary tables and its plots. An experiment is one folder implementing
//! [`Experiment`] plus one line in [`crate::lab::registry::EXPERIMENTS`]. The contract
//! sits at the bottom of the lab: it names neither the runner nor the report, which
//! build on it ([`TrialResult`], [`SummaryContext`] are its terms).

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

use std::sync::Arc;

use super::LabError;
use super::layout::Layout;
use super::odometry_check::OdometryCheck;
use super::strain::Strain;
use super::stuck_check::StuckCheck;
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

/// Who an experiment is: what `snake-lab list`, `--help`, the runner and the summary
/// show and use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct About {
    /// Its `snake-lab` subcommand.
    pub name: &'static str,
    /// One line for `snake-lab list` and `--help`.
    pub summary: &'static str,
    /// The heading of its `summary.md`.
    pub title: &'static str,
    /// The gait its controllers run.
    pub gait: GaitKind,
    /// The controllers it compares by default, in report order (registry names).
    pub controllers: &'static [&'static str],
    /// Whether it compares gaits: a controller name not in its gait is looked up in the
    /// others, and `navigator` runs the navigator.
    pub any_gait: bool,
    /// The controller a `--variant` overrides unless its JSON names another.
    pub variant_base: &'static str,
    /// Its defaults for the common options.
    pub defaults: Defaults,
}

/// What the summary says about how the results were made.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct SummaryContext {
    /// The exact command line.
    pub command: String,
    pub layouts: Vec<String>,
    pub starts: usize,
    /// Trials per start (differing in their sensor-noise seed).
    pub repeats: usize,
    pub limit_s: f64,
    /// PNG files written beside the summary (names).
    pub plots: Vec<String>,
    /// Controllers calibrated on open ground before the trials: label and what was
    /// measured (JSON).
    pub calibrations: Vec<(String, String)>,
}

/// One finished trial of experiment `E`.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct TrialResult<E: Experiment> {
    pub controller: String,
    pub layout: String,
    pub start: usize,
    pub repeat: usize,
    pub metrics: E::Metrics,
    /// What the trial asked of the actuators (every experiment reports it).
    pub strain: Strain,
    /// How the loop's stuck detector did against the truth (every experiment).
    #[serde(default)]
    pub stuck: StuckCheck,
    /// How the estimator's contact odometry did against the truth (every experiment).
    #[serde(default)]
    pub odometry: OdometryCheck,
    /// How the fused position did against the truth (with `--pose-source`).
    #[serde(default)]
    pub position: super::position_check::PositionCheck,
    /// The world and the full record, kept for the trial the report plots (each
    /// controller's first layout and start).
    pub plotted: Option<(Arc<WorldSpec>, E::Goal, TrialRecord)>,
}

/// The controllers of `results`, in the order they first appear.
pub fn controller_names<E: Experiment>(results: &[TrialResult<E>]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for r in results {
        if !names.contains(&r.controller.as_str()) {
            names.push(&r.controller);
        }
    }
    names
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

    /// Who it is (as its options configure it).
    fn about(&self) -> About;

    /// Its `snake-lab` subcommand.
    fn name(&self) -> &'static str {
        self.about().name
    }
    fn summary(&self) -> &'static str {
        self.about().summary
    }
    fn title(&self) -> &'static str {
        self.about().title
    }
    fn gait(&self) -> GaitKind {
        self.about().gait
    }
    fn controllers(&self) -> &'static [&'static str] {
        self.about().controllers
    }
    fn any_gait(&self) -> bool {
        self.about().any_gait
    }
    fn variant_base(&self) -> &'static str {
        self.about().variant_base
    }
    fn defaults(&self) -> Defaults {
        self.about().defaults
    }

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
    /// Plots of one controller's plotted trial (its first layout, start and repeat);
    /// none by default.
    fn trial_plots(
        &self,
        dir: &Path,
        result: &TrialResult<Self>,
        plotted: (&WorldSpec, &Self::Goal, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        let _ = (dir, result, plotted);
        Ok(Vec::new())
    }
    /// Plots over every trial; none by default.
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let _ = (dir, results);
        Ok(Vec::new())
    }
}
