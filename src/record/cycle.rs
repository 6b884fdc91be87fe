//! What the loop hands the recorder: `Copy` items pushed into a bounded lock-free ring
//! (never blocking, never allocating; a full ring drops the item and counts it).

use crate::controller_interface::BodyEstimate;
use crate::controller_interface::report::ControllerReport;
use crate::emu::LinkPose;
use crate::gait::GaitKind;
use crate::navigation::progress::ProgressReport;
use crate::navigation::state::NavigatorState;
use crate::rt::messages::LoopRequest;
use crate::rt::stats::LoopStats;
use crate::safety::failsafe::{Mode, Reason};

/// Modules a record holds; a bigger body is recorded up to this many (the file's
/// metadata says how many the body has).
pub const RECORD_MAX_MODULES: usize = 64;
/// Ground-truth links a record holds (a body of N modules has N + 1 links).
pub const RECORD_MAX_LINKS: usize = RECORD_MAX_MODULES + 1;

/// One joint in one cycle: its feedback and what was commanded.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointSample {
    pub position_rad: f32,
    pub velocity_rad_s: f32,
    pub torque_nm: f32,
    /// Set-point sent this cycle (NaN: not commanded, e.g. limp).
    pub cmd_position_rad: f32,
    pub cmd_velocity_rad_s: f32,
    pub accel_m_s2: [f32; 3],
    pub gyro_rad_s: [f32; 3],
}

/// Everything one cycle recorded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleRecord {
    pub cycle: u64,
    /// Loop time, ns since the loop started (simulated time in lockstep).
    pub t_ns: u64,
    pub mode: Mode,
    pub reason: Reason,
    /// The gait run or blended into.
    pub gait: GaitKind,
    /// The active gait's controller ([`crate::controller_interface::catalog`] id; 0: none).
    pub controller_id: u64,
    /// Whether that controller drove the joints this cycle (else the selector did).
    pub engaged: bool,
    /// Modules in the body; `joints[..modules.min(RECORD_MAX_MODULES)]` are valid.
    pub modules: usize,
    pub joints: [JointSample; RECORD_MAX_MODULES],
    /// The controller's report (meaningful while `engaged`).
    pub report: ControllerReport,
    /// The estimators' body estimate this cycle (the robot's own, not ground truth).
    pub body: BodyEstimate,
    /// Whether the running gait makes way (the stuck detector).
    pub progress: ProgressReport,
    /// What the navigator does.
    pub navigator: NavigatorState,
    /// Ground-truth link poses (simulated runs only; 0 links otherwise), head first.
    pub links: usize,
    pub link_poses: [LinkPose; RECORD_MAX_LINKS],
}

impl CycleRecord {
    pub const EMPTY: CycleRecord = CycleRecord {
        cycle: 0,
        t_ns: 0,
        mode: Mode::Limp,
        reason: Reason::Startup,
        gait: GaitKind::Slithering,
        controller_id: 0,
        engaged: false,
        modules: 0,
        joints: [JointSample {
            position_rad: 0.0,
            velocity_rad_s: 0.0,
            torque_nm: 0.0,
            cmd_position_rad: f32::NAN,
            cmd_velocity_rad_s: f32::NAN,
            accel_m_s2: [0.0; 3],
            gyro_rad_s: [0.0; 3],
        }; RECORD_MAX_MODULES],
        report: ControllerReport::EMPTY,
        body: BodyEstimate::NONE,
        progress: ProgressReport::NONE,
        navigator: NavigatorState::OFF,
        links: 0,
        link_poses: [LinkPose {
            position_m: [0.0; 3],
            quat_wxyz: [1.0, 0.0, 0.0, 0.0],
        }; RECORD_MAX_LINKS],
    };

    /// The valid joints.
    pub fn joints(&self) -> &[JointSample] {
        &self.joints[..self.modules.min(RECORD_MAX_MODULES)]
    }

    /// The valid link poses.
    pub fn link_poses(&self) -> &[LinkPose] {
        &self.link_poses[..self.links.min(RECORD_MAX_LINKS)]
    }
}

/// Something that happened, recorded as an event.
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(clippy::large_enum_variant)] // Copied into the ring inside a RecordItem anyway.
pub enum RecordEvent {
    /// The failsafe's mode changed.
    Mode { mode: Mode, reason: Reason },
    /// An operator request the loop applied (`Ok`) or refused.
    Request {
        ticket: u64,
        request: LoopRequest,
        result: crate::rt::messages::LoopResult,
    },
    /// A controller took over the joints from the selector.
    Engaged { gait: GaitKind, controller_id: u64 },
    /// A controller handed the joints back to the selector.
    Released { gait: GaitKind, controller_id: u64 },
    /// A set-point failed the guard (non-finite): the failsafe holds.
    SetpointFault { joint: usize, controller_id: u64 },
}

/// One item of the ring.
#[derive(Clone, Copy)]
#[allow(clippy::large_enum_variant)] // Copied into a preallocated ring, never boxed.
pub enum RecordItem {
    Cycle(CycleRecord),
    Event {
        t_ns: u64,
        event: RecordEvent,
    },
    /// The loop's statistics (pushed once a second).
    Stats {
        t_ns: u64,
        stats: LoopStats,
    },
}

impl RecordItem {
    /// The loop time the item was pushed at, ns.
    pub fn t_ns(&self) -> u64 {
        match self {
            RecordItem::Cycle(rec) => rec.t_ns,
            RecordItem::Event { t_ns, .. } | RecordItem::Stats { t_ns, .. } => *t_ns,
        }
    }
}
