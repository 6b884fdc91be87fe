use std::f64::consts::{FRAC_PI_4, PI};

use super::*;
use crate::emu::servo::MODULE_LENGTH_M;
use crate::gait::{GaitKind, GaitParams, Serpenoid};
use crate::shape::function::numeric_jacobian;
use crate::shape::window::steepness_for_width;

fn layout() -> BodyLayout {
    BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M)
}

#[test]
fn central_fields_reproduce_the_serpenoid() {
    let l = layout();
    let shape = SlitheringShape::new(&l, steepness_for_width(0.03), 8);
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
    let mut shape = SlitheringShape::new(&l, steepness_for_width(0.05), 8);
    // Windowed amplitude and spatial frequency, central phase; then windowed phase too.
    let edges = [f64::NEG_INFINITY, 0.12, 0.45, 0.8, f64::INFINITY];
    let windows: Vec<Window> = edges
        .windows(2)
        .map(|e| Window { a: e[0], b: e[1] })
        .collect();
    shape.set_windows(Param::Amplitude, windows.iter().copied());
    shape.set_windows(Param::SpatialFreq, windows.iter().copied());
    let sigma: Vec<f64> = [0.7, 0.9, 0.6, 0.8, 9.0, 10.5, 8.0, 11.0, 1.3].to_vec();
    check(&shape, &sigma);
    shape.set_windows(Param::Phase, windows.iter().copied());
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
