//! Failsafe state machine (to be implemented by the gaits/failsafe helper).
use serde::Serialize;

/// What the loop does with the joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Running (or blending into) the active gait.
    Running,
    /// Set-points frozen where they were.
    Hold,
    /// Joints not driven.
    Limp,
    /// Limp and latched until the operator arms.
    EStop,
}

/// Why the loop is in its mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    Startup,
    Operator,
    FeedbackTimeout,
    NonFiniteFeedback,
    EStop,
    Shutdown,
}
