//! The module emulator: a plant (the snake's body and actuators) behind either the
//! UDP module endpoints (`snake-emu`) or the in-process `SimBus`.
//!
//! The plant is a trait so the rigid-body physics of a later stage can replace the
//! joint-space model without touching the network side.

pub mod faults;
pub mod model_file;
pub mod module;
pub mod plant;
pub mod pose_csv;
pub mod server;
pub mod servo;
pub mod sim_bus;
pub mod truth_csv;
pub mod world;

use crate::module::{Command, Feedback};

/// A simulated snake: N series-elastic modules and the world they touch.
pub trait Plant: Send {
    fn module_count(&self) -> usize;
    /// Advance the simulation by `dt_s`. `commands[i]` is what module `i` is
    /// driving right now (already `Command::LIMP` when its lifetime expired or its
    /// strategy is off).
    fn step(&mut self, dt_s: f64, commands: &[Command]);
    /// Simulated time since start, s.
    fn time_s(&self) -> f64;
    /// Feedback of module `i` as its sensors would report it now.
    fn feedback(&self, i: usize) -> Feedback;
    /// Exact (noise-free) state of joint `i`, for ground-truth recordings. The
    /// default reports the sensors' values.
    fn ground_truth(&self, i: usize) -> GroundTruth {
        let f = self.feedback(i);
        GroundTruth {
            position_rad: f64::from(f.position_rad),
            torque_nm: f64::from(f.torque_nm),
        }
    }
    /// Rigid bodies the plant can report poses of (0: it has none).
    fn link_count(&self) -> usize {
        0
    }
    /// Exact pose of body `k` (`k < link_count()`), for ground-truth recordings.
    fn link_pose(&self, _k: usize) -> LinkPose {
        LinkPose::default()
    }
    /// Contacts with the world after the last step (none for a plant without them).
    fn contacts(&self) -> ContactSummary {
        ContactSummary::default()
    }
    /// Contact onsets between non-adjacent links of the body since the start (a pair
    /// that starts touching counts once until it separates); 0 for a plant without
    /// self-collision.
    fn self_contacts(&self) -> u64 {
        0
    }
    /// Pairs of non-adjacent links touching after the last step.
    fn self_contact_pairs_now(&self) -> usize {
        0
    }
}

/// One body's exact pose: position, m, and orientation quaternion (w, x, y, z).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkPose {
    pub position_m: [f64; 3],
    pub quat_wxyz: [f64; 4],
}

/// Contacts between the snake and the world after a step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactSummary {
    /// Collider pairs (link–obstacle) in contact; link–link pairs are
    /// [`Plant::self_contact_pairs_now`].
    pub pairs: usize,
    /// Sum of their normal forces, N.
    pub normal_force_n: f64,
}

/// Exact joint state of a plant, as recorded out of band.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GroundTruth {
    pub position_rad: f64,
    /// Spring torque, N·m (same sign convention as [`Feedback::torque_nm`]).
    pub torque_nm: f64,
}
