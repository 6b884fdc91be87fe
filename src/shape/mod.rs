//! Shape-based compliance (SPEC §3-§5): shape functions with analytic Jacobians,
//! admittance in shape space, activation windows and their manager, and the
//! controllers built from them (compliant slithering and its ablations, a CPG baseline).

pub mod admittance;
pub mod compliant_slithering;
pub mod controller;
pub mod cpg;
pub mod function;
pub mod report;
pub mod slithering_config;
pub mod slithering_shape;
pub mod torque;
pub mod window;
pub mod window_manager;

pub use compliant_slithering::CompliantSlithering;
pub use controller::{JointController, Measured, OpenLoopSlithering};
pub use function::ShapeFunction;
pub use report::{ComplianceReport, FieldReport, REPORT_MAX_WINDOWS};
pub use slithering_config::{Centralization, SlitheringCompliance};

use crate::gait::{BodyLayout, GaitParams};

/// Names of the slithering controllers the lab and the daemon can build, in the order
/// the lab reports them: open loop, the ablations (each adds a compliant parameter), the
/// centralisation variants of the full controller, and the CPG baseline.
pub const SLITHERING_CONTROLLERS: &[&str] = &[
    "open_loop",
    "a",
    "a_ws",
    "a_ws_omega",
    "a_ws_omega_central",
    "a_ws_omega_per_joint",
    "a_ws_omega_windowed_phase",
    "cpg",
];

/// Builds the slithering controller called `name` for `layout` with nominal `params`.
pub fn slithering_controller(
    name: &str,
    layout: &BodyLayout,
    params: &GaitParams,
) -> Result<Box<dyn JointController>, String> {
    let known = || SLITHERING_CONTROLLERS.join(", ");
    match name {
        "open_loop" => Ok(Box::new(OpenLoopSlithering::new(layout.clone(), params))),
        "cpg" => Ok(Box::new(cpg::Cpg::new(
            layout,
            params,
            cpg::CpgGains::default(),
        ))),
        _ => {
            let static_name = SLITHERING_CONTROLLERS
                .iter()
                .find(|n| **n == name)
                .ok_or_else(|| {
                    format!("unknown slithering controller {name:?}; known: {}", known())
                })?;
            let config = SlitheringCompliance::preset(name).ok_or_else(|| {
                format!("unknown slithering controller {name:?}; known: {}", known())
            })?;
            Ok(Box::new(CompliantSlithering::new(
                static_name,
                layout,
                params,
                config,
            )?))
        }
    }
}
