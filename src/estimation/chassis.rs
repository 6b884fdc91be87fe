//! The virtual chassis (Rollinson and Choset): a body frame at the links' centroid,
//! aligned with their principal axes, x along the body towards the head, z up.
//!
//! Only x comes from the shape (the principal axis of largest spread); z is world up
//! made perpendicular to it, so the frame is defined whatever the other two spreads
//! are (a straight body has no second axis; a body lying flat has its least spread
//! vertical anyway). Signs and degenerate shapes:
//! - x points from the tail half's centroid to the head half's, which does not swing
//!   as the wave travels; where that is unclear (a U, the halves side by side) x keeps
//!   the sign of the last frame's (at the first, the head's side of the centroid);
//! - a shape with no clear main axis (coiled, or a circle: the two largest spreads
//!   within [`ROUND_RATIO`]) keeps the last frame's x and
//!   is reported `round`; with no last frame the head's direction is taken;
//! - an x (nearly) vertical keeps the last frame's z instead of world up.

use nalgebra::{Matrix3, Rotation3, SymmetricEigen, Unit, Vector3};

/// Largest second spread, as a fraction of the first, at which the main axis is
/// still taken from the shape.
pub const ROUND_RATIO: f64 = 0.8;

/// The head half's centroid must lie this far ahead of the tail half's along the main
/// axis, in units of the spread along it (√λ₁; a straight body: 1.73), for the axis's
/// sign to come from the shape rather than the last frame.
pub const SIGN_FROM_SHAPE: f64 = 0.5;

/// A body frame in the world (z up) and how it was found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chassis {
    pub origin: Vector3<f64>,
    /// Columns x (body axis, to the head), y (left), z (up).
    pub rotation: Rotation3<f64>,
    /// The shape had no clear main axis; x is the last frame's.
    pub round: bool,
}

impl Chassis {
    /// Heading of x in the ground plane, rad from world x.
    pub fn heading_rad(&self) -> f64 {
        let x = self.rotation * Vector3::x();
        x.y.atan2(x.x)
    }
}

/// The chassis of `points` (link centres, world-aligned, head first), continuing
/// `previous`. No allocation.
pub fn chassis(points: &[Vector3<f64>], previous: Option<&Chassis>) -> Chassis {
    let n = points.len() as f64;
    let origin = points.iter().sum::<Vector3<f64>>() / n;
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = p - origin;
        cov += d * d.transpose();
    }
    let eig = SymmetricEigen::new(cov / n);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let (first, l1, l2) = (
        order[0],
        eig.eigenvalues[order[0]],
        eig.eigenvalues[order[1]],
    );
    let round = !(l1 > 0.0 && l2 < ROUND_RATIO * l1);
    let previous_x = previous.map(|c| c.rotation * Vector3::x());
    let head_side = points[0] - origin;
    let mut x: Vector3<f64> = match (round, previous_x) {
        (true, Some(px)) => px,
        (true, None) => head_side,
        (false, _) => eig.eigenvectors.column(first).into_owned(),
    };
    if x.norm() < 1e-12 {
        x = Vector3::x();
    }
    x.normalize_mut();
    // The sign: towards the head half's centroid from the tail half's where the shape
    // says so clearly; otherwise the last frame's (or the head's side at the first).
    // Only the last frame's would carry a flip for good once a main axis swapped.
    let half = points.len() / 2;
    let along = if half > 0 {
        let head: Vector3<f64> = points[..half].iter().sum();
        let tail: Vector3<f64> = points[points.len() - half..].iter().sum();
        (head - tail) / half as f64
    } else {
        Vector3::zeros()
    };
    let clear = !round && x.dot(&along).abs() > SIGN_FROM_SHAPE * l1.max(0.0).sqrt();
    let reference = if clear {
        along
    } else {
        previous_x.unwrap_or(head_side)
    };
    if x.dot(&reference) < 0.0 {
        x = -x;
    }
    let up = Vector3::z();
    let mut z = up - x * x.dot(&up);
    if z.norm() < 0.1 {
        // x nearly vertical: keep the last frame's z (or any horizontal direction).
        z = previous.map_or(Vector3::y(), |c| c.rotation * Vector3::z());
        z -= x * x.dot(&z);
    }
    let z = Unit::new_normalize(z).into_inner();
    let y = z.cross(&x);
    Chassis {
        origin,
        rotation: Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z])),
        round,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, dir: Vector3<f64>) -> Vec<Vector3<f64>> {
        (0..n).map(|k| dir * -(k as f64) * 0.064).collect()
    }

    #[test]
    fn a_straight_body_points_to_its_head_with_z_up() {
        let dir = Vector3::new(1.0, 1.0, 0.0).normalize();
        let c = chassis(&line(10, dir), None);
        assert!(!c.round);
        assert!((c.rotation * Vector3::x() - dir).norm() < 1e-9);
        assert!((c.rotation * Vector3::z() - Vector3::z()).norm() < 1e-9);
        assert!((c.heading_rad() - std::f64::consts::FRAC_PI_4).abs() < 1e-9);
        // A body sloping up keeps z as near up as its axis allows.
        let slope = Vector3::new(1.0, 0.0, 0.5).normalize();
        let c = chassis(&line(10, slope), None);
        let z = c.rotation * Vector3::z();
        assert!(z.dot(&slope).abs() < 1e-9 && z.z > 0.8, "{z}");
    }

    #[test]
    fn the_axis_keeps_its_sign_from_frame_to_frame() {
        // A wave whose head swings across the centroid: the sign must not follow it.
        let mut last: Option<Chassis> = None;
        for k in 0..200 {
            let phase = k as f64 * 0.05;
            let pts: Vec<_> = (0..19)
                .map(|i| {
                    let s = i as f64 * 0.064;
                    Vector3::new(-s, 0.1 * (9.4 * s - phase).sin(), 0.0)
                })
                .collect();
            let c = chassis(&pts, last.as_ref());
            assert!((c.rotation * Vector3::x()).x > 0.9, "flipped at {k}");
            last = Some(c);
        }
    }

    /// A last frame pointing the wrong way (as after a swap of the main axes) does not
    /// carry over to a shape whose head half is clearly ahead; a U (halves side by
    /// side) keeps the last frame's sign.
    #[test]
    fn the_shape_sets_the_sign_where_it_is_clear() {
        let body = line(19, Vector3::x());
        let wrong = chassis(&line(19, -Vector3::x()), None);
        let c = chassis(&body, Some(&wrong));
        assert!((c.rotation * Vector3::x() - Vector3::x()).norm() < 1e-9);
        // A U: arms along y, 0.15 m apart, the head at the end of one arm.
        let u: Vec<_> = (0..19)
            .map(|i| {
                let k = i as f64;
                if i < 8 {
                    Vector3::new(0.0, 0.5 - 0.064 * k, 0.0)
                } else if i < 11 {
                    Vector3::new(0.05 * (k - 7.0), 0.0, 0.0)
                } else {
                    Vector3::new(0.15, 0.064 * (k - 11.0), 0.0)
                }
            })
            .collect();
        for last in [Vector3::y(), -Vector3::y()] {
            let previous = chassis(&line(19, last), None);
            let c = chassis(&u, Some(&previous));
            assert!((c.rotation * Vector3::x()).dot(&last) > 0.9, "{last}");
        }
    }

    #[test]
    fn a_coil_keeps_the_last_axis_and_says_so() {
        let ring: Vec<_> = (0..19)
            .map(|i| {
                let a = i as f64 / 19.0 * std::f64::consts::TAU;
                Vector3::new(0.2 * a.cos(), 0.2 * a.sin(), 0.0)
            })
            .collect();
        let c = chassis(&ring, None);
        assert!(c.round);
        // Without a last frame, towards the head.
        assert!((c.rotation * Vector3::x() - Vector3::x()).norm() < 1e-9);
        let last = chassis(&line(10, Vector3::y()), None);
        let c = chassis(&ring, Some(&last));
        assert!(c.round);
        assert!((c.rotation * Vector3::x() - Vector3::y()).norm() < 1e-9);
        assert!((c.rotation * Vector3::z() - Vector3::z()).norm() < 1e-9);
    }

    #[test]
    fn a_standing_body_keeps_a_horizontal_z() {
        let c = chassis(&line(10, Vector3::z()), None);
        let z = c.rotation * Vector3::z();
        assert!(
            z.dot(&Vector3::z()).abs() < 1e-9 && (z.norm() - 1.0).abs() < 1e-9,
            "{z}"
        );
        let r = c.rotation.matrix();
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-9);
    }
}
