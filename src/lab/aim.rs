//! Aiming a trial's controller as an operator would: a direction of travel in the true
//! world becomes the body heading the gait needs in the estimate's world, sent as
//! `controller.heading` once the controller drives (before it, the loop's slot would
//! take it for a controller that is not running yet).

use crossbeam_channel::Sender;

use crate::controller_interface::ControllerCommand;
use crate::gait::GaitKind;
use crate::rt::control_loop::ControlLoop;
use crate::rt::messages::{Envelope, LoopRequest};

/// A direction of travel in the true world, which the trial turns into the body heading
/// the controller's gait needs ([`crate::navigation::body_heading_for`]) in the estimate's
/// world (yaw 0 along the head at the start: docs/estimation.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aim {
    pub travel_rad: f64,
    /// Sidewinding's bend to the left among obstacles, made up for
    /// ([`crate::navigation::SIDEWINDING_DRIFT_RAD`]), rad.
    pub sidewind_drift_rad: f64,
    /// A goal in the true world (the simulated source's), m: the navigator steers to it
    /// by position when the trial has a pose source (`TrialConfig::pose_source`).
    pub goal_m: Option<[f64; 2]>,
}

impl Aim {
    /// The nominal heading for `gait` in the estimate's world of a start whose head ->
    /// tail yaw was `start_yaw_rad`; `None` for a gait that does not travel by heading.
    pub fn nominal_heading(self, gait: GaitKind, start_yaw_rad: f64) -> Option<f64> {
        crate::navigation::body_heading_for(gait, self.travel_rad, self.sidewind_drift_rad)
            .map(|h| crate::num::wrap_pi(h - facing(start_yaw_rad)))
    }

    /// The direction of travel in the estimate's world of that start.
    pub fn travel_in_estimate(self, start_yaw_rad: f64) -> f64 {
        crate::num::wrap_pi(self.travel_rad - facing(start_yaw_rad))
    }
}

/// The head's direction of a start whose head -> tail yaw is `start_yaw_rad`.
fn facing(start_yaw_rad: f64) -> f64 {
    start_yaw_rad + std::f64::consts::PI
}

/// A heading waiting for its gait's controller to drive.
#[derive(Debug, Clone, Copy, Default)]
pub struct PendingHeading(Option<(GaitKind, f64)>);

impl PendingHeading {
    pub fn new(gait: GaitKind, heading_rad: Option<f64>) -> Self {
        Self(heading_rad.map(|h| (gait, h)))
    }

    /// Sends it (ticket `ticket`) if its controller drives now; true when sent.
    pub fn send_when_engaged(
        &mut self,
        lp: &ControlLoop,
        tx: &Sender<Envelope>,
        ticket: u64,
    ) -> bool {
        let Some((gait, h)) = self.0 else {
            return false;
        };
        if lp.controllers().engaged() != Some(gait) {
            return false;
        }
        self.0 = None;
        let command = ControllerCommand::SetHeading {
            heading_rad: Some(h),
        };
        // The trial's queue has room for a few; a full one would be a sizing bug.
        let _ = tx.try_send(Envelope::new(
            ticket,
            LoopRequest::ControllerCommand { gait, command },
        ));
        true
    }
}
