//! The robot's pose from its own sensors (issue 11): the head's attitude from every
//! module's IMU fused through the kinematics ([`attitude`]), the body's shape from the
//! joint angles ([`crate::gait::kinematics`]), and the virtual chassis from both ([`chassis`]). As an
//! [`Estimator`] it fills [`BodyEstimate`] before the controllers run; allocation-free
//! after construction. Every loop runs it ([`standard_estimators`]: the daemon, the
//! test harness, the lab). One update costs 1.8 µs optimised (`cargo bench --bench
//! estimator`); the dev profile builds this crate at opt-level 1 because at 0
//! nalgebra's generic code made it 0.36 ms, a third of the cycle.
//!
//! The estimate's world frame: z up (gravity), yaw zero where the estimator started,
//! origin at the head link's centre (`position_m` is the chassis' origin relative to
//! the head, in world axes). Where the body has gone comes from contact odometry
//! ([`odometry`]): `odometry_m`, meaningful while part of the body is lifted.

pub mod attitude;
pub mod chassis;
pub mod external_pose;
pub mod odometry;
pub mod world_position;

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

use crate::controller_interface::{BodyEstimate, Estimator, Observation};
use crate::gait::BodyLayout;
use attitude::FusedAttitude;
use chassis::{Chassis, chassis};
use odometry::ContactOdometry;

/// The attitude filter's default time constant, s: the gyros are trusted for about a
/// second, longer than a gait's accelerations last, shorter than their bias drifts.
pub const DEFAULT_TIME_CONSTANT_S: f64 = 1.0;

/// The estimators every control loop runs, in order, for a body of `layout` (the loop
/// knows none of them by name).
pub fn standard_estimators(layout: &BodyLayout) -> Vec<Box<dyn Estimator>> {
    vec![Box::new(VirtualChassisEstimator::new(
        layout.clone(),
        DEFAULT_TIME_CONSTANT_S,
    ))]
}

/// The virtual-chassis estimator of a body with `layout`.
pub struct VirtualChassisEstimator {
    layout: BodyLayout,
    attitude: FusedAttitude,
    poses: Vec<Isometry3<f64>>,
    rel_before: Vec<UnitQuaternion<f64>>,
    rel_now: Vec<UnitQuaternion<f64>>,
    points: Vec<Vector3<f64>>,
    last: Option<Chassis>,
    odometry: ContactOdometry,
    last_t_s: Option<f64>,
}

impl VirtualChassisEstimator {
    pub fn new(layout: BodyLayout, time_constant_s: f64) -> Self {
        let n = layout.len();
        Self {
            attitude: FusedAttitude::new(time_constant_s),
            poses: vec![Isometry3::identity(); n + 1],
            rel_before: vec![UnitQuaternion::identity(); n],
            rel_now: vec![UnitQuaternion::identity(); n],
            points: vec![Vector3::zeros(); n + 1],
            last: None,
            odometry: ContactOdometry::new(n + 1),
            last_t_s: None,
            layout,
        }
    }

    /// The head's attitude (head frame → world).
    pub fn head_attitude(&self) -> UnitQuaternion<f64> {
        self.attitude.head
    }
}

fn finite(obs: &Observation<'_>, n: usize) -> bool {
    obs.position_rad.len() >= n
        && obs.imu.len() >= n
        && obs.position_rad[..n].iter().all(|x| x.is_finite())
        && obs.imu[..n].iter().all(|m| {
            m.accel_m_s2
                .iter()
                .chain(&m.gyro_rad_s)
                .all(|x| x.is_finite())
        })
}

impl Estimator for VirtualChassisEstimator {
    fn update(&mut self, t_s: f64, obs: &Observation<'_>, out: &mut BodyEstimate) {
        let n = self.layout.len();
        if !finite(obs, n) {
            // A lost or garbled module: hold the state, say the estimate is not valid.
            self.odometry.pause();
            out.valid = false;
            return;
        }
        crate::gait::kinematics::link_poses(
            Isometry3::identity(),
            &self.layout,
            &obs.position_rad[..n],
            &mut self.poses,
        );
        for (r, p) in self.rel_now.iter_mut().zip(&self.poses[1..]) {
            *r = p.rotation;
        }
        let dt = self.last_t_s.map_or(0.0, |t0| (t_s - t0).max(0.0));
        self.attitude
            .update(dt, &self.rel_before, &self.rel_now, &obs.imu[..n]);
        self.rel_before.copy_from_slice(&self.rel_now);
        self.last_t_s = Some(t_s);
        if !self.attitude.initialised() {
            out.valid = false;
            return;
        }
        let head = self.attitude.head;
        for (q, p) in self.points.iter_mut().zip(&self.poses) {
            *q = head * p.translation.vector;
        }
        let c = chassis(&self.points, self.last.as_ref());
        self.last = Some(c);
        self.odometry.update(&self.points);
        let travelled = self.odometry.head_m() + c.origin;
        let q = UnitQuaternion::from_rotation_matrix(&c.rotation);
        *out = BodyEstimate {
            valid: true,
            position_m: c.origin.into(),
            orientation_wxyz: [q.w, q.i, q.j, q.k],
            heading_rad: c.heading_rad(),
            round: c.round,
            odometry_m: [travelled.x, travelled.y],
            odometry_lifted: self.odometry.lifted(),
            head_wxyz: [head.w, head.i, head.j, head.k],
            // The external fix's estimator, which runs after this one, keeps it.
            fix: out.fix,
            world: out.world,
        };
    }
}

#[cfg(test)]
mod validation_tests;
