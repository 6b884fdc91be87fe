//! Forward kinematics of the chain (f64, nalgebra) and conversions to rapier's f32
//! glam types.
//!
//! Link frames: x toward the head (the nose), y left, z up when the body lies straight
//! and flat. Link 0 is the head; joint `i` joins link `i` (parent) to link `i + 1`
//! (child, the output side of module `i`, where its IMU sits). A lateral joint turns
//! about the links' z axis (positive: the tail side swings right, as in the
//! joint-space plant), a dorsal joint about their −y axis (positive: the tail side
//! pitches down; the joint-space plant uses +y). Only the relative sign of the two
//! planes has a physical consequence: it decides which sections of a sidewinding body
//! touch the ground, and with this choice the thesis' `δ = 3π/4` sidewinds (with +y
//! it travels obliquely; see docs/emulator.md).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rapier3d::math::{Pose, Rotation, Vector};

use crate::gait::{BodyLayout, Plane, kinematics};

/// Joint axis of `plane` in both links' frames ([`crate::gait::kinematics`]).
pub fn axis_of(plane: Plane) -> Vector3<f64> {
    kinematics::axis_of(plane).into_inner()
}

/// Pose of the head link whose head end is at `head_m` and whose body points from
/// head to tail along `yaw_rad` (from +x), lying flat with its axis at `head_m.z`.
pub fn head_pose(head_m: [f64; 3], yaw_rad: f64, link_length_m: f64) -> Isometry3<f64> {
    // Link x points to the nose: opposite to the head-to-tail direction.
    let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw_rad + std::f64::consts::PI);
    let tail_dir = Vector3::new(yaw_rad.cos(), yaw_rad.sin(), 0.0);
    let centre = Vector3::from(head_m) + tail_dir * (0.5 * link_length_m);
    Isometry3::from_parts(Translation3::from(centre), rot)
}

/// Poses of all `angles.len() + 1` links from the head's pose and the joint angles
/// (joint `i` in plane `plane_of(first, i)`).
pub fn chain_poses(
    head: Isometry3<f64>,
    first: Plane,
    angles_rad: &[f64],
    link_length_m: f64,
) -> Vec<Isometry3<f64>> {
    let layout = BodyLayout::alternating(angles_rad.len(), first, link_length_m);
    let mut poses = vec![Isometry3::identity(); angles_rad.len() + 1];
    kinematics::link_poses(head, &layout, angles_rad, &mut poses);
    poses
}

/// nalgebra → rapier (f32 glam) pose.
pub fn to_rapier(p: &Isometry3<f64>) -> Pose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    Pose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
    )
}

/// rapier → nalgebra (f64) pose.
pub fn from_rapier(p: &Pose) -> Isometry3<f64> {
    let t = p.translation;
    let q = p.rotation;
    Isometry3::from_parts(
        Translation3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z)),
        UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
            f64::from(q.w),
            f64::from(q.x),
            f64::from(q.y),
            f64::from(q.z),
        )),
    )
}

/// Angle of `child` relative to `parent` about `axis` (in the parent's frame), rad,
/// in (−π, π]: the twist part of the relative rotation.
pub fn twist_angle(parent: &Rotation, child: &Rotation, axis: Vector) -> f64 {
    let rel = parent.inverse() * *child;
    let s = f64::from(rel.x * axis.x + rel.y * axis.y + rel.z * axis.z);
    let w = f64::from(rel.w);
    let a = 2.0 * s.atan2(w);
    if a > std::f64::consts::PI {
        a - std::f64::consts::TAU
    } else if a <= -std::f64::consts::PI {
        a + std::f64::consts::TAU
    } else {
        a
    }
}
