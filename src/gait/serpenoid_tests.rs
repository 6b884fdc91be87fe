//! Each gait's defining property, the analytic velocity, and the rolling helix's shape.
use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::*;
use crate::gait::params::GaitTable;
use crate::module::MODULE_LENGTH_M;

fn sea() -> BodyLayout {
    BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M)
}

fn eval(kind: GaitKind, p: &GaitParams, layout: &BodyLayout, psi: f64) -> Vec<f64> {
    let mut out = vec![0.0; layout.len()];
    Serpenoid::for_layout(kind, p, layout).evaluate(layout, psi, &mut out);
    out
}

fn joints_of(layout: &BodyLayout, plane: Plane) -> impl Iterator<Item = usize> + '_ {
    (0..layout.len()).filter(move |&i| layout.planes[i] == plane)
}

#[test]
fn slithering_moves_only_lateral_joints() {
    let layout = sea();
    let p = *GaitTable::default().get(GaitKind::Slithering);
    for psi in [0.0, 0.7, 2.0] {
        let th = eval(GaitKind::Slithering, &p, &layout, psi);
        for i in joints_of(&layout, Plane::Dorsal) {
            assert_eq!(th[i], 0.0, "dorsal joint {i}");
        }
        let lat_max = joints_of(&layout, Plane::Lateral)
            .map(|i| th[i].abs())
            .fold(0.0, f64::max);
        assert!(
            lat_max > 0.5 * p.amplitude_lat_rad,
            "lateral wave too small"
        );
        for i in joints_of(&layout, Plane::Lateral) {
            let expected = p.amplitude_lat_rad * (p.spatial_freq_rad * layout.s[i] - psi).sin();
            assert!((th[i] - expected).abs() < 1e-12);
        }
    }
}

#[test]
fn linear_progression_moves_only_dorsal_joints() {
    let layout = sea();
    let p = *GaitTable::default().get(GaitKind::LinearProgression);
    let th = eval(GaitKind::LinearProgression, &p, &layout, 1.3);
    for i in joints_of(&layout, Plane::Lateral) {
        assert_eq!(th[i], 0.0);
    }
    for i in joints_of(&layout, Plane::Dorsal) {
        let expected = p.amplitude_dor_rad * (p.spatial_freq_rad * layout.s[i] - 1.3).sin();
        assert!((th[i] - expected).abs() < 1e-12);
    }
}

#[test]
fn offsets_apply_to_the_plane_without_a_wave() {
    let layout = sea();
    let p = GaitParams {
        offset_dor_rad: 0.2,
        ..*GaitTable::default().get(GaitKind::Slithering)
    };
    let th = eval(GaitKind::Slithering, &p, &layout, 0.4);
    for i in joints_of(&layout, Plane::Dorsal) {
        assert_eq!(th[i], 0.2);
    }
}

#[test]
fn sidewinding_dorsal_wave_leads_by_the_phase_shift() {
    // A joint pair at the same s: the dorsal wave equals the lateral one shifted by δ.
    let p = *GaitTable::default().get(GaitKind::Sidewinding);
    let w = Serpenoid::for_layout(GaitKind::Sidewinding, &p, &sea());
    assert_eq!(w.dorsal.phase_rad, p.phase_shift_rad);
    for s in [0.1, 0.37, 0.8] {
        for psi in [0.0, 1.0, 4.0] {
            let (lat, _) = w.joint(Plane::Lateral, s, psi);
            let (dor, _) = w.joint(Plane::Dorsal, s, psi);
            let lat_shifted = w.joint(Plane::Lateral, s, psi - p.phase_shift_rad).0;
            let scale = p.amplitude_dor_rad / p.amplitude_lat_rad;
            assert!((dor - scale * lat_shifted).abs() < 1e-12);
            assert!(
                (lat - p.amplitude_lat_rad * (p.spatial_freq_rad * s - psi).sin()).abs() < 1e-12
            );
        }
    }
}

#[test]
fn rolling_bends_every_joint_of_a_plane_alike_and_planes_a_quarter_apart() {
    let layout = sea();
    let p = *GaitTable::default().get(GaitKind::Rolling);
    let a = p.amplitude_lat_rad;
    for psi in [0.0, 0.9, 2.5] {
        let th = eval(GaitKind::Rolling, &p, &layout, psi);
        for i in joints_of(&layout, Plane::Lateral) {
            assert!((th[i] - a * (-psi).sin()).abs() < 1e-12);
        }
        for i in joints_of(&layout, Plane::Dorsal) {
            assert!((th[i] - a * (-psi).cos()).abs() < 1e-12);
        }
        // The bend keeps its size and only turns about the body: (lat, dor) on a circle.
        assert!((th[0].hypot(th[1]) - a).abs() < 1e-12);
    }
}

#[test]
fn conical_sidewinding_tapers_amplitude_along_the_body() {
    let layout = sea();
    let p = *GaitTable::default().get(GaitKind::ConicalSidewinding);
    let w = Serpenoid::for_layout(GaitKind::ConicalSidewinding, &p, &layout);
    let plain = Serpenoid::for_layout(GaitKind::Sidewinding, &p, &layout);
    for i in 0..layout.len() {
        let (plane, s) = (layout.planes[i], layout.s[i]);
        // Amplitude = |dθ/dψ| at the peak; compare through the phase derivative.
        let cone = w.joint(plane, s, 0.3);
        let flat = plain.joint(plane, s, 0.3);
        let k = 1.0 - p.taper * s;
        assert!((cone.0 - k * flat.0).abs() < 1e-12, "joint {i}");
        assert!((cone.1 - k * flat.1).abs() < 1e-12, "joint {i}");
    }
    // Positive taper: the tail's wave is smaller than the head's.
    let amp = |i: usize| {
        let (plane, s) = (layout.planes[i], layout.s[i]);
        let (a, b) = w.joint(plane, s, 0.0);
        a.hypot(b)
    };
    assert!(amp(16) < 0.8 * amp(0));
}

#[test]
fn velocity_matches_finite_difference_of_position_for_every_gait() {
    let layout = sea();
    let table = GaitTable::default();
    let n = layout.len();
    for kind in GaitKind::ALL {
        let p = table.get(kind);
        let w = Serpenoid::for_layout(kind, p, &layout);
        let wt = p.temporal_freq_rad_s;
        let (t, h) = (1.234, 1e-6);
        let (mut pos, mut vel) = (vec![0.0; n], vec![0.0; n]);
        w.evaluate_with_velocity(&layout, wt * t, wt, &mut pos, &mut vel);
        let (mut ahead, mut behind) = (vec![0.0; n], vec![0.0; n]);
        w.evaluate(&layout, wt * (t + h), &mut ahead);
        w.evaluate(&layout, wt * (t - h), &mut behind);
        for i in 0..n {
            let fd = (ahead[i] - behind[i]) / (2.0 * h);
            assert!(
                (vel[i] - fd).abs() < 1e-6,
                "{kind:?} joint {i}: {} vs {fd}",
                vel[i]
            );
        }
        let peak = vel.iter().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(peak <= w.peak_joint_speed_rad_s() + 1e-12, "{kind:?}");
    }
}

#[test]
fn helix_amplitude_formula_and_its_limit() {
    let (a, tau) = helix_wave(0.1, 0.04, 0.064);
    let d: f64 = 0.1 * 0.1 + 0.04 * 0.04;
    assert!((tau - 0.04 / d).abs() < 1e-12);
    let kappa = 0.1 / d;
    assert!((a - 2.0 * kappa * (tau * 0.064).sin() / tau).abs() < 1e-12);
    // Pitch → 0: a flat circle, each same-plane joint bends κ·2l.
    let (a0, tau0) = helix_wave(0.1, 0.0, 0.064);
    assert_eq!(tau0, 0.0);
    assert!((a0 - 2.0 * 0.064 / 0.1).abs() < 1e-12);
}

/// Joint positions of the chain: module segments of `l` along local x, lateral joints
/// turn about local z, dorsal joints about local y.
fn forward_kinematics(layout: &BodyLayout, theta: &[f64]) -> Vec<Vector3<f64>> {
    let mut rot = Rotation3::identity();
    let mut p = Vector3::zeros();
    let mut points = Vec::new();
    for (i, &th) in theta.iter().enumerate() {
        p += rot * Vector3::new(layout.module_length_m, 0.0, 0.0);
        points.push(p);
        let axis = match layout.planes[i] {
            Plane::Lateral => Vector3::z_axis(),
            Plane::Dorsal => Vector3::y_axis(),
        };
        rot *= Rotation3::from_axis_angle(&axis, th);
    }
    points
}

/// Kåsa circle fit of `points` projected across `axis`:
/// returns (rms radial residual, radius, [centre, u, v]).
fn circle_across(points: &[Vector3<f64>], axis: &Vector3<f64>) -> (f64, f64, [Vector3<f64>; 3]) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = axis.cross(&helper).normalize();
    let v = axis.cross(&u);
    // x² + y² = 2a·x + 2b·y + c.
    let (mut ata, mut atb) = (Matrix3::zeros(), Vector3::zeros());
    for q in points {
        let (x, y) = (q.dot(&u), q.dot(&v));
        let row = Vector3::new(2.0 * x, 2.0 * y, 1.0);
        ata += row * row.transpose();
        atb += row * (x * x + y * y);
    }
    let sol = ata.lu().solve(&atb).expect("circle fit is well posed");
    let (a, b) = (sol[0], sol[1]);
    let r = (sol[2] + a * a + b * b).sqrt();
    let centre = u * a + v * b;
    let ss: f64 = points
        .iter()
        .map(|q| {
            let d = q - centre;
            (d - axis * d.dot(axis)).norm() - r
        })
        .map(|e| e * e)
        .sum();
    ((ss / points.len() as f64).sqrt(), r, [centre, u, v])
}

/// Fits a helix to `points`: the axis is the direction across which the points lie
/// best on a circle (searched over a Fibonacci sphere, then refined). Returns (radius,
/// max relative deviation of the distances from the axis, advance along the axis per
/// radian around it, i.e. the pitch parameter p).
fn fit_helix(points: &[Vector3<f64>]) -> (f64, f64, f64) {
    let n_dirs = 500;
    let mut best = (f64::INFINITY, Vector3::z());
    for i in 0..n_dirs {
        let z = 1.0 - (i as f64 + 0.5) / n_dirs as f64;
        let (rho, phi) = ((1.0 - z * z).sqrt(), i as f64 * 2.399_963_229_728_653);
        let axis = Vector3::new(rho * phi.cos(), rho * phi.sin(), z);
        let rms = circle_across(points, &axis).0;
        if rms < best.0 {
            best = (rms, axis);
        }
    }
    let mut step = 0.05;
    while step > 1e-5 {
        let mut improved = false;
        for d in [Vector3::x(), Vector3::y(), Vector3::z()] {
            for sign in [-1.0, 1.0] {
                let axis = (best.1 + d * (sign * step)).normalize();
                let rms = circle_across(points, &axis).0;
                if rms < best.0 {
                    best = (rms, axis);
                    improved = true;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    let axis = best.1;
    let (_, r, [centre, u, v]) = circle_across(points, &axis);
    let mut dev: f64 = 0.0;
    let (mut prev, mut turned) = (None::<f64>, 0.0);
    for q in points {
        let d = q - centre;
        dev = dev.max(((d - axis * d.dot(&axis)).norm() - r).abs() / r);
        let ang = d.dot(&v).atan2(d.dot(&u));
        if let Some(p) = prev {
            let mut step = ang - p;
            step -= (step / (2.0 * PI)).round() * 2.0 * PI;
            turned += step;
        }
        prev = Some(ang);
    }
    let axial = (points[points.len() - 1] - points[0]).dot(&axis);
    (r, dev, (axial / turned).abs())
}

#[test]
fn rolling_helix_chain_is_a_helix_of_the_commanded_radius() {
    let (r, p) = (0.10, 0.04);
    let params = GaitParams {
        helix_radius_m: r,
        helix_pitch_m: p,
        ..GaitParams::default()
    };
    // The SEA Snake (coarse: 18 modules of 6.4 cm, each joint bending about 1 rad, so the
    // joints zig-zag about 10 % off the helix), and a finely discretised body showing
    // that the formula converges to the continuous helix. Tolerances: (radius, distance
    // of any joint from the helix, pitch), relative.
    for (layout, tol_r, tol_dev, tol_p) in [
        (sea(), 0.05, 0.15, 0.1),
        (
            BodyLayout::alternating(120, Plane::Lateral, 0.01),
            0.005,
            0.01,
            0.01,
        ),
    ] {
        for psi in [0.0, 1.0, FRAC_PI_2 + 0.3] {
            let th = eval(GaitKind::RollingHelix, &params, &layout, psi);
            let (fit_r, dev, fit_p) = fit_helix(&forward_kinematics(&layout, &th));
            let n = layout.len();
            assert!(
                (fit_r - r).abs() < tol_r * r,
                "n={n} psi={psi}: radius {fit_r}"
            );
            assert!(dev < tol_dev, "n={n} psi={psi}: off the helix by {dev}");
            assert!(
                (fit_p - p).abs() < tol_p * p,
                "n={n} psi={psi}: pitch p {fit_p}"
            );
        }
    }
}
