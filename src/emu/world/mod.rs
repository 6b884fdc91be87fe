//! The world the simulated snake touches, described as plain data (`WorldSpec`),
//! produced from scenario files by seeded generators (`scenario`), and turned into
//! a rapier3d rigid-body world by `physics`.
//!
//! Frames: world z up, gravity −z, metres. The ground's top surface is z = 0.

mod build;
pub mod generators;
pub mod physics;
pub mod scenario;
pub mod spec;
mod validate;

pub use spec::*;
