//! The interface every joint-space controller offers to the lab and the daemon: time is
//! an argument, the measured joints come in, set-points go out, nothing allocates.

use super::report::ComplianceReport;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Plane, Serpenoid};

/// What a controller sees of the modules each step.
#[derive(Debug, Clone, Copy)]
pub struct Measured<'a> {
    /// Joint angles, rad.
    pub position_rad: &'a [f64],
    /// Reported spring torques, N·m, in the protocol's sign (docs/protocol.md): the
    /// torque the motor side applies to the output. The environment's torque on the
    /// joint is about the opposite (see `shape::torque`).
    pub torque_nm: &'a [f64],
}

/// A joint-space controller stepped at the loop rate.
pub trait JointController: Send {
    /// Its name in the lab's tables and the daemon's status.
    fn name(&self) -> &'static str;
    /// Joint set-points at `t_s` from `measured`. Deterministic; allocates nothing.
    fn step(&mut self, t_s: f64, measured: &Measured<'_>, set_points_rad: &mut [f64]);
    /// Nominal temporal frequency of the body wave, rad/s (the lab counts nominal wave
    /// cycles `ωT·t / 2π`, as the thesis does).
    fn temporal_freq_rad_s(&self) -> f64;
    /// Named values worth logging or plotting (shape parameters, forces), in a fixed
    /// order for a given controller: `f(name, value)` for each.
    fn for_each_signal(&self, _f: &mut dyn FnMut(&str, f64)) {}
    /// Forgets everything learnt and starts afresh: the next step behaves like the first
    /// step of a new controller (the daemon resets a controller before each takeover).
    /// Allocates nothing. Controllers with state must override it.
    fn reset(&mut self) {}
    /// Writes the compliance state after the last step into `out` (fixed size, no
    /// allocation). The default reports nothing (`out.available` false).
    fn compliance_report(&self, out: &mut ComplianceReport) {
        out.clear();
    }
}

/// Open-loop slithering: the serpenoid of `params`, lateral joints only (the thesis
/// experiment's baseline).
pub struct OpenLoopSlithering {
    layout: BodyLayout,
    gait: Serpenoid,
}

impl OpenLoopSlithering {
    pub fn new(layout: BodyLayout, params: &GaitParams) -> Self {
        let gait = Serpenoid::for_layout(GaitKind::Slithering, params, &layout);
        Self { layout, gait }
    }
}

impl JointController for OpenLoopSlithering {
    fn name(&self) -> &'static str {
        "open_loop"
    }

    fn step(&mut self, t_s: f64, _measured: &Measured<'_>, set_points_rad: &mut [f64]) {
        let psi = self.gait.temporal_freq_rad_s * t_s;
        self.gait.evaluate(&self.layout, psi, set_points_rad);
        for (out, &plane) in set_points_rad.iter_mut().zip(&self.layout.planes) {
            if plane == Plane::Dorsal {
                *out = 0.0;
            }
        }
    }

    fn temporal_freq_rad_s(&self) -> f64 {
        self.gait.temporal_freq_rad_s
    }
}
