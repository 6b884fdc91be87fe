//! Joint speeds the emulator reports against the motor's (issue 25): no odd–even
//! oscillation at the 1 ms step, and readings above the motor's speed only at contact
//! events (docs/emulator.md, "Joint speeds above the motor's").

use std::f64::consts::PI;

use super::validation_tests::{N, layout, roll_from_flat, run_gait};
use super::*;
use crate::emu::Plant;
use crate::gait::{GaitKind, GaitParams, Serpenoid};

/// Sign changes of `x`'s fast part (`x` minus its centred 21-sample moving average)
/// past ±`threshold`: an oscillation at the 1 ms step (odd–even) changes sign every
/// sample, a physical mode of the body (the spring against one link's inertia rings at
/// about 95 Hz, everything else is slower) at most every 5.
fn fast_sign_changes(x: &[f64], threshold: f64) -> usize {
    let w = 10;
    let (mut changes, mut last) = (0, 0.0);
    for k in w..x.len().saturating_sub(w) {
        let mean = x[k - w..=k + w].iter().sum::<f64>() / (2 * w + 1) as f64;
        let fast = x[k] - mean;
        if fast.abs() > threshold {
            if last != 0.0 && fast.signum() != last {
                changes += 1;
            }
            last = fast.signum();
        }
    }
    changes
}

/// Open-loop rolling on flat ground: every link rests on the ground and the joints
/// turn at most 0.3 rad/s, so the reported joint speeds stay near that. With the
/// servo's torque applied explicitly over each 1 ms step (its velocity feedback read at
/// the step's start), the end links' joints used to oscillate odd–even at the step
/// (about 35 sign changes per joint-second, 200-400 at the two end joints, up to 2.2
/// rad/s) while the solver left the velocities they read unconverged: it runs 3
/// stabilisation sweeps now (docs/emulator.md, "Joint speeds above the motor's").
#[test]
fn open_loop_rolling_joints_do_not_oscillate_at_the_step() {
    let params = GaitParams::default_for(GaitKind::Rolling);
    let (settle_s, seconds) = (1.0, 3.0);
    let mut rates: Vec<Vec<f64>> = vec![Vec::new(); N];
    roll_from_flat(settle_s + seconds, |t, p| {
        if t > settle_s {
            for (i, r) in rates.iter_mut().enumerate() {
                r.push(f64::from(p.feedback(i).velocity_rad_s));
            }
        }
    });
    let changes: Vec<usize> = rates.iter().map(|r| fast_sign_changes(r, 0.3)).collect();
    let per_joint_s = changes.iter().sum::<usize>() as f64 / (N as f64 * seconds);
    let peak = rates.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let commanded =
        Serpenoid::for_layout(GaitKind::Rolling, &params, &layout()).peak_joint_speed_rad_s();
    println!(
        "open-loop rolling: fast part's sign changes (past ±0.3 rad/s) {per_joint_s:.2} per \
         joint-second (per joint over {seconds} s: {changes:?}); reported speeds up to \
         {peak:.2} rad/s (commanded up to {commanded:.2})"
    );
    assert!(per_joint_s < 1.0, "odd–even oscillation: {changes:?}");
    assert!(
        changes.iter().all(|&c| (c as f64) < 5.0 * seconds),
        "{changes:?}"
    );
    assert!(peak < 1.0, "reported joint speed {peak} rad/s");
}

/// The world's normal force on each link over the last rigid-body step, N.
fn normal_force_per_link(plant: &PhysicsPlant) -> Vec<f64> {
    let w = plant.world();
    let dt = f64::from(w.integration_parameters.dt);
    let mut f = vec![0.0; plant.link_count()];
    let tag = |h| w.colliders.get(h).map_or(0, |c| c.user_data);
    for pair in w.narrow_phase.contact_pairs() {
        let (a, b) = (tag(pair.collider1), tag(pair.collider2));
        if (a >= build::TAG_LINK_BASE) != (b >= build::TAG_LINK_BASE) {
            f[(a.max(b) - build::TAG_LINK_BASE) as usize] +=
                f64::from(pair.total_impulse_magnitude()) / dt;
        }
    }
    f
}

/// Conical sidewinding on flat ground over a whole cycle: a reported joint speed above
/// the motor's (3.46 rad/s) is a single sample (at most two steps) in which one of the
/// joint's two links lands on the ground or is hit (its normal force jumps by more than
/// a link's weight within 3 ms), never a stretch of samples or one without a contact
/// event. The head's landing once per cycle reads about 4 rad/s for one step: the
/// contacts' stiffness makes the impact last under a millisecond (docs/emulator.md,
/// "Joint speeds above the motor's").
#[test]
fn joints_exceed_the_motor_s_speed_only_at_contact_events() {
    let params = GaitParams::default_for(GaitKind::ConicalSidewinding);
    let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
    let settle_s = 1.0;
    let motor = crate::module::MODULE_MAX_SPEED_RAD_S;
    let (mut rates, mut forces) = (Vec::new(), Vec::new());
    run_gait(
        &WorldSpec::default(),
        GaitKind::ConicalSidewinding,
        params,
        settle_s + cycle_s,
        |t, p| {
            if t > settle_s {
                rates.push(
                    (0..N)
                        .map(|i| f64::from(p.feedback(i).velocity_rad_s))
                        .collect::<Vec<_>>(),
                );
                forces.push(normal_force_per_link(p));
            }
        },
    );
    let weight = crate::module::MODULE_MASS_KG * crate::emu::plant::GRAVITY_M_S2;
    let (mut episodes, mut peak) = (Vec::new(), 0.0f64);
    for i in 0..N {
        let mut k = 0;
        while k < rates.len() {
            if rates[k][i].abs() <= motor {
                k += 1;
                continue;
            }
            let start = k;
            while k < rates.len() && rates[k][i].abs() > motor {
                peak = peak.max(rates[k][i].abs());
                k += 1;
            }
            let impact = (start.saturating_sub(3).max(1)..=start).any(|j| {
                [i, i + 1]
                    .iter()
                    .any(|&l| (forces[j][l] - forces[j - 1][l]).abs() > weight)
            });
            episodes.push((i, start, k - start, impact));
        }
    }
    println!(
        "conical sidewinding, one cycle: {} episode(s) above {motor} rad/s (joint, sample, \
         steps, at a contact event): {episodes:?}, up to {peak:.2} rad/s",
        episodes.len()
    );
    for &(i, start, steps, impact) in &episodes {
        assert!(
            steps <= 2 && impact,
            "joint {i} above the motor's speed for {steps} steps from sample {start} \
             (contact event: {impact})"
        );
    }
}
