//! What crosses between the control socket and the loop. Everything is `Copy`
//! so the bounded crossbeam channels never allocate per message.
use crate::gait::{GaitKind, ParamPatch};

/// An operator request, applied by the loop at a cycle boundary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoopRequest {
    /// Blend into this gait (arms the loop if it was held or limp and feedback is healthy).
    SetGait(GaitKind),
    /// Change a gait's parameters (validated again by the loop before use).
    SetParams(GaitKind, ParamPatch),
    /// Change the gait blend time, s.
    SetBlendTime(f64),
    /// Freeze the set-points where they are.
    Hold,
    /// Stop driving the joints.
    Limp,
    /// Emergency stop: limp and latched until `Arm`.
    EStop,
    /// Leave hold / limp / e-stop: re-sync to the measured positions and blend into
    /// the active gait.
    Arm,
    /// Safe stop for shutdown: hold, then limp, then the loop exits.
    Shutdown,
}

/// A request with the ticket its answer will carry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Envelope {
    pub ticket: u64,
    pub request: LoopRequest,
}

/// Why the loop refused a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Rejection {
    #[error("e-stop is latched: send arm first")]
    EStopLatched,
    #[error("feedback is not healthy; cannot arm")]
    FeedbackUnhealthy,
    #[error("parameter out of range")]
    InvalidParams,
    #[error("shutting down")]
    ShuttingDown,
}

/// The loop's answer to one envelope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ack {
    pub ticket: u64,
    pub result: Result<(), Rejection>,
}
