//! The controller in the physics, through the daemon's loop (the lab's trial loop, with
//! the pose estimate in it): which way the conical taper turns the body, that a
//! nominal heading turned round reverses the travel, and that it steers to a heading.

use crate::controllers::sidewinding::{HeadingConfig, wrap_pi};
use std::f64::consts::{PI, TAU};

use crate::controller::ControllerCommand;
use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::PhysicsPlant;
use crate::gait::GaitKind;
use crate::lab::controllers::LabController;
use crate::lab::trial::{TrialConfig, plant_of, trial_loop};
use crate::rt::messages::LoopRequest;

/// The body's true heading (tail to head) and centre.
fn pose(plant: &dyn Plant) -> (f64, [f64; 2]) {
    let n = plant.link_count();
    let (h, t) = (
        plant.link_pose(0).position_m,
        plant.link_pose(n - 1).position_m,
    );
    let mut c = [0.0, 0.0];
    for k in 0..n {
        let p = plant.link_pose(k).position_m;
        c = [c[0] + p[0] / n as f64, c[1] + p[1] / n as f64];
    }
    ((h[1] - t[1]).atan2(h[0] - t[0]), c)
}

/// Runs `name` on `gait` on flat ground for `seconds`, with `requests` waiting for its
/// first cycle; the body's pose every 0.1 s.
fn run(gait: GaitKind, name: &str, seconds: f64, requests: &[LoopRequest]) -> Vec<(f64, [f64; 2])> {
    let controller = LabController::named(gait, name).unwrap();
    let config = TrialConfig::default();
    let plant = PhysicsPlant::new(&WorldSpec::default(), config.physics(7)).unwrap();
    let (mut lp, _, _) = trial_loop(&controller, plant, &config, None, requests).unwrap();
    let mut poses = vec![pose(plant_of(&lp))];
    for k in 1..=(seconds * 1000.0) as usize {
        lp.step();
        if k % 100 == 0 {
            poses.push(pose(plant_of(&lp)));
        }
    }
    poses
}

fn heading(gait_h: f64) -> LoopRequest {
    LoopRequest::ControllerCommand(
        GaitKind::Sidewinding,
        ControllerCommand::SetHeading {
            heading_rad: Some(gait_h),
        },
    )
}

/// The mean heading of `poses` (the heading sways within a gait cycle: average whole
/// cycles).
fn mean_heading(poses: &[(f64, [f64; 2])]) -> f64 {
    let (c, s) = poses
        .iter()
        .fold((0.0, 0.0), |(c, s), p| (c + p.0.cos(), s + p.0.sin()));
    s.atan2(c)
}

/// Heading turned from the first to the last whole cycle of 4-26 s by open-loop
/// conical sidewinding with the gait table's `taper`, the dorsal wave shifted by `beta`
/// more than the gait's δ.
fn conical_turn(taper: f64, beta: f64) -> f64 {
    conical_turn_scaled(taper, beta, 1.0)
}

/// [`conical_turn`] with both amplitudes scaled by `scale`.
fn conical_turn_scaled(taper: f64, beta: f64, scale: f64) -> f64 {
    let gait = GaitKind::ConicalSidewinding;
    let p = crate::gait::GaitParams::default_for(gait);
    let patch = crate::gait::ParamPatch {
        taper: Some(taper),
        phase_shift_rad: Some(p.phase_shift_rad + beta),
        amplitude_lat_rad: Some(p.amplitude_lat_rad * scale),
        amplitude_dor_rad: Some(p.amplitude_dor_rad * scale),
        ..Default::default()
    };
    let poses = run(
        gait,
        "open_loop",
        26.0,
        &[LoopRequest::SetParams(gait, patch)],
    );
    let cycle = (TAU / 0.1).round() as usize; // samples in one gait period (ωT = 1)
    wrap_pi(mean_heading(&poses[poses.len() - cycle..]) - mean_heading(&poses[40..40 + cycle]))
}

/// The controller's taper `c` as the gait table's conical sidewinding: a head-heavy
/// cone is the amplitude scaled by `1 + c` with the table's taper `c / (1 + c)`.
fn grow_turn(c: f64, beta: f64) -> f64 {
    if c >= 0.0 {
        conical_turn_scaled(c / (1.0 + c), beta, 1.0 + c)
    } else {
        conical_turn(c, beta)
    }
}

/// The heading adjustment's assumption: a positive (head-heavy) taper turns the body
/// `turn_sign` way in the forward gait (β = 0), a negative (tail-heavy) one the other
/// way, and both swap in the reversed gait (β = π). The straight gait turns a little
/// by itself, so the taper's effect is measured against it.
#[test]
fn the_conical_taper_turns_the_body_the_configured_way() {
    let [straight, straight_r, head, tail, head_r] =
        [(0.0, 0.0), (0.0, PI), (0.4, 0.0), (-0.4, 0.0), (0.4, PI)].map(|(c, b)| grow_turn(c, b));
    let (head, tail, head_r) = (head - straight, tail - straight, head_r - straight_r);
    println!(
        "over 16 s: straight sidewinding turns {straight:+.3} rad (β 0) / {straight_r:+.3} \
         (β π); a head-heavy taper of 0.4 turns it {head:+.3} more (β π: {head_r:+.3}), \
         a tail-heavy one {tail:+.3}"
    );
    let sign = HeadingConfig::DEFAULT.turn_sign;
    for (effect, want) in [(head, sign), (tail, -sign), (head_r, -sign)] {
        assert!(effect.abs() > 0.03, "{head} {tail} {head_r}");
        assert_eq!(effect.signum(), want, "{head} {tail} {head_r}");
    }
}

/// A nominal heading half a turn from the body's drags β over the hill: the gait
/// reverses and the body travels back the way the same gait without the command goes.
#[test]
fn a_nominal_heading_turned_round_reverses_the_travel() {
    // The estimate's yaw is zero at the start's head direction: the body heads at 0.
    let ahead = run(GaitKind::Sidewinding, "sw_open_loop", 30.0, &[]);
    let back = run(GaitKind::Sidewinding, "sw_open_loop", 30.0, &[heading(PI)]);
    let travel = |p: &[(f64, [f64; 2])]| {
        let (a, b) = (p[80].1, p[300].1);
        [b[0] - a[0], b[1] - a[1]]
    };
    let (a, b) = (travel(&ahead), travel(&back));
    let cos = (a[0] * b[0] + a[1] * b[1]) / (a[0].hypot(a[1]) * b[0].hypot(b[1]));
    let headings = |p: &[(f64, [f64; 2])]| p.iter().step_by(50).map(|x| x.0).collect::<Vec<_>>();
    println!(
        "8-30 s: {a:.3?} without a command, {b:.3?} with the nominal heading at π (cos {cos:.2}); \
         headings every 5 s {:.2?} / {:.2?}",
        headings(&ahead),
        headings(&back)
    );
    assert!(b[0].hypot(b[1]) > 0.3, "it still moves: {b:?}");
    assert!(cos < -0.7, "the travel reversed: {a:?} vs {b:?}");
}
