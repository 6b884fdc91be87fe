use std::f64::consts::{FRAC_PI_4, PI};

use super::*;
use crate::gait::{GaitKind, GaitParams, Serpenoid};
use crate::module::MODULE_LENGTH_M;
use crate::shape::function::numeric_jacobian;
use crate::shape::window::steepness_for_width;

fn layout() -> BodyLayout {
    BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M)
}

#[test]
fn central_fields_reproduce_the_serpenoid() {
    let l = layout();
    let shape = SlitheringShape::new(&l, steepness_for_width(0.03), [8; 3]);
    let params = GaitParams::default_for(GaitKind::Slithering);
    let gait = Serpenoid::for_layout(GaitKind::Slithering, &params, &l);
    let (mut ours, mut theirs) = (vec![0.0; 18], vec![0.0; 18]);
    for psi in [0.0, 0.7, 2.0, 5.5] {
        shape.value(&[FRAC_PI_4, 3.0 * PI, psi], &mut ours);
        gait.evaluate(&l, psi, &mut theirs);
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            let b = if l.planes[i] == Plane::Lateral {
                *b
            } else {
                0.0
            };
            assert!((a - b).abs() < 1e-12, "joint {i} psi {psi}: {a} vs {b}");
        }
    }
}

#[test]
fn analytic_jacobian_matches_finite_differences() {
    let l = layout();
    let mut shape = SlitheringShape::new(&l, steepness_for_width(0.05), [8; 3]);
    // Windowed amplitude and spatial frequency, central phase; then windowed phase too.
    let edges = [f64::NEG_INFINITY, 0.12, 0.45, 0.8, f64::INFINITY];
    let windows: Vec<Window> = edges
        .windows(2)
        .map(|e| Window { a: e[0], b: e[1] })
        .collect();
    shape.set_windows(
        &[Param::Amplitude, Param::SpatialFreq],
        windows.iter().copied(),
    );
    let sigma: Vec<f64> = [0.7, 0.9, 0.6, 0.8, 9.0, 10.5, 8.0, 11.0, 1.3].to_vec();
    check(&shape, &sigma);
    shape.set_windows(&[Param::Phase], windows.iter().copied());
    let sigma: Vec<f64> = [0.7, 0.9, 0.6, 0.8, 9.0, 10.5, 8.0, 11.0, 1.3, 1.1, 1.6, 1.2].to_vec();
    check(&shape, &sigma);
}

fn check(shape: &SlitheringShape, sigma: &[f64]) {
    let (n, m) = (shape.joint_count(), shape.param_count());
    assert_eq!(sigma.len(), m);
    let mut analytic = vec![0.0; n * m];
    shape.jacobian(sigma, &mut analytic);
    let numeric = numeric_jacobian(shape, sigma, 1e-6);
    for (k, (a, b)) in analytic.iter().zip(&numeric).enumerate() {
        assert!((a - b).abs() < 1e-6, "J[{}][{}]: {a} vs {b}", k / m, k % m);
    }
    // Not trivially zero: every column is felt by some joint.
    for j in 0..m {
        assert!(
            (0..n).any(|i| analytic[i * m + j].abs() > 1e-3),
            "column {j} empty"
        );
    }
}

/// `p`'s field and the wave phase at `s` from the windows' definitions.
fn field(shape: &SlitheringShape, sigma: &[f64], p: Param, s: f64) -> f64 {
    let (m, at) = (shape.steepness(), shape.offset(p));
    let w = shape.windows(p).iter().map(|w| w.weight(s, m));
    sigma[at..].iter().zip(w).map(|(v, w)| v * w).sum()
}

fn phase(shape: &SlitheringShape, sigma: &[f64], s: f64) -> f64 {
    let (m, at) = (shape.steepness(), shape.offset(Param::SpatialFreq));
    let windows = shape.windows(Param::SpatialFreq);
    let int = windows.iter().map(|w| w.integral(s, m));
    let integral: f64 = sigma[at..].iter().zip(int).map(|(v, i)| v * i).sum();
    integral - field(shape, sigma, Param::Phase, s)
}

/// The set-points and window-local forces from the windows' definitions, joint by joint.
fn pointwise(shape: &SlitheringShape, sigma: &[f64], tau: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut joints = vec![0.0; shape.joint_count()];
    for (i, s) in shape.lateral_joints() {
        joints[i] = field(shape, sigma, Param::Amplitude, s) * phase(shape, sigma, s).sin();
    }
    let m = shape.steepness();
    let mut forces = vec![0.0; sigma.len()];
    let [oa, ow, op] = Param::ALL.map(|p| shape.offset(p));
    for (i, s) in shape.lateral_joints() {
        if tau[i] == 0.0 {
            continue;
        }
        let a = field(shape, sigma, Param::Amplitude, s);
        let (sin, cos) = phase(shape, sigma, s).sin_cos();
        for (j, w) in shape.windows(Param::Amplitude).iter().enumerate() {
            forces[oa + j] += w.weight(s, m) * sin * tau[i];
        }
        for (j, w) in shape.windows(Param::SpatialFreq).iter().enumerate() {
            forces[ow + j] += w.weight(s, m) * a * cos * w.integral(s, m) * tau[i];
        }
        for (j, w) in shape.windows(Param::Phase).iter().enumerate() {
            forces[op + j] -= a * cos * w.weight(s, m) * tau[i];
        }
    }
    (joints, forces)
}

/// However fields share windows and change them, the sampled step (set-points,
/// window-local forces) gives what evaluating every window at every joint gives, to the
/// bit, and the lateral means agree.
#[test]
fn sampled_fields_give_what_pointwise_evaluation_gives() {
    let l = layout();
    let mut shape = SlitheringShape::new(&l, steepness_for_width(0.5 / 19.0), [8; 3]);
    let tiling = |edges: &[f64]| -> Vec<Window> {
        let mut all = vec![f64::NEG_INFINITY];
        all.extend_from_slice(edges);
        all.push(f64::INFINITY);
        all.windows(2)
            .map(|e| Window { a: e[0], b: e[1] })
            .collect()
    };
    let sets = [
        tiling(&[0.1, 0.43, 0.77]),
        tiling(&[0.3]),
        vec![Window::EVERYWHERE],
        tiling(&[-0.05, 0.2, 0.5, 0.52, 0.95, 1.2]),
    ];
    use Param::{Amplitude as A, Phase as P, SpatialFreq as W};
    let changes: [(&[Param], usize); 9] = [
        (&[A, W], 0),
        (&[P], 1),
        (&[A], 3),
        (&[W, P], 0),
        (&[A, W, P], 3),
        (&[W], 1),
        (&[P, A], 2),
        (&[W], 3),
        (&[A, P], 0),
    ];
    let n = l.len();
    let tau: Vec<f64> = (0..n).map(|i| [0.0, 1.5, -2.0][i % 3]).collect();
    for (step, (params, set)) in changes.into_iter().enumerate() {
        shape.set_windows(params, sets[set].iter().copied());
        let sigma: Vec<f64> = (0..shape.param_count())
            .map(|k| 0.4 + 0.37 * ((k * 7 + step) % 5) as f64)
            .collect();
        let (joints, forces) = pointwise(&shape, &sigma, &tau);
        let mut ours = vec![0.0; n];
        shape.value(&sigma, &mut ours);
        assert_eq!(ours, joints, "change {step}: pointwise");
        shape.set_points(&sigma, &mut ours);
        assert_eq!(ours, joints, "change {step}: sampled");
        let mut ours = vec![0.0; sigma.len()];
        shape.local_forces(&sigma, &tau, &mut ours);
        assert_eq!(ours, forces, "change {step}");
        for p in Param::ALL {
            let lateral = shape.lateral_s().map(|s| field(&shape, &sigma, p, s));
            let mean = lateral.sum::<f64>() / shape.lateral_count() as f64;
            let sampled = shape.lateral_mean(&sigma, p);
            assert!(
                (sampled - mean).abs() < 1e-12,
                "change {step}: {sampled} vs {mean}"
            );
        }
    }
}
