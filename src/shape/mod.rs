//! Shape-based compliance (SPEC §3-§5): shape functions with analytic Jacobians,
//! admittance in shape space, activation windows and their manager, and the
//! controllers built from them (compliant slithering and its ablations, a CPG baseline).

pub mod admittance;
pub mod controller;
pub mod function;
pub mod slithering_shape;
pub mod torque;
pub mod window;
pub mod window_manager;

pub use controller::{JointController, Measured, OpenLoopSlithering};
pub use function::ShapeFunction;

use crate::gait::{BodyLayout, GaitParams};

/// Names of the slithering controllers the lab and the daemon can build, in the order
/// the lab reports them.
pub const SLITHERING_CONTROLLERS: &[&str] = &["open_loop"];

/// Builds the slithering controller called `name` for `layout` with nominal `params`.
pub fn slithering_controller(
    name: &str,
    layout: &BodyLayout,
    params: &GaitParams,
) -> Result<Box<dyn JointController>, String> {
    match name {
        "open_loop" => Ok(Box::new(OpenLoopSlithering::new(layout.clone(), params))),
        other => Err(format!(
            "unknown slithering controller {other:?}; known: {}",
            SLITHERING_CONTROLLERS.join(", ")
        )),
    }
}
