//! What makes an experiment, separate from the machinery every experiment shares (the
//! trial through the daemon's loop, the runner across threads, recording): its gait,
//! the controllers it compares, its worlds, and the goal that ends a trial. The
//! peg-board experiment is the first ([`crate::lab::pegboard`]); pole climbing,
//! sidewinding through pegs and directional compliance are to be modules like it.

use crate::emu::Plant;
use crate::gait::GaitKind;

/// The condition that ends a trial early as a success, read from the ground truth.
pub trait Goal: Sync {
    fn reached(&self, plant: &dyn Plant) -> bool;
}

/// An experiment module.
pub trait ExperimentModule: Sync {
    /// Its `snake-lab` subcommand.
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    /// The gait its controllers run.
    fn gait(&self) -> GaitKind;
    /// The controllers it compares by default, in report order (registry names).
    fn controllers(&self) -> &'static [&'static str];
}
