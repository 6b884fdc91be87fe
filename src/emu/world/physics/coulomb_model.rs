//! An independent check on the rigid-body physics: the quasi-static model of a planar
//! chain on isotropic Coulomb friction. Inertia is neglected (the gaits are slow next to
//! µ·g), so at each instant the body moves so that the friction forces balance: the rigid
//! velocity (vx, vy, ω) that, added to the shape's own motion, minimises the dissipation
//! Σ µ·m_k·|v_k| (Newton's method). Contact points: by default the two sphere centres
//! of each capsule link, equal loads; [`displacement_per_cycle_with`] spreads more
//! points along each link (a cylinder's contact line).

use nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};

use crate::gait::{BodyLayout, Plane, Serpenoid};

/// Ground contact points of the chain with joint angles `angles` (lateral joints bend in
/// the plane, dorsal ones are ignored), head link centred at the origin along +x:
/// `per_link` (≥ 2) points evenly from one end of a link's contact line (`inset_m` in
/// from the link's ends) to the other.
fn contact_points(
    layout: &BodyLayout,
    angles: &[f64],
    inset_m: f64,
    per_link: usize,
    out: &mut Vec<Vector2<f64>>,
) {
    out.clear();
    let l = layout.module_length_m;
    let (mut centre, mut heading) = (Vector2::zeros(), 0.0_f64);
    for k in 0..=angles.len() {
        let dir = Vector2::new(heading.cos(), heading.sin());
        let half = 0.5 * l - inset_m;
        for i in 0..per_link {
            let s = -half + 2.0 * half * i as f64 / (per_link - 1) as f64;
            out.push(centre + dir * s);
        }
        if let (Some(&a), Some(&plane)) = (angles.get(k), layout.planes.get(k)) {
            if plane == Plane::Lateral {
                heading += a;
            }
            let next = Vector2::new(heading.cos(), heading.sin());
            centre += dir * (0.5 * l) + next * (0.5 * l);
        }
    }
}

/// Net displacement of the centre over one gait cycle, m: `[forward, across]`, forward
/// along the line from the tail to the head at the cycle's start.
pub fn displacement_per_cycle(
    gait: &Serpenoid,
    layout: &BodyLayout,
    radius_m: f64,
    steps: usize,
) -> [f64; 2] {
    displacement_per_cycle_with(gait, layout, radius_m, 2, steps)
}

/// [`displacement_per_cycle`] with `per_link` contact points along each link, from
/// `inset_m` inside one end to `inset_m` inside the other.
pub fn displacement_per_cycle_with(
    gait: &Serpenoid,
    layout: &BodyLayout,
    inset_m: f64,
    per_link: usize,
    steps: usize,
) -> [f64; 2] {
    assert!(per_link >= 2, "a link needs two contact points at least");
    let n = layout.len();
    let (mut angles, mut ahead) = (vec![0.0; n], vec![0.0; n]);
    let (mut pts, mut pts_ahead) = (Vec::new(), Vec::new());
    // World pose of the body frame (the shape's frame).
    let (mut pos, mut yaw) = (Vector2::zeros(), 0.0_f64);
    let mut start: Option<(Vector2<f64>, Vector2<f64>)> = None;
    // The twist changes smoothly with the phase: each solve starts from the last one.
    let mut u = Vector3::zeros();
    let dpsi = std::f64::consts::TAU / steps as f64;
    for k in 0..=steps {
        let psi = k as f64 * dpsi;
        gait.evaluate(layout, psi, &mut angles);
        contact_points(layout, &angles, inset_m, per_link, &mut pts);
        let rot = nalgebra::Rotation2::new(yaw);
        let centre = pos + rot * (pts.iter().sum::<Vector2<f64>>() / pts.len() as f64);
        let (centre0, fwd) = *start.get_or_insert_with(|| (centre, tail_to_head(&pts, per_link)));
        if k == steps {
            let d = centre - centre0;
            return [d.dot(&fwd), fwd.perp(&d)];
        }
        // Shape velocity per unit phase, in the body frame.
        gait.evaluate(layout, psi + 1e-6, &mut ahead);
        contact_points(layout, &ahead, inset_m, per_link, &mut pts_ahead);
        let shape_v: Vec<Vector2<f64>> = pts
            .iter()
            .zip(&pts_ahead)
            .map(|(a, b)| (b - a) / 1e-6)
            .collect();
        u = balance_friction(&pts, &shape_v, u);
        // Integrate the body frame (body-frame twist u per unit phase).
        pos += rot * Vector2::new(u.x, u.y) * dpsi;
        yaw += u.z * dpsi;
    }
    unreachable!("the loop returns at k == steps")
}

/// [`displacement_per_cycle_with`] of a cycle given as its shapes: `shapes[k]` the joint
/// angles at phase 2π·k/len (a cycle sampled evenly, e.g. measured joint angles).
pub fn displacement_of_shapes(
    shapes: &[Vec<f64>],
    layout: &BodyLayout,
    inset_m: f64,
    per_link: usize,
) -> [f64; 2] {
    displacement_of_loaded_shapes(shapes, None, layout, inset_m, per_link)
}

/// [`displacement_of_shapes`] with each link's share of the load at each sample
/// (`loads[k][link]`, any scale; `None`: equal loads).
pub fn displacement_of_loaded_shapes(
    shapes: &[Vec<f64>],
    loads: Option<&[Vec<f64>]>,
    layout: &BodyLayout,
    inset_m: f64,
    per_link: usize,
) -> [f64; 2] {
    let mut w = Vec::new();
    let (mut pts, mut pts_next) = (Vec::new(), Vec::new());
    let (mut pos, mut yaw) = (Vector2::zeros(), 0.0_f64);
    let mut start: Option<(Vector2<f64>, Vector2<f64>)> = None;
    let mut u = Vector3::zeros();
    let steps = shapes.len();
    for k in 0..=steps {
        contact_points(layout, &shapes[k % steps], inset_m, per_link, &mut pts);
        let rot = nalgebra::Rotation2::new(yaw);
        let centre = pos + rot * (pts.iter().sum::<Vector2<f64>>() / pts.len() as f64);
        let (centre0, fwd) = *start.get_or_insert_with(|| (centre, tail_to_head(&pts, per_link)));
        if k == steps {
            let d = centre - centre0;
            return [d.dot(&fwd), fwd.perp(&d)];
        }
        contact_points(
            layout,
            &shapes[(k + 1) % steps],
            inset_m,
            per_link,
            &mut pts_next,
        );
        // Shape velocity per step, in the body frame.
        let shape_v: Vec<Vector2<f64>> = pts.iter().zip(&pts_next).map(|(a, b)| b - a).collect();
        w.clear();
        match loads {
            Some(l) if l[k].len() == pts.len() => w.extend_from_slice(&l[k]),
            Some(l) => w.extend(l[k].iter().flat_map(|&x| std::iter::repeat_n(x, per_link))),
            None => w.resize(pts.len(), 1.0),
        }
        u = balance_weighted(&pts, &shape_v, &w, u);
        pos += rot * Vector2::new(u.x, u.y);
        yaw += u.z;
    }
    unreachable!("the loop returns at k == steps")
}

/// Unit vector from the tail link's centre to the head link's (the physics' own
/// definition of "forward"), `per_link` points per link.
fn tail_to_head(pts: &[Vector2<f64>], per_link: usize) -> Vector2<f64> {
    let centre = |s: &[Vector2<f64>]| s.iter().sum::<Vector2<f64>>() / s.len() as f64;
    let line = centre(&pts[..per_link]) - centre(&pts[pts.len() - per_link..]);
    line / line.norm()
}

/// Rigid twist (vx, vy, ω about the body origin) that balances isotropic Coulomb
/// friction on points `pts` moving with `shape_v` relative to the body, from `guess`:
/// Newton's method on the dissipation Σ |v_k|, smoothed below `EPS` so a sticking point
/// does not make it singular.
fn balance_friction(
    pts: &[Vector2<f64>],
    shape_v: &[Vector2<f64>],
    guess: Vector3<f64>,
) -> Vector3<f64> {
    let w = vec![1.0; pts.len()];
    balance_weighted(pts, shape_v, &w, guess)
}

/// [`balance_friction`] with a normal load `w[k]` on each point.
fn balance_weighted(
    pts: &[Vector2<f64>],
    shape_v: &[Vector2<f64>],
    w: &[f64],
    guess: Vector3<f64>,
) -> Vector3<f64> {
    const EPS: f64 = 1e-6;
    let mut u = guess;
    for _ in 0..50 {
        let (mut hess, mut grad) = (Matrix3::zeros(), Vector3::zeros());
        for ((p, sv), &wk) in pts.iter().zip(shape_v).zip(w) {
            let j = Matrix2x3::new(1.0, 0.0, -p.y, 0.0, 1.0, p.x);
            let v = j * u + sv;
            let r = (v.norm_squared() + EPS * EPS).sqrt();
            grad += j.transpose() * v * (wk / r);
            let h = (nalgebra::Matrix2::identity() - v * v.transpose() / (r * r)) * (wk / r);
            hess += j.transpose() * h * j;
        }
        let Some(step) = hess.try_inverse().map(|inv| inv * grad) else {
            break;
        };
        // Backtracking: the smoothed |v| is nearly a cone, where full steps overshoot.
        let f0 = dissipation(pts, shape_v, w, u, EPS);
        let mut t = 1.0;
        while t > 1e-6 && dissipation(pts, shape_v, w, u - step * t, EPS) > f0 {
            t *= 0.5;
        }
        u -= step * t;
        if (step * t).norm() < 1e-12 * (1.0 + u.norm()) {
            break;
        }
    }
    u
}

/// Σ sqrt(|v_k|² + eps²) for the twist `u`.
fn dissipation(
    pts: &[Vector2<f64>],
    shape_v: &[Vector2<f64>],
    w: &[f64],
    u: Vector3<f64>,
    eps: f64,
) -> f64 {
    pts.iter()
        .zip(shape_v)
        .zip(w)
        .map(|((p, sv), wk)| {
            let v = Vector2::new(u.x - u.z * p.y, u.y + u.z * p.x) + sv;
            wk * (v.norm_squared() + eps * eps).sqrt()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::{GaitKind, GaitParams};
    use crate::module::MODULE_LENGTH_M;

    fn slithering(amplitude_rad: f64) -> (Serpenoid, BodyLayout) {
        let layout = BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M);
        let params = GaitParams {
            amplitude_lat_rad: amplitude_rad,
            ..GaitParams::default_for(GaitKind::Slithering)
        };
        (
            Serpenoid::for_layout(GaitKind::Slithering, &params, &layout),
            layout,
        )
    }

    #[test]
    fn a_still_body_stays_put_and_the_result_is_converged_in_steps() {
        let (still, layout) = slithering(0.0);
        let d = displacement_per_cycle(&still, &layout, 0.0255, 200);
        assert!(d[0].abs() < 1e-12 && d[1].abs() < 1e-12, "{d:?}");
        let (gait, layout) = slithering(std::f64::consts::FRAC_PI_4);
        let coarse = displacement_per_cycle(&gait, &layout, 0.0255, 500);
        let fine = displacement_per_cycle(&gait, &layout, 0.0255, 2000);
        assert!(fine[0].abs() > 0.01, "{fine:?}");
        assert!(
            (coarse[0] - fine[0]).abs() < 0.02 * fine[0].abs(),
            "{coarse:?} {fine:?}"
        );
    }

    /// Scratch: how the drift depends on where the links touch the ground.
    #[test]
    #[ignore]
    fn drift_by_contact_points() {
        let layout = BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M);
        for amp in [0.6, std::f64::consts::FRAC_PI_4, 1.0, 1.2] {
            for sf in [
                std::f64::consts::PI,
                std::f64::consts::TAU,
                3.0 * std::f64::consts::PI,
            ] {
                let params = GaitParams {
                    amplitude_lat_rad: amp,
                    spatial_freq_rad: sf,
                    ..GaitParams::default_for(GaitKind::Slithering)
                };
                let gait = Serpenoid::for_layout(GaitKind::Slithering, &params, &layout);
                let mut row = format!("A {amp:.1} ws {sf:.2}:");
                for (inset, per) in [
                    (0.0255, 2),
                    (0.0, 2),
                    (0.0, 3),
                    (0.0, 5),
                    (0.0, 9),
                    (0.0255, 9),
                ] {
                    let d = displacement_per_cycle_with(&gait, &layout, inset, per, 1000);
                    row += &format!("  [{inset:.3},{per}] {:+.4}", d[0]);
                }
                println!("{row}");
            }
        }
    }
}
