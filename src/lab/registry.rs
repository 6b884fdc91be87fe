//! Every experiment `snake-lab` runs, in `snake-lab list` order. A new experiment is a
//! folder under `lab/` implementing [`crate::lab::experiment::Experiment`] and one line
//! here.

use super::cli::{Lab, Plugin};
use super::crossing::Crossing;
use super::displacement::Displacement;
use super::pegboard::Pegboard;
use super::pole::PoleClimb;
use super::sidewinding::SidewindingPegs;

/// The experiments, each as its unconfigured value.
pub static EXPERIMENTS: &[&dyn Lab] = &[
    &Plugin(Pegboard::UNCONFIGURED),
    &Plugin(Displacement::PEG_ARRAY),
    &Plugin(Displacement::ROCK_PILE),
    &Plugin(SidewindingPegs),
    &Plugin(PoleClimb::UNCONFIGURED),
    &Plugin(super::flat_ground::FlatGround::UNCONFIGURED),
    &Plugin(Crossing::UNCONFIGURED),
];

/// The experiment named `name`.
pub fn find(name: &str) -> Option<&'static dyn Lab> {
    EXPERIMENTS.iter().copied().find(|e| e.name() == name)
}
