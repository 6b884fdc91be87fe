//! What makes an experiment, separate from the machinery every experiment shares (the
//! trial through the daemon's loop, the runner across threads, recording): its gait,
//! the controllers it compares, its worlds, the goal that ends a trial, and its
//! metrics. The peg-board experiment is the first ([`crate::lab::pegboard`], with its
//! report in `lab::report` and `lab::plots`); pole climbing, sidewinding through pegs
//! and directional compliance are to be modules like it on the same runner.

use super::LabError;
use super::board::Layout;
use super::trial::{TrialConfig, TrialRecord};
use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::gait::GaitKind;

/// The condition that ends a trial early as a success, read from the ground truth.
pub trait Goal: Sync {
    fn reached(&self, plant: &dyn Plant) -> bool;
}

/// An experiment module: the runner (`lab::runner`) plans its worlds, runs every
/// controller on each through the daemon's loop until the goal or the time limit, and
/// hands each trial's record back for its metrics.
pub trait ExperimentModule: Sync {
    /// What ends one world's trials.
    type Goal: Goal + Clone + Send + Sync + std::fmt::Debug;
    /// One trial's figures.
    type Metrics: Clone + Send + PartialEq + std::fmt::Debug;
    /// Its `snake-lab` subcommand.
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    /// The gait its controllers run.
    fn gait(&self) -> GaitKind;
    /// The controllers it compares by default, in report order (registry names).
    fn controllers(&self) -> &'static [&'static str];
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
}
