//! How far a gait could carry the body per cycle without its skin slipping, from the
//! commanded shape alone: a check on the physics independent of the contact solver.
//!
//! From one phase to the next the shape moves as a whole (the best-fitting rigid
//! motion of the link centres, Kabsch) plus what is left: the wave carrying the links
//! round loops, and in rolling each link turning about its own axis while the shape
//! stays put. That remainder is how the skin moves relative to the body. Quasi-
//! statically friction must balance, so the body cannot go faster than the fastest
//! backward motion of a skin point touching the ground: were it faster, every contact
//! would slide forward and friction would only brake it. On flat ground the links
//! that touch are the lowest ones (within [`CONTACT_BAND_M`]), on whichever side the
//! body lies. Per cycle that bounds the travel by `2π · max over phase and touching
//! links of (|v_centre,horizontal| + r·|ω_horizontal|)` per unit phase. Seen along the body's axis, each link's centre traces a loop per cycle
//! (the loop a sidewinding cross-section rolls round); its mean length is reported as
//! the estimate for a body rolling round it at a uniform speed.

use nalgebra::{Isometry3, Matrix3, SymmetricEigen, UnitQuaternion, Vector3};

use super::kinematics::chain_poses;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Serpenoid};

/// Links whose centres are within this of the lowest one can touch flat ground (the
/// contacts' give and the servos' errors are a few mm).
const CONTACT_BAND_M: f64 = 0.01;

/// The bound and the loop estimate, m per cycle.
#[derive(Debug, Clone, Copy)]
pub struct NoSlip {
    /// Upper bound on the travel per cycle.
    pub bound_m: f64,
    /// Mean length of the links' loops across the body's axis.
    pub loop_m: f64,
}

/// Centroid and principal axes (columns, largest first) of the link centres.
fn principal(poses: &[Isometry3<f64>]) -> (Vector3<f64>, Matrix3<f64>) {
    let c = poses
        .iter()
        .map(|p| p.translation.vector)
        .sum::<Vector3<f64>>()
        / poses.len() as f64;
    let mut cov = Matrix3::zeros();
    for p in poses {
        let d = p.translation.vector - c;
        cov += d * d.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axes = order.map(|i| Vector3::<f64>::from(eig.eigenvectors.column(i)));
    (c, Matrix3::from_columns(&axes))
}

/// The rotation that best maps the centred points `a` onto `b` (Kabsch).
fn kabsch(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Matrix3<f64> {
    let h: Matrix3<f64> = a.iter().zip(b).map(|(p, q)| q * p.transpose()).sum();
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let d = (u * vt).determinant().signum();
    u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt
}

fn poses_at(gait: &Serpenoid, layout: &BodyLayout, psi: f64) -> Vec<Isometry3<f64>> {
    let mut angles = vec![0.0; layout.len()];
    gait.evaluate(layout, psi, &mut angles);
    chain_poses(
        Isometry3::identity(),
        layout.planes[0],
        &angles,
        layout.module_length_m,
    )
}

/// [`NoSlip`] of `kind` with `params` on `layout`, links of radius `radius_m`.
pub fn no_slip(kind: GaitKind, params: &GaitParams, layout: &BodyLayout, radius_m: f64) -> NoSlip {
    let gait = Serpenoid::for_layout(kind, params, layout);
    let steps = 2000;
    let dpsi = std::f64::consts::TAU / steps as f64;
    let mut prev = poses_at(&gait, layout, 0.0);
    let mut loops = vec![0.0; prev.len()];
    // Per side the body may lie on (the minor axis up or down): the fastest skin point
    // among the links low enough to touch the ground.
    let mut fastest = [0.0f64; 2];
    for k in 1..=steps {
        let now = poses_at(&gait, layout, k as f64 * dpsi);
        let (ca, _) = principal(&prev);
        let (cb, axes) = principal(&now);
        let a: Vec<_> = prev.iter().map(|p| p.translation.vector - ca).collect();
        let b: Vec<_> = now.iter().map(|p| p.translation.vector - cb).collect();
        let r = kabsch(&a, &b);
        let rq = UnitQuaternion::from_matrix(&r);
        let (along, up) = (axes.column(0).into_owned(), axes.column(2).into_owned());
        for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
            let height = |i: usize| sign * b[i].dot(&up);
            let lowest = (0..b.len()).map(height).fold(f64::INFINITY, f64::min);
            for i in (0..b.len()).filter(|&i| height(i) < lowest + CONTACT_BAND_M) {
                // What the link does besides moving with the shape as a whole.
                let d = b[i] - r * a[i];
                let w = (now[i].rotation * (rq * prev[i].rotation).inverse()).scaled_axis();
                // The skin under the centre moves by ω × (−r·up): only the turn about
                // a horizontal axis moves it (a yaw turns it on the spot).
                let tilt = (w - up * w.dot(&up)).norm();
                let horizontal = d - up * d.dot(&up);
                fastest[side] = fastest[side].max((horizontal.norm() + radius_m * tilt) / dpsi);
            }
        }
        for i in 0..now.len() {
            let d = b[i] - r * a[i];
            loops[i] += (d - along * d.dot(&along)).norm();
        }
        prev = now;
    }
    NoSlip {
        bound_m: std::f64::consts::TAU * fastest[0].max(fastest[1]),
        loop_m: loops.iter().sum::<f64>() / loops.len() as f64,
    }
}
