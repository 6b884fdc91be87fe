//! Blending, resync, parameter changes and the slew limiter.
use super::*;
use crate::gait::body::Plane;
use crate::module::{MODULE_LENGTH_M, MODULE_MAX_SPEED_RAD_S};

const DT: f64 = 1e-3;
const VMAX: f64 = MODULE_MAX_SPEED_RAD_S;

fn sea() -> BodyLayout {
    BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M)
}

fn selector(initial: GaitKind) -> GaitSelector {
    GaitSelector::new(
        sea(),
        GaitTable::default(),
        initial,
        DEFAULT_BLEND_TIME_S,
        VMAX,
    )
}

/// Drives a selector cycle by cycle and records the largest per-step motion.
struct Rig {
    sel: GaitSelector,
    t: f64,
    pos: Vec<f64>,
    vel: Vec<f64>,
    prev: Option<Vec<f64>>,
    max_step: f64,
}

impl Rig {
    fn new(sel: GaitSelector, t: f64) -> Self {
        let n = sel.layout().len();
        Rig {
            sel,
            t,
            pos: vec![0.0; n],
            vel: vec![0.0; n],
            prev: None,
            max_step: 0.0,
        }
    }

    fn step(&mut self) -> f64 {
        self.sel.update(self.t, &mut self.pos, &mut self.vel);
        let mut step: f64 = 0.0;
        if let Some(prev) = &self.prev {
            for (a, b) in self.pos.iter().zip(prev) {
                step = step.max((a - b).abs());
            }
        }
        self.max_step = self.max_step.max(step);
        self.prev = Some(self.pos.clone());
        self.t += DT;
        step
    }

    fn run(&mut self, seconds: f64) {
        let steps = (seconds / DT).round() as usize;
        for _ in 0..steps {
            self.step();
        }
    }

    /// Set-points the pure active gait would command at the rig's last update.
    fn pure(&self) -> (Vec<f64>, Vec<f64>) {
        let kind = self.sel.active();
        let p = self.sel.table().get(kind);
        let layout = self.sel.layout();
        let (mut pos, mut vel) = (vec![0.0; layout.len()], vec![0.0; layout.len()]);
        Serpenoid::for_layout(kind, p, layout).evaluate_with_velocity(
            layout,
            self.sel.phase(),
            p.temporal_freq_rad_s,
            &mut pos,
            &mut vel,
        );
        (pos, vel)
    }

    fn assert_pure(&self, what: &str) {
        let (pos, vel) = self.pure();
        for i in 0..pos.len() {
            assert!(
                (self.pos[i] - pos[i]).abs() < 1e-9,
                "{what}: joint {i} position"
            );
            assert!(
                (self.vel[i] - vel[i]).abs() < 1e-9,
                "{what}: joint {i} velocity"
            );
        }
    }
}

fn assert_within_speed(rig: &Rig, what: &str) {
    assert!(
        rig.max_step <= VMAX * DT * (1.0 + 1e-9),
        "{what}: a set-point moved {} rad in one {DT} s step",
        rig.max_step
    );
}

#[test]
fn first_setpoint_after_resync_equals_the_measured_pose() {
    let measured: Vec<f64> = (0..18)
        .map(|i| 1.4 * ((i * 7 % 5) as f64 / 2.0 - 1.0))
        .collect();
    for kind in GaitKind::ALL {
        let mut rig = Rig::new(selector(kind), 0.0);
        rig.run(1.0); // some history the resync must forget
        rig.sel.resync(&measured, rig.t);
        rig.prev = None;
        rig.step();
        assert_eq!(rig.pos, measured, "{kind:?}");
        assert!(
            rig.vel.iter().all(|&v| v == 0.0),
            "{kind:?}: starts at rest"
        );
        assert_eq!(rig.sel.blend_progress(), 0.0);
        rig.max_step = 0.0;
        rig.run(DEFAULT_BLEND_TIME_S + 0.5);
        assert_within_speed(&rig, kind.name());
        assert_eq!(rig.sel.blend_progress(), 1.0);
        rig.assert_pure(kind.name());
    }
}

#[test]
fn switching_between_every_pair_of_gaits_stays_within_joint_speed_without_the_limiter() {
    for from in GaitKind::ALL {
        for to in GaitKind::ALL {
            if from == to {
                continue;
            }
            let mut rig = Rig::new(selector(from), 0.0);
            rig.run(2.345); // switch at an arbitrary phase
            rig.sel.set_gait(to, rig.t);
            assert_eq!(rig.sel.active(), to);
            rig.run(DEFAULT_BLEND_TIME_S + 0.2);
            let what = format!("{from:?} -> {to:?}");
            assert_within_speed(&rig, &what);
            assert_eq!(rig.sel.limited_cycles(), 0, "{what}: limiter was needed");
            rig.assert_pure(&what);
        }
    }
}

#[test]
fn blend_progress_rises_smoothly_from_zero_to_one() {
    let mut rig = Rig::new(selector(GaitKind::Slithering), 0.0);
    rig.run(0.5);
    assert_eq!(rig.sel.blend_progress(), 1.0);
    rig.sel.set_gait(GaitKind::Sidewinding, rig.t);
    rig.step();
    assert_eq!(rig.sel.blend_progress(), 0.0);
    rig.run(DEFAULT_BLEND_TIME_S / 2.0);
    assert!((rig.sel.blend_progress() - 0.5).abs() < 2e-3);
    rig.run(DEFAULT_BLEND_TIME_S / 2.0 + 0.01);
    assert_eq!(rig.sel.blend_progress(), 1.0);
}

#[test]
fn velocity_feed_forward_is_the_derivative_of_the_set_points_during_a_blend() {
    let mut rig = Rig::new(selector(GaitKind::Rolling), 0.0);
    rig.run(1.0);
    rig.sel.set_gait(GaitKind::RollingHelix, rig.t);
    rig.run(0.7);
    // Central difference over two consecutive fine steps vs the reported velocity.
    let h = 1e-5;
    let mut sel = rig.sel.clone();
    let n = 18;
    let (mut p0, mut p1, mut p2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut v = vec![0.0; n];
    sel.update(rig.t, &mut p0, &mut v);
    sel.update(rig.t + h, &mut p1, &mut v);
    let v_mid = v.clone();
    sel.update(rig.t + 2.0 * h, &mut p2, &mut v);
    for i in 0..n {
        let fd = (p2[i] - p0[i]) / (2.0 * h);
        assert!(
            (v_mid[i] - fd).abs() < 1e-4,
            "joint {i}: {} vs {fd}",
            v_mid[i]
        );
    }
    assert!(v_mid.iter().any(|v| v.abs() > 0.1), "a blend that moves");
}

#[test]
fn switching_mid_blend_is_smooth_and_ends_on_the_last_gait() {
    let mut rig = Rig::new(selector(GaitKind::Slithering), 0.0);
    rig.run(1.0);
    rig.sel.set_gait(GaitKind::Sidewinding, rig.t);
    rig.run(0.8);
    rig.sel.set_gait(GaitKind::LinearProgression, rig.t);
    rig.run(0.6);
    rig.sel.set_gait(GaitKind::Slithering, rig.t);
    rig.run(DEFAULT_BLEND_TIME_S + 0.1);
    assert_within_speed(&rig, "mid-blend switches");
    assert_eq!(rig.sel.limited_cycles(), 0);
    rig.assert_pure("after mid-blend switches");
}

#[test]
fn many_rapid_switches_collapse_layers_without_a_jump() {
    let mut rig = Rig::new(selector(GaitKind::Sidewinding), 0.0);
    rig.run(0.5);
    let order = [
        GaitKind::Rolling,
        GaitKind::Slithering,
        GaitKind::RollingHelix,
        GaitKind::ConicalSidewinding,
        GaitKind::LinearProgression,
    ];
    for k in 0..3 * MAX_LAYERS {
        rig.sel.set_gait(order[k % order.len()], rig.t);
        rig.run(0.05);
    }
    rig.run(DEFAULT_BLEND_TIME_S + 0.1);
    assert_within_speed(&rig, "rapid switches");
    rig.assert_pure("after rapid switches");
}

#[test]
fn a_parameter_change_mid_run_blends_in_without_a_step() {
    let mut rig = Rig::new(selector(GaitKind::Slithering), 0.0);
    rig.run(1.5);
    let before = rig.max_step;
    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.5),
        spatial_freq_rad: Some(2.0 * std::f64::consts::PI),
        temporal_freq_rad_s: Some(-1.2),
        ..ParamPatch::default()
    };
    rig.sel
        .set_params(GaitKind::Slithering, &patch, rig.t)
        .expect("valid patch");
    assert_eq!(
        rig.sel.table().get(GaitKind::Slithering).amplitude_lat_rad,
        0.5
    );
    let first = rig.step();
    assert!(
        first <= before * 1.01,
        "the change stepped: {first} > {before}"
    );
    assert!(rig.sel.blend_progress() < 0.01);
    rig.run(DEFAULT_BLEND_TIME_S + 0.1);
    assert_within_speed(&rig, "param change");
    assert_eq!(rig.sel.limited_cycles(), 0);
    rig.assert_pure("after param change");
}

#[test]
fn changing_temporal_frequency_never_jumps_the_phase() {
    let mut rig = Rig::new(selector(GaitKind::Sidewinding), 0.0);
    rig.run(1.0);
    let (w_old, w_new) = (1.0, 2.5);
    let patch = ParamPatch {
        temporal_freq_rad_s: Some(w_new),
        ..ParamPatch::default()
    };
    rig.sel
        .set_params(GaitKind::Sidewinding, &patch, rig.t)
        .unwrap();
    let mut prev = rig.sel.phase();
    let mut last_rate = 0.0;
    for _ in 0..((DEFAULT_BLEND_TIME_S + 0.5) / DT) as usize {
        rig.step();
        let dpsi = rig.sel.phase() - prev;
        assert!(dpsi >= w_old * DT * (1.0 - 1e-9), "phase slowed: {dpsi}");
        assert!(dpsi <= w_new * DT * (1.0 + 1e-9), "phase jumped by {dpsi}");
        last_rate = dpsi / DT;
        prev = rig.sel.phase();
    }
    assert!(
        (last_rate - w_new).abs() < 1e-9,
        "runs at the new ωT: {last_rate}"
    );
}

#[test]
fn changing_an_inactive_gait_does_not_touch_the_output() {
    let mut a = Rig::new(selector(GaitKind::Slithering), 0.0);
    let mut b = Rig::new(selector(GaitKind::Slithering), 0.0);
    a.run(0.5);
    b.run(0.5);
    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.2),
        ..ParamPatch::default()
    };
    b.sel.set_params(GaitKind::Rolling, &patch, b.t).unwrap();
    assert_eq!(b.sel.table().get(GaitKind::Rolling).amplitude_lat_rad, 0.2);
    a.run(0.5);
    b.run(0.5);
    assert_eq!(a.pos, b.pos);
    assert_eq!(b.sel.blend_progress(), 1.0);
}

#[test]
fn refused_parameters_change_nothing() {
    let mut sel = selector(GaitKind::Slithering);
    let before = *sel.table();
    let fast = ParamPatch {
        temporal_freq_rad_s: Some(8.0),
        ..ParamPatch::default()
    };
    let err = sel
        .set_params(GaitKind::Slithering, &fast, 0.0)
        .unwrap_err();
    assert!(matches!(err, ParamError::TooFast { .. }));
    assert_eq!(*sel.table(), before);
    assert_eq!(sel.blend_progress(), 1.0);
}

#[test]
fn blend_time_is_range_checked() {
    let mut sel = selector(GaitKind::Rolling);
    assert_eq!(sel.blend_time_s(), DEFAULT_BLEND_TIME_S);
    assert!(matches!(
        sel.set_blend_time(0.05),
        Err(ParamError::OutOfRange { .. })
    ));
    assert!(matches!(
        sel.set_blend_time(31.0),
        Err(ParamError::OutOfRange { .. })
    ));
    assert!(matches!(
        sel.set_blend_time(f64::NAN),
        Err(ParamError::NotFinite { .. })
    ));
    assert_eq!(sel.set_blend_time(0.1), Ok(()));
    assert_eq!(sel.set_blend_time(30.0), Ok(()));
    assert_eq!(sel.blend_time_s(), 30.0);
}

#[test]
fn setting_the_active_gait_again_changes_nothing() {
    let mut rig = Rig::new(selector(GaitKind::Sidewinding), 0.0);
    rig.run(0.3);
    rig.sel.set_gait(GaitKind::Sidewinding, rig.t);
    rig.step();
    assert_eq!(rig.sel.blend_progress(), 1.0);
    rig.assert_pure("same gait again");
}

#[test]
fn slew_limiter_catches_what_a_short_blend_would_overspeed() {
    let mut sel = selector(GaitKind::RollingHelix);
    sel.set_blend_time(0.1).unwrap();
    let mut rig = Rig::new(sel, 0.0);
    rig.run(0.2);
    // Start far from the helix: ~1.5 rad to cover in 0.1 s is ~20 rad/s.
    let measured: Vec<f64> = (0..18)
        .map(|i| if i % 2 == 0 { -1.5 } else { 1.5 })
        .collect();
    rig.sel.resync(&measured, rig.t);
    // Motion is measured from the pose the joints are in, not the old set-points.
    rig.prev = Some(measured.clone());
    rig.max_step = 0.0;
    rig.run(1.0);
    assert!(rig.sel.limited_cycles() > 0, "the limiter was needed here");
    assert_within_speed(&rig, "limited resync");
    assert!(rig.vel.iter().all(|v| v.abs() <= VMAX));
    // Once caught up, the pure gait again.
    rig.run(2.0);
    rig.assert_pure("after the limiter let go");
}

#[test]
fn non_finite_measured_joint_starts_on_the_gait() {
    let mut rig = Rig::new(selector(GaitKind::Slithering), 0.0);
    let mut measured = vec![0.1; 18];
    measured[4] = f64::NAN;
    rig.sel.resync(&measured, 0.0);
    rig.step();
    assert!(rig.pos.iter().all(|p| p.is_finite()));
    assert_eq!(rig.pos[0], 0.1);
}
