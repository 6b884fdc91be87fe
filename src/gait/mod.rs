//! Open-loop gaits (SPEC §2): serpenoid waves per plane, their parameter sets,
//! and the selector that blends between them.
//!
//! Everything here is pure: time comes in as an argument, nothing allocates after
//! construction, nothing reads a clock.

pub mod layout;
pub mod params;
pub mod selector;
pub mod serpenoid;

pub use layout::{BodyLayout, Plane};
pub use params::{GaitKind, GaitParams, GaitTable, ParamError, ParamPatch};
pub use selector::GaitSelector;
