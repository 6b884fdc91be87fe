//! The loop over an ideal plant: start-up, requests, failsafe, safe stop.
use crate::gait::GaitKind;
use crate::rt::control_loop::Flow;
use crate::rt::harness::{Harness, echo_harness};
use crate::rt::messages::{Envelope, LoopRequest, Refusal, Rejection};
use crate::safety::failsafe::{FailsafeConfig, Mode, Reason};

fn request(h: &mut Harness, ticket: u64, r: LoopRequest) -> Result<(), Rejection> {
    h.requests
        .try_send(Envelope::new(ticket, r))
        .expect("queue has room");
    h.control.step();
    let ack = h
        .acks
        .try_recv()
        .expect("the loop answers within the cycle");
    assert_eq!(ack.ticket, ticket);
    ack.result.map(|_| ())
}

fn steps(h: &mut Harness, k: usize) {
    for _ in 0..k {
        h.control.step();
    }
}

#[test]
fn starts_from_the_measured_pose_without_a_step() {
    let pose: Vec<f32> = (0..18).map(|i| 0.3 * ((i as f32) * 0.7).sin()).collect();
    let mut h = echo_harness(
        18,
        Some(&pose),
        GaitKind::Sidewinding,
        false,
        FailsafeConfig::default(),
    );
    // Cycle 0 sees feedback for the first time and re-syncs.
    h.control.step();
    for (c, p) in h.control.commands().iter().zip(&pose) {
        assert!(
            (c.position_rad - p).abs() < 3.46e-3 * 1.01,
            "first set-point {} vs pose {p}",
            c.position_rad
        );
    }
    let mut prev: Vec<f32> = h
        .control
        .commands()
        .iter()
        .map(|c| c.position_rad)
        .collect();
    for _ in 0..4000 {
        h.control.step();
        for (c, p) in h.control.commands().iter().zip(&prev) {
            assert!(
                (c.position_rad - p).abs() <= 3.46e-3 * 1.001,
                "set-point step"
            );
        }
        prev = h
            .control
            .commands()
            .iter()
            .map(|c| c.position_rad)
            .collect();
    }
    let snap = h.telemetry.latest();
    assert_eq!(snap.mode, Mode::Running);
    assert_eq!(snap.blend_progress, 1.0);
}

#[test]
fn hold_at_start_holds_the_measured_pose_until_a_gait_is_set() {
    let pose = [0.2f32; 8];
    let mut h = echo_harness(
        8,
        Some(&pose),
        GaitKind::Slithering,
        true,
        FailsafeConfig::default(),
    );
    steps(&mut h, 100);
    assert_eq!(h.telemetry.latest().mode, Mode::Hold);
    assert!(
        h.control
            .commands()
            .iter()
            .all(|c| (c.position_rad - 0.2).abs() < 1e-6)
    );
    assert_eq!(
        request(
            &mut h,
            1,
            LoopRequest::SetGait {
                gait: GaitKind::Rolling
            }
        ),
        Ok(())
    );
    steps(&mut h, 10);
    let snap = h.telemetry.latest();
    assert_eq!((snap.mode, snap.gait), (Mode::Running, GaitKind::Rolling));
}

#[test]
fn a_silent_module_holds_then_goes_limp_and_is_reported() {
    let cfg = FailsafeConfig {
        feedback_timeout_s: 0.05,
        limp_after_s: 0.5,
        ..FailsafeConfig::default()
    };
    let mut h = echo_harness(18, None, GaitKind::Sidewinding, false, cfg);
    steps(&mut h, 500);
    assert_eq!(h.telemetry.latest().mode, Mode::Running);
    h.faults.set_silent(7, true);
    steps(&mut h, 49);
    assert_eq!(
        h.telemetry.latest().mode,
        Mode::Running,
        "within the timeout"
    );
    steps(&mut h, 3);
    let snap = h.telemetry.latest();
    assert_eq!(
        (snap.mode, snap.reason),
        (Mode::Hold, Reason::FeedbackTimeout)
    );
    let held: Vec<f32> = h
        .control
        .commands()
        .iter()
        .map(|c| c.position_rad)
        .collect();
    steps(&mut h, 100);
    let still: Vec<f32> = h
        .control
        .commands()
        .iter()
        .map(|c| c.position_rad)
        .collect();
    assert_eq!(held, still, "hold freezes the set-points");
    steps(&mut h, 450);
    let snap = h.telemetry.latest();
    assert_eq!(
        (snap.mode, snap.reason),
        (Mode::Limp, Reason::FeedbackTimeout)
    );
    assert!(h.control.commands().iter().all(|c| c.is_limp()));
    assert!(snap.joints[7].feedback_age_s > 0.5);
    // Back, but not re-armed until the operator says so (auto_resume is off).
    h.faults.set_silent(7, false);
    steps(&mut h, 10);
    assert_eq!(h.telemetry.latest().mode, Mode::Limp);
    assert_eq!(request(&mut h, 1, LoopRequest::Arm), Ok(()));
    steps(&mut h, 2);
    assert_eq!(h.telemetry.latest().mode, Mode::Running);
}

#[test]
fn non_finite_feedback_holds() {
    let mut h = echo_harness(6, None, GaitKind::Rolling, false, FailsafeConfig::default());
    steps(&mut h, 50);
    h.faults.set_corrupt(2, true);
    steps(&mut h, 2);
    let snap = h.telemetry.latest();
    assert_eq!(
        (snap.mode, snap.reason),
        (Mode::Hold, Reason::NonFiniteFeedback)
    );
}

#[test]
fn estop_latches_and_only_arm_releases_it() {
    let mut h = echo_harness(6, None, GaitKind::Rolling, false, FailsafeConfig::default());
    steps(&mut h, 20);
    assert_eq!(request(&mut h, 1, LoopRequest::EStop), Ok(()));
    assert!(h.control.commands().iter().all(|c| c.is_limp()));
    assert_eq!(
        request(
            &mut h,
            2,
            LoopRequest::SetGait {
                gait: GaitKind::Sidewinding
            }
        ),
        Err(Rejection::Failsafe(Refusal::EStopLatched))
    );
    assert_eq!(
        request(&mut h, 3, LoopRequest::Hold),
        Err(Rejection::Failsafe(Refusal::EStopLatched))
    );
    assert_eq!(h.telemetry.latest().mode, Mode::EStop);
    assert_eq!(request(&mut h, 4, LoopRequest::Arm), Ok(()));
    steps(&mut h, 2);
    assert_eq!(h.telemetry.latest().mode, Mode::Running);
    assert_eq!(h.telemetry.latest().requests_refused, 2);
}

#[test]
fn invalid_params_are_refused_by_the_loop_too() {
    let mut h = echo_harness(6, None, GaitKind::Rolling, false, FailsafeConfig::default());
    steps(&mut h, 5);
    let patch = crate::gait::ParamPatch {
        amplitude_lat_rad: Some(f64::NAN),
        ..Default::default()
    };
    assert_eq!(
        request(
            &mut h,
            1,
            LoopRequest::SetParams {
                gait: GaitKind::Rolling,
                patch
            }
        ),
        Err(Rejection::InvalidParams)
    );
    assert_eq!(
        request(&mut h, 2, LoopRequest::SetBlendTime { blend_time_s: 1e9 }),
        Err(Rejection::InvalidParams)
    );
}

#[test]
fn stop_holds_then_goes_limp_then_finishes() {
    let mut h = echo_harness(
        6,
        None,
        GaitKind::Sidewinding,
        false,
        FailsafeConfig::default(),
    );
    steps(&mut h, 100);
    h.stop.store(true, std::sync::atomic::Ordering::Relaxed);
    h.control.step();
    assert_eq!(h.telemetry.latest().mode, Mode::Hold);
    let mut cycles = 1;
    while h.control.step() == Flow::Continue {
        cycles += 1;
        assert!(cycles < 5000, "the safe stop finishes");
    }
    assert!(h.control.commands().iter().all(|c| c.is_limp()));
    assert!(
        cycles >= 200,
        "held for shutdown_hold_s before going limp ({cycles} cycles)"
    );
}

#[test]
fn the_navigator_s_report_and_a_new_heading_do_not_restart_the_progress_monitor() {
    use crate::controller_interface::ControllerCommand;
    use crate::navigation::navigator::{Choice, Why};
    use crate::navigation::state::NavigatorState;
    let mut h = echo_harness(
        18,
        None,
        GaitKind::Slithering,
        false,
        FailsafeConfig::default(),
    );
    steps(&mut h, 3000);
    let measuring = |h: &Harness| h.control.progress().measuring_s;
    let before = measuring(&h);
    assert!(
        before > 0.5,
        "measuring for {before} s (since the blend ended)"
    );
    let state = NavigatorState {
        active: true,
        travel_rad: 0.4,
        choice: Some(Choice::Slither),
        why: Some(Why::Start),
        switches: 0,
        stopped: None,
        goal_m: Some([2.0, 0.5]),
        by_position: true,
        distance_m: 1.5,
        cross_track_m: 0.1,
    };
    assert_eq!(
        request(&mut h, 1, LoopRequest::Navigation { state }),
        Ok(())
    );
    assert_eq!(h.control.navigator(), state);
    let heading = ControllerCommand::SetHeading {
        heading_rad: Some(0.4),
    };
    let command = LoopRequest::ControllerCommand {
        gait: GaitKind::Slithering,
        command: heading,
    };
    assert_eq!(request(&mut h, 2, command), Ok(()));
    steps(&mut h, 1);
    assert!(measuring(&h) > before, "{} after {before}", measuring(&h));
    assert_eq!(h.telemetry.latest().navigator, state);
    // A new gait is measured afresh.
    let gait = LoopRequest::SetGait {
        gait: GaitKind::Sidewinding,
    };
    assert_eq!(request(&mut h, 3, gait), Ok(()));
    assert!(measuring(&h) < 0.01, "{}", measuring(&h));
}

fn positions(h: &Harness) -> Vec<f32> {
    h.control
        .commands()
        .iter()
        .map(|c| c.position_rad)
        .collect()
}

#[test]
fn a_controlled_stop_brings_every_joint_to_rest_within_its_time_whatever_the_blend() {
    let mut h = echo_harness(
        12,
        None,
        GaitKind::Rolling,
        false,
        FailsafeConfig::default(),
    );
    steps(&mut h, 2500);
    // The slowest blend there is, and a parameter change blending in over it.
    let long = LoopRequest::SetBlendTime { blend_time_s: 30.0 };
    assert_eq!(request(&mut h, 1, long), Ok(()));
    let patch = crate::gait::ParamPatch {
        temporal_freq_rad_s: Some(3.0),
        ..Default::default()
    };
    let faster = LoopRequest::SetParams {
        gait: GaitKind::Rolling,
        patch,
    };
    assert_eq!(request(&mut h, 2, faster), Ok(()));
    steps(&mut h, 500);
    let stop = LoopRequest::StopGait { within_s: 0.3 };
    assert_eq!(request(&mut h, 3, stop), Ok(()));
    let mut prev = positions(&h);
    let mut moved_at = Vec::new();
    for k in 1..=1000 {
        h.control.step();
        let now = positions(&h);
        let step = now
            .iter()
            .zip(&prev)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        if step > 0.0 {
            moved_at.push(k);
        }
        for c in h.control.commands() {
            assert!(c.velocity_rad_s.is_nan() || c.velocity_rad_s.abs() < 10.0);
        }
        prev = now;
    }
    let last = *moved_at.last().expect("it was moving when stopped");
    assert!(
        last <= 301,
        "at rest 0.3 s after the stop, moved until cycle {last}"
    );
    assert!(
        moved_at.len() > 100,
        "it decelerates, not freezes: {moved_at:?}"
    );
    let snap = h.telemetry.latest();
    assert_eq!(snap.motion, crate::rt::gait_clock::Motion::Stopped);
    assert_eq!(
        snap.mode,
        Mode::Running,
        "a stop is not a hold: no arm needed"
    );
    // It moves again on resume, from where it stood.
    let resume = LoopRequest::ResumeGait { within_s: 0.3 };
    assert_eq!(request(&mut h, 4, resume), Ok(()));
    steps(&mut h, 400);
    assert_ne!(positions(&h), prev, "moving again");
    assert_eq!(
        request(&mut h, 5, LoopRequest::StopGait { within_s: 9.0 }),
        Err(Rejection::InvalidParams)
    );
}

#[test]
fn an_estopped_loop_takes_no_change_of_what_runs_after_arm() {
    let mut h = echo_harness(6, None, GaitKind::Rolling, false, FailsafeConfig::default());
    steps(&mut h, 20);
    let before = h.telemetry.latest().params;
    assert_eq!(request(&mut h, 1, LoopRequest::EStop), Ok(()));
    let patch = crate::gait::ParamPatch {
        temporal_freq_rad_s: Some(0.3),
        ..Default::default()
    };
    let refused = Err(Rejection::Failsafe(Refusal::EStopLatched));
    let changes = [
        LoopRequest::SetParams {
            gait: GaitKind::Rolling,
            patch,
        },
        LoopRequest::ControllerCommand {
            gait: GaitKind::Rolling,
            command: crate::controller_interface::ControllerCommand::SetHeading {
                heading_rad: Some(1.0),
            },
        },
        LoopRequest::SetBlendTime { blend_time_s: 5.0 },
        LoopRequest::ResumeGait { within_s: 0.3 },
    ];
    for (k, r) in changes.into_iter().enumerate() {
        assert_eq!(request(&mut h, 10 + k as u64, r), refused, "{r:?}");
    }
    assert_eq!(request(&mut h, 20, LoopRequest::Arm), Ok(()));
    steps(&mut h, 2);
    assert_eq!(
        h.telemetry.latest().params,
        before,
        "nothing changed by the e-stop"
    );
}
