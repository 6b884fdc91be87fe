//! What crosses between the control socket and the loop. Requests and acks are
//! `Copy`; the only heap object is a controller attached to an envelope, built on the
//! control side and moved (a pointer) through the bounded channel, so nothing
//! allocates per message.
use serde::Serialize;

use crate::controller_interface::{CommandRefused, ControllerCommand, NominalMismatch};
use crate::gait::{GaitKind, ParamPatch};
pub use crate::rt::controller_slots::Continuity;
use crate::rt::controller_slots::Installed;
pub use crate::safety::failsafe::Refusal;

/// An operator request, applied by the loop at a cycle boundary. Recorded as it is
/// defined (`/events`: `"request"` the variant's name, `"args"` its fields).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "request", content = "args", rename_all = "snake_case")]
pub enum LoopRequest {
    /// Blend into this gait (arms the loop if it was held or limp and feedback is healthy).
    SetGait { gait: GaitKind },
    /// Change a gait's parameters (validated again by the loop before use, also
    /// against the gait's controller). The envelope may carry a new controller for
    /// the gait, installed with them.
    SetParams { gait: GaitKind, patch: ParamPatch },
    /// Install the controller the envelope carries for this gait.
    SetController { gait: GaitKind },
    /// A command to this gait's installed controller (e.g. calibrate).
    ControllerCommand {
        gait: GaitKind,
        #[serde(flatten)]
        command: ControllerCommand,
    },
    /// Change the gait blend time, s.
    SetBlendTime { blend_time_s: f64 },
    /// A controlled stop: the gait (selector, blends, the driving controller) comes to
    /// rest within this long, s, whatever the blend time, and stands still until
    /// `ResumeGait` (`rt::gait_clock`).
    StopGait { within_s: f64 },
    /// The gait moves again, back to full rate within this long, s.
    ResumeGait { within_s: f64 },
    /// Freeze the set-points where they are.
    Hold,
    /// Stop driving the joints.
    Limp,
    /// Emergency stop: limp and latched until `Arm`.
    #[serde(rename = "estop")]
    EStop,
    /// Leave hold / limp / e-stop: re-sync to the measured positions and blend into
    /// the active gait.
    Arm,
    /// Safe stop for shutdown: hold, then limp, then the loop exits.
    Shutdown,
    /// What the navigator does now (its runner tells the loop at each change), reported
    /// with every cycle. Changes nothing the joints do.
    Navigation {
        state: crate::navigation::state::NavigatorState,
    },
}

/// A request with the ticket its answer will carry.
#[derive(Debug)]
pub struct Envelope {
    pub ticket: u64,
    pub request: LoopRequest,
    /// A controller that goes with `request` (`SetController`, or `SetParams`). The
    /// loop never frees it: a refused or replaced controller goes back through the
    /// retired channel.
    pub controller: Option<Installed>,
}

impl Envelope {
    /// A request without a controller.
    pub fn new(ticket: u64, request: LoopRequest) -> Self {
        Self {
            ticket,
            request,
            controller: None,
        }
    }
}

/// Why the loop refused a request.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum Rejection {
    /// The failsafe's (e-stop latched, feedback unhealthy, shutting down).
    #[error(transparent)]
    Failsafe(#[from] Refusal),
    #[error("parameter out of range")]
    InvalidParams,
    #[error("the gait's controller cannot follow these parameters: {0}")]
    ControllerRefuses(NominalMismatch),
    #[error("no controller attached")]
    NoController,
    #[error("the gait has no controller installed")]
    NoControllerInstalled,
    #[error("the controller refuses: {0}")]
    CommandRefused(CommandRefused),
}

/// What the loop did with a request: refused, or applied (and, for a change of a
/// gait's parameters or controller, what became of its controller).
pub type LoopResult = Result<Option<Continuity>, Rejection>;

/// The loop's answer to one envelope: refused, or applied (and, for a change of a
/// gait's parameters or controller, what became of its controller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ack {
    pub ticket: u64,
    pub result: LoopResult,
}
