//! Open-loop gaits (SPEC §2): serpenoid waves per plane, their parameter sets,
//! and the selector that blends between them.
//!
//! Everything here is pure: time comes in as an argument, nothing allocates after
//! construction, nothing reads a clock. See `docs/gaits.md`.

pub mod body;
pub mod kinematics;
pub mod params;
pub mod selector;
pub mod serpenoid;
pub mod slew;

pub use body::{BodyLayout, Plane};
pub use params::{Field, GaitKind, GaitParams, GaitTable, JOINT_LIMIT_RAD, ParamError, ParamPatch};
pub use selector::{BLEND_TIME_RANGE_S, DEFAULT_BLEND_TIME_S, GaitSelector, smoothstep};
pub use serpenoid::{Serpenoid, Wave, helix_wave};
