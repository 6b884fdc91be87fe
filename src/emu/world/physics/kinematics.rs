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

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
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

/// Axis direction, centre (on the axis) and radius of the helix through the links'
/// centres: the axis is the mean binormal, the circle a least-squares fit of the
/// centres projected on the plane across it.
fn fit_helix(pts: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>, f64) {
    let mut d = Vector3::zeros();
    for w in pts.windows(3) {
        d += (w[1] - w[0]).cross(&(w[2] - w[1])).normalize();
    }
    let d = d.normalize();
    let e1 = d
        .cross(&Vector3::x())
        .try_normalize(1e-6)
        .unwrap_or_else(|| d.cross(&Vector3::y()).normalize());
    let e2 = d.cross(&e1);
    // u² + v² = a·u + b·v + c.
    let mut m = Matrix3::zeros();
    let mut r = Vector3::zeros();
    for p in pts {
        let (u, v) = (p.dot(&e1), p.dot(&e2));
        let row = Vector3::new(u, v, 1.0);
        m += row * row.transpose();
        r += row * (u * u + v * v);
    }
    let s = m.lu().solve(&r).unwrap();
    let (cu, cv) = (0.5 * s.x, 0.5 * s.y);
    let radius = (s.z + cu * cu + cv * cv).sqrt();
    let mean_d = pts.iter().map(|p| p.dot(&d)).sum::<f64>() / pts.len() as f64;
    (d, e1 * cu + e2 * cv + d * mean_d, radius)
}

/// A helical body stood upright: the head pose that puts the helix of `angles_rad`
/// (joint 0 in `first`) with its axis on the world's z axis and its middle at height
/// `z_m`, and the radius of the helix through the links' centres, m.
pub fn upright_helix(
    first: Plane,
    angles_rad: &[f64],
    link_length_m: f64,
    z_m: f64,
) -> (Isometry3<f64>, f64) {
    let poses = chain_poses(Isometry3::identity(), first, angles_rad, link_length_m);
    let pts: Vec<Vector3<f64>> = poses.iter().map(|p| p.translation.vector).collect();
    let (axis, centre, r) = fit_helix(&pts);
    let rot = UnitQuaternion::rotation_between(&axis, &Vector3::z())
        .unwrap_or_else(UnitQuaternion::identity);
    (
        Translation3::new(0.0, 0.0, z_m) * rot * Translation3::from(-centre),
        r,
    )
}
