//! The body's shape from its joint angles: every link's pose in the head link's frame.
//! One convention for the daemon's estimator and the emulator's physics.
//!
//! Link frames: x toward the head, y left, z up when the body lies straight and flat;
//! link 0 is the head, joint `i` joins link `i` to link `i + 1` (module `i`'s output
//! side, where its IMU sits). A lateral joint turns about z (positive: the tail side
//! swings right), a dorsal joint about −y (positive: the tail side pitches down).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::gait::{BodyLayout, Plane};

/// Joint axis of `plane` in both links' frames.
pub fn axis_of(plane: Plane) -> nalgebra::Unit<Vector3<f64>> {
    match plane {
        Plane::Lateral => Vector3::z_axis(),
        Plane::Dorsal => -Vector3::y_axis(),
    }
}

/// Writes the poses of the `angles.len() + 1` links into `out` (which must hold that
/// many), from the head link's pose `head` (identity: in the head's frame). No
/// allocation.
pub fn link_poses(
    head: Isometry3<f64>,
    layout: &BodyLayout,
    angles_rad: &[f64],
    out: &mut [Isometry3<f64>],
) {
    let half = Translation3::new(-0.5 * layout.module_length_m, 0.0, 0.0);
    let mut pose = head;
    out[0] = pose;
    for (i, (&a, &plane)) in angles_rad.iter().zip(&layout.planes).enumerate() {
        let turn = UnitQuaternion::from_axis_angle(&axis_of(plane), a);
        pose = pose * half * Isometry3::from_parts(Translation3::identity(), turn) * half;
        out[i + 1] = pose;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::module::MODULE_LENGTH_M;

    #[test]
    fn a_straight_body_lies_along_minus_x_and_a_bend_turns_the_tail() {
        let layout = BodyLayout::alternating(2, Plane::Lateral, MODULE_LENGTH_M);
        let mut poses = [Isometry3::identity(); 3];
        link_poses(Isometry3::identity(), &layout, &[0.0, 0.0], &mut poses);
        let l = MODULE_LENGTH_M;
        assert!((poses[2].translation.vector - Vector3::new(-2.0 * l, 0.0, 0.0)).norm() < 1e-12);
        // Lateral +90°: the tail side swings to −y (right); dorsal +90°: it pitches down.
        link_poses(
            Isometry3::identity(),
            &layout,
            &[std::f64::consts::FRAC_PI_2, 0.0],
            &mut poses,
        );
        let t = poses[2].translation.vector;
        assert!(
            (t - Vector3::new(-0.5 * l, -1.5 * l, 0.0)).norm() < 1e-12,
            "{t}"
        );
        link_poses(
            Isometry3::identity(),
            &layout,
            &[0.0, std::f64::consts::FRAC_PI_2],
            &mut poses,
        );
        let t = poses[2].translation.vector;
        assert!(
            (t - Vector3::new(-1.5 * l, 0.0, -0.5 * l)).norm() < 1e-12,
            "{t}"
        );
    }
}
