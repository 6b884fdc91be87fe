//! The interface every controller offers the loop. A controller is built off the loop
//! (building allocates), then, in the loop thread and without allocating:
//! - checked against the gait's nominal parameters ([`Controller::accepts`]) before
//!   the loop takes new ones,
//! - engaged from a [`Handover`]: the set-points and wave phase the selector's blend
//!   reached, so nothing jumps, and the nominal parameters it is to follow,
//! - stepped each cycle as a pure function of a [`Tick`] (the loop's time and the time
//!   since its previous step) and an [`Observation`],
//! - asked for its [`ControllerReport`] (signal values, window fields).

use super::report::ControllerReport;
use crate::gait::{BodyLayout, GaitParams};
use crate::num::Num;

/// One module's inertial sensors, in the module's frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Imu {
    pub accel_m_s2: [f64; 3],
    pub gyro_rad_s: [f64; 3],
}

/// The body's pose as estimators see it. Estimators fill it each cycle before any
/// controller runs; without an estimator it stays `valid: false`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct BodyEstimate {
    pub valid: bool,
    /// Body frame origin in the estimator's world frame, m.
    pub position_m: [f64; 3],
    /// Body frame orientation (w, x, y, z).
    pub orientation_wxyz: [f64; 4],
    /// Heading of the body frame's forward axis in the ground plane, rad.
    pub heading_rad: f64,
    /// The shape had no clear main axis (coiled): the axis is the last one kept.
    pub round: bool,
    /// The chassis origin's ground-plane position in the estimator's world frame from
    /// contact odometry (zero where it started), m: the links on the ground taken to
    /// stay put (docs/estimation.md).
    pub odometry_m: [f64; 2],
    /// Part of the body was lifted, so `odometry_m` stood on contacts; with the whole
    /// body down (slithering) it assumes the centroid does not drift.
    pub odometry_lifted: bool,
    /// The head link's orientation (w, x, y, z) on the same world axes: with
    /// `position_m` and `orientation_wxyz`, where the head sits in the chassis frame.
    pub head_wxyz: [f64; 4],
    /// The newest external fix and its age (`estimation::external_pose`).
    pub fix: super::position::FixState,
    /// The chassis in the external source's world (`estimation::world_position`).
    pub world: super::position::WorldPosition,
}

impl BodyEstimate {
    /// No estimate yet.
    pub const NONE: BodyEstimate = BodyEstimate {
        valid: false,
        position_m: [0.0; 3],
        orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
        heading_rad: 0.0,
        round: false,
        odometry_m: [0.0; 2],
        odometry_lifted: false,
        head_wxyz: [1.0, 0.0, 0.0, 0.0],
        fix: super::position::FixState::NONE,
        world: super::position::WorldPosition::NONE,
    };
}

impl Default for BodyEstimate {
    fn default() -> Self {
        Self::NONE
    }
}

/// What a controller sees each cycle; one entry per joint (head first).
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    pub position_rad: &'a [f64],
    pub velocity_rad_s: &'a [f64],
    /// Reported spring torques, N·m, in the protocol's sign (docs/protocol.md): the
    /// torque the motor side applies to the output. The environment's torque on the
    /// joint is about the opposite (see `shape::torque`).
    pub torque_nm: &'a [f64],
    pub imu: &'a [Imu],
    pub body: &'a BodyEstimate,
}

impl Observation<'static> {
    /// No joints, no body estimate: for estimators that read none of it (tests).
    pub const NONE: Observation<'static> = Observation {
        position_rad: &[],
        velocity_rad_s: &[],
        torque_nm: &[],
        imu: &[],
        body: &BodyEstimate::NONE,
    };
}

/// The time of one step, as ros2_control hands a controller `update(time, period)`:
/// the loop's time and the time since this controller's previous step (0 at the first
/// step after an engagement, never negative).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    pub t_s: f64,
    pub dt_s: f64,
}

/// Makes the [`Tick`]s of one engaged controller: the loop's controller slot keeps
/// one, restarted at every engagement; tests that step a controller by hand use one.
#[derive(Debug, Clone, Copy, Default)]
pub struct TickClock {
    last_t_s: Option<f64>,
}

impl TickClock {
    /// The next step's tick is a first one (dt 0).
    pub fn restart(&mut self) {
        self.last_t_s = None;
    }

    /// The tick of a step at `t_s`.
    pub fn tick(&mut self, t_s: f64) -> Tick {
        let dt_s = self.last_t_s.map_or(0.0, |last| (t_s - last).max(0.0));
        self.last_t_s = Some(t_s);
        Tick { t_s, dt_s }
    }
}

/// Where the selector's blend left the joints when a controller takes over.
#[derive(Debug, Clone, Copy)]
pub struct Handover<'a> {
    /// Loop time of the takeover, s.
    pub t_s: f64,
    /// The gait's temporal phase ψ reached by the selector, rad: a controller whose
    /// nominal phase is `ψ + ωT·(t − t_s)` continues the selector's wave exactly.
    pub phase_rad: f64,
    /// The set-points the selector sent this cycle, rad.
    pub set_points_rad: &'a [f64],
    /// The gait's nominal parameters (the operator's), which the controller follows.
    pub params: &'a GaitParams,
    pub layout: &'a BodyLayout,
}

/// A nominal parameter a controller cannot follow (built without allocating, so the
/// loop can refuse a request with it).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the nominal {field} = {} is outside the controller's range {}", Num(*.value), range(*.min, *.max))]
pub struct NominalMismatch {
    pub field: &'static str,
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

/// `[min, max]`, or why there is none (an offset's room is the joint limit minus the
/// controller's reach, which can exceed it).
fn range(min: f64, max: f64) -> String {
    if min <= max {
        format!("[{}, {}]", Num(min), Num(max))
    } else {
        "(none: the controller's amplitude reach alone exceeds the joint limit; \
         lower its amplitude bound or turning reach)"
            .to_string()
    }
}

/// An operator's command to a running controller (`controller.calibrate` on the
/// socket). `Copy`: it crosses the loop's channel without allocating. Recorded as
/// `"command"` (the variant's name) beside its fields.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum ControllerCommand {
    /// Measure what the controller calibrates (e.g. the ground's friction offset of
    /// directional compliance) over the next `duration_s` of its own steps. A
    /// controller that accepts it reports a signal named `calibration`:
    /// 0 none, 1 running, 2 calibrated.
    Calibrate { duration_s: f64 },
    /// Forget the calibration (back to none).
    ClearCalibration,
    /// The nominal heading a steering controller holds (sidewinding's reversal and
    /// heading adjustment), rad in the pose estimate's world; `None`: the heading now.
    SetHeading { heading_rad: Option<f64> },
}

impl ControllerCommand {
    /// A `SetHeading`'s nominal heading wrapped into (−π, π], `Ok(None)` for "the
    /// heading now"; refused when not finite or not a `SetHeading`.
    pub fn nominal_heading(self) -> Result<Option<f64>, CommandRefused> {
        match self {
            ControllerCommand::SetHeading {
                heading_rad: Some(h),
            } if h.is_finite() => Ok(Some(crate::num::wrap_pi(h))),
            ControllerCommand::SetHeading {
                heading_rad: Some(_),
            } => Err(CommandRefused::BadHeading),
            ControllerCommand::SetHeading { heading_rad: None } => Ok(None),
            other => Err(CommandRefused::unsupported(other)),
        }
    }
}

/// Why a controller refused a command (built without allocating).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CommandRefused {
    #[error("this controller has nothing to calibrate")]
    NothingToCalibrate,
    #[error("this controller does not steer by a heading")]
    NoHeading,
    #[error("the heading must be a finite angle in radians")]
    BadHeading,
    #[error("the calibration time must be positive and finite, at most an hour")]
    BadDuration,
}

impl CommandRefused {
    /// Why a controller that does not take `command` refuses it.
    pub fn unsupported(command: ControllerCommand) -> Self {
        match command {
            ControllerCommand::Calibrate { .. } | ControllerCommand::ClearCalibration => {
                Self::NothingToCalibrate
            }
            ControllerCommand::SetHeading { .. } => Self::NoHeading,
        }
    }
}

/// Why a driving controller does not take a change in place (built without
/// allocating): the loop hands the joints back to the selector, which blends into the
/// change, and the controller takes over afresh when the blend ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct CannotFollow(pub &'static str);

impl CannotFollow {
    /// The default: the controller declares no following.
    pub const NOT_DECLARED: CannotFollow =
        CannotFollow("this controller does not follow changes while it drives");
    /// A reconfiguration by a controller of another kind.
    pub const OTHER_KIND: CannotFollow = CannotFollow("another controller");
}

/// Where a controller's calibration stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationState {
    None,
    Running,
    Calibrated,
}

/// What a controller offers the operator now, declared by the controller (published
/// each cycle with its report): what operators read instead of a signal's name.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Capabilities {
    /// It steers by a nominal heading now: [`ControllerCommand::SetHeading`] turns it
    /// (a teleop turn moves the heading, not the gait's steering knob).
    pub steers_by_heading: bool,
    /// It calibrates ([`ControllerCommand::Calibrate`]): where that stands.
    pub calibration: Option<CalibrationState>,
}

/// `new` as a controller of kind `T` (for [`Controller::reconfigure`]).
pub fn same_kind<T: Controller>(new: &mut dyn Controller) -> Result<&mut T, CannotFollow> {
    let any: &mut dyn std::any::Any = new;
    any.downcast_mut::<T>().ok_or(CannotFollow::OTHER_KIND)
}

/// A controller the loop can run. Every method but construction runs in the loop
/// thread: none may allocate, lock, block or read a clock. `Any`: a controller can
/// recognise another of its own kind ([`Controller::reconfigure`]).
pub trait Controller: Send + std::any::Any {
    /// Whether the controller can follow these nominal parameters of its gait.
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch>;
    /// Forgets everything learnt and starts from `handover` (called at every takeover;
    /// the parameters have passed [`Controller::accepts`]).
    fn engage(&mut self, handover: &Handover<'_>);
    /// Joint set-points at `tick.t_s` (non-decreasing between engagements) from `obs`;
    /// `tick.dt_s` is the time since the previous step (0 at the first after
    /// [`Controller::engage`]). Deterministic. Dorsal and lateral joints alike: write
    /// every entry.
    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]);
    /// The report after the last step, in the order of the controller's
    /// [`super::report::ReportSpec`].
    fn report(&self, out: &mut ControllerReport);
    /// Whether the controller takes over as soon as its gait is selected, from the pose
    /// the selector's blend starts at, and makes its own way into the gait (the rolling
    /// helix winds itself round a pole: a blend into the coil would coil on the ground).
    /// Such a controller must itself move smoothly from the handover's set-points.
    /// Most controllers take over when the selector's blend ends.
    fn takes_over_at_switch(&self) -> bool {
        false
    }
    /// While it drives, follow a change of the gait's nominal parameters from `t_s` on
    /// (they have passed [`Controller::accepts`]), keeping what it has learnt, as
    /// ros2_control's controllers take parameter updates: the shape moves to them
    /// smoothly (see [`super::nominal::Nominal::follow`]). `Err`: the change needs a
    /// fresh takeover (the loop hands back; nothing jumps either way).
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        let _ = (t_s, params);
        Err(CannotFollow::NOT_DECLARED)
    }
    /// Take `new`'s configuration in place (gains, thresholds, limits), keeping what
    /// this one has learnt and its engagement; `new` is a controller just built with the
    /// changed configuration and is retired after. Swap, don't clone: nothing may
    /// allocate. `Err`: the change needs `new` installed and engaged afresh (another
    /// kind, another structure).
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let _ = new;
        Err(CannotFollow::NOT_DECLARED)
    }
    /// What it offers the operator now (after its last step).
    fn capabilities(&self) -> Capabilities {
        Capabilities::default()
    }
    /// An operator's command; it takes effect at the controller's next step. Most
    /// controllers have none.
    fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        Err(CommandRefused::unsupported(command))
    }
}

/// Fills the body estimate before the controllers run (e.g. the virtual chassis).
pub trait Estimator: Send {
    fn update(&mut self, t_s: f64, obs: &Observation<'_>, out: &mut BodyEstimate);
}
