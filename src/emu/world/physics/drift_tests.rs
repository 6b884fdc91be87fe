//! Slithering's drift on isotropic ground: the physics against the quasi-static Coulomb
//! model, with the physics' own joint angles and ground loads (issue 28, point 0;
//! docs/measurements.md, "Slithering on open ground"). A diagnostic that prints.

use std::f64::consts::PI;

use super::tests::quiet;
use super::validation_tests::{N, layout, run_gait_from};
use super::*;
use crate::emu::Plant;
use crate::gait::{GaitKind, GaitParams, Serpenoid};

/// Scratch (issue 28, point 0): slithering's drift on isotropic ground in the physics
/// against the quasi-static Coulomb model, over amplitude and spatial frequency.
#[test]
#[ignore]
fn slithering_drift_sweep() {
    let l = layout();
    let wt: f64 = std::env::var("WT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    for sf in [2.0 * PI, 3.0 * PI] {
        for amp in [std::f64::consts::FRAC_PI_4, 1.0] {
            let params = GaitParams {
                amplitude_lat_rad: amp,
                spatial_freq_rad: sf,
                temporal_freq_rad_s: wt,
                ..GaitParams::default_for(GaitKind::Slithering)
            };
            let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
            let cycles = 3;
            let settle = cycle_s;
            let mut start: Option<([f64; 3], [f64; 2])> = None;
            let mut end = [0.0; 3];
            let mut measured: Vec<Vec<f64>> = Vec::new();
            let mut loads: Vec<Vec<f64>> = Vec::new();
            let mut commanded: Vec<Vec<f64>> = Vec::new();
            let period_ms = (cycle_s * 1e3).round() as usize;
            run_gait_from(
                &WorldSpec::default(),
                quiet(N),
                GaitKind::Slithering,
                params,
                0.0,
                settle + cycle_s * cycles as f64,
                |t, p| {
                    if start.is_none() && t >= settle - 1e-9 {
                        let head = p.link_pose(0).position_m;
                        let tail = p.link_pose(p.link_count() - 1).position_m;
                        let d = [head[0] - tail[0], head[1] - tail[1]];
                        let n = d[0].hypot(d[1]);
                        start = Some((p.centre_of_mass_m(), [d[0] / n, d[1] / n]));
                    }
                    if start.is_some() && measured.len() < period_ms {
                        loads.push(ground_loads(p));
                        measured.push(
                            (0..N)
                                .map(|i| f64::from(p.feedback(i).position_rad))
                                .collect(),
                        );
                    }
                    end = p.centre_of_mass_m();
                },
            );
            let (c0, fwd) = start.unwrap();
            let d = [end[0] - c0[0], end[1] - c0[1]];
            let along = (d[0] * fwd[0] + d[1] * fwd[1]) / cycles as f64;
            let gait = Serpenoid::for_layout(GaitKind::Slithering, &params, &l);
            let model = super::coulomb_model::displacement_per_cycle(
                &gait,
                &l,
                0.5 * build::MODULE_DIAMETER_M,
                1000,
            );
            for k in 0..measured.len() {
                let mut a = vec![0.0; N];
                let psi = 2.0 * PI * k as f64 / measured.len() as f64;
                gait.evaluate(&l, psi + params.temporal_freq_rad_s * settle, &mut a);
                commanded.push(a);
            }
            let r = 0.5 * build::MODULE_DIAMETER_M;
            let of_measured = super::coulomb_model::displacement_of_shapes(&measured, &l, r, 2);
            let of_commanded = super::coulomb_model::displacement_of_shapes(&commanded, &l, r, 2);
            let lag: f64 = (0..N)
                .step_by(2)
                .map(|i| {
                    measured
                        .iter()
                        .zip(&commanded)
                        .map(|(m, c)| (m[i] - c[i]).powi(2))
                        .sum::<f64>()
                        / measured.len() as f64
                })
                .sum::<f64>()
                .sqrt();
            let loaded = super::coulomb_model::displacement_of_loaded_shapes(
                &measured,
                Some(&loads),
                &l,
                r,
                2,
            );
            let spread: f64 = {
                let (mut s, mut n) = (0.0, 0.0);
                for row in &loads {
                    let m = row.iter().sum::<f64>() / row.len() as f64;
                    for x in row {
                        s += (x / m - 1.0).powi(2);
                        n += 1.0;
                    }
                }
                (s / n).sqrt()
            };
            println!(
                "ws {sf:.2} A {amp:.2}: physics {along:+.4} m/cycle, model {:+.4}, model of the measured shapes {:+.4} (of the commanded {:+.4}), with the measured loads {:+.4}; rms tracking error {lag:.3} rad; load spread (cv) {spread:.2}",
                model[0], of_measured[0], of_commanded[0], loaded[0]
            );
        }
    }
}

/// Each link's normal force from the ground this step, N (scratch, issue 28).
fn ground_loads(p: &PhysicsPlant) -> Vec<f64> {
    p.chain
        .colliders
        .iter()
        .map(|&ch| {
            p.world
                .narrow_phase
                .contact_pairs_with(ch)
                .filter(|pair| {
                    let other = if pair.collider1 == ch {
                        pair.collider2
                    } else {
                        pair.collider1
                    };
                    p.world
                        .colliders
                        .get(other)
                        .is_some_and(|c| c.user_data == build::TAG_SKIN_SURFACE)
                        && pair.has_any_active_contact()
                })
                .map(|pair| f64::from(pair.total_impulse().length()) / 1e-3)
                .sum()
        })
        .collect()
}
