//! The body's shape from its joint angles, for the 3-D view: forward kinematics over a
//! [`BodyLayout`] in the `body` frame (the head link's frame), with the physics plant's
//! conventions (`emu::world::physics::kinematics`): link x toward the nose, a lateral
//! joint turns about z (yaw), a dorsal one about −y (pitch), link centres one module
//! length apart. Keeping the plant's conventions makes the drawn body match the
//! ground-truth links in simulation.

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion};

use crate::emu::world::physics::kinematics::axis_of;
use crate::gait::BodyLayout;

/// Poses in the body frame of the head link and one link per joint (`angles.len() + 1`
/// links; joints beyond the layout are ignored), written into `out`.
pub fn link_poses_in_body(
    layout: &BodyLayout,
    angles_rad: impl IntoIterator<Item = f64>,
    out: &mut Vec<Isometry3<f64>>,
) {
    out.clear();
    let half = Translation3::new(-0.5 * layout.module_length_m, 0.0, 0.0);
    let mut pose = Isometry3::identity();
    out.push(pose);
    for (plane, a) in layout.planes.iter().zip(angles_rad) {
        // A non-finite angle (a module that never reported) draws straight.
        let a = if a.is_finite() { a } else { 0.0 };
        let rot = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis_of(*plane)), a);
        pose = pose * half * Isometry3::from_parts(Translation3::identity(), rot) * half;
        out.push(pose);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::physics::kinematics::chain_poses;
    use crate::gait::Plane;

    #[test]
    fn a_straight_body_lies_along_minus_x() {
        let layout = BodyLayout::alternating(4, Plane::Lateral, 0.1);
        let mut out = Vec::new();
        link_poses_in_body(&layout, [0.0; 4], &mut out);
        assert_eq!(out.len(), 5);
        for (k, p) in out.iter().enumerate() {
            let t = p.translation.vector;
            assert!((t.x + 0.1 * k as f64).abs() < 1e-12, "link {k} at {t:?}");
            assert!(t.y.abs() < 1e-12 && t.z.abs() < 1e-12);
        }
    }

    #[test]
    fn a_lateral_joint_yaws_and_a_dorsal_one_pitches() {
        let layout = BodyLayout::alternating(2, Plane::Lateral, 0.1);
        let mut out = Vec::new();
        let q = std::f64::consts::FRAC_PI_2;
        link_poses_in_body(&layout, [q, 0.0], &mut out);
        // Joint 0 at x = -0.05; link 1's centre swings off the x axis in the plane z = 0.
        let t1 = out[1].translation.vector;
        assert!((t1.x + 0.05).abs() < 1e-12 && (t1.y.abs() - 0.05).abs() < 1e-12);
        assert!(t1.z.abs() < 1e-12);
        link_poses_in_body(&layout, [0.0, q], &mut out);
        let t2 = out[2].translation.vector;
        assert!(
            t2.y.abs() < 1e-12 && (t2.z.abs() - 0.05).abs() < 1e-12,
            "{t2:?}"
        );
    }

    #[test]
    fn matches_the_physics_plants_chain() {
        let layout = BodyLayout::alternating(6, Plane::Dorsal, 0.064);
        let angles = [0.3, -0.2, 0.5, 0.1, -0.4, 0.25];
        let mut out = Vec::new();
        link_poses_in_body(&layout, angles, &mut out);
        let plant = chain_poses(Isometry3::identity(), Plane::Dorsal, &angles, 0.064);
        assert_eq!(out.len(), plant.len());
        for (a, b) in out.iter().zip(&plant) {
            assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
            assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
        }
    }

    #[test]
    fn non_finite_angles_draw_straight_and_extra_joints_are_ignored() {
        let layout = BodyLayout::alternating(2, Plane::Lateral, 0.1);
        let mut out = Vec::new();
        link_poses_in_body(&layout, [f64::NAN, 0.0, 1.0, 1.0], &mut out);
        assert_eq!(out.len(), 3);
        assert!((out[2].translation.vector.x + 0.2).abs() < 1e-12);
    }
}
