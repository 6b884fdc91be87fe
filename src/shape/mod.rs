//! Shape-based compliance's building blocks (SPEC §3-§4): shape functions with
//! analytic Jacobians, admittance in shape space, torque filtering, activation windows
//! and their manager. Controllers (`crate::controllers`) compose them.

pub mod admittance;
pub mod function;
pub mod helix_shape;
mod joint_samples;
pub mod slithering_shape;
pub mod torque;
pub mod window;
pub mod window_manager;
mod window_set;

pub use function::ShapeFunction;
