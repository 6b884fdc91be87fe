//! The daemon's own loop over the HEBI bus, paced in real time: over HEBI's imitation
//! group (the library's thread delivering the feedback) it runs the gait, and the
//! failsafe holds and then goes limp when the group's feedback stream stops; over the
//! fake group, what the imitation cannot show (e-stop, a lost module, a missing IMU).

use crate::gait::{GaitKind, GaitTable};
use crate::rt::harness::{Harness, harness_on_bus};
use crate::rt::pacer::RealTimePacer;
use crate::safety::failsafe::{FailsafeConfig, Mode, Reason};

fn steps(h: &mut Harness, k: usize) {
    for _ in 0..k {
        h.control.step();
    }
}

/// The daemon's loop over `bus` in real time, slithering.
fn real_time_loop(bus: Box<dyn crate::bus::Bus>) -> Harness {
    let failsafe = FailsafeConfig {
        // Generous: a loaded CI machine must not starve the library's thread (or the
        // loop) into a hold while feedback flows.
        feedback_timeout_s: 0.2,
        limp_after_s: 0.3,
        auto_resume: false,
        shutdown_hold_s: 0.05,
    };
    let pacer = Box::new(RealTimePacer::new(crate::rt::harness::PERIOD_NS));
    let (table, gait) = (GaitTable::default(), GaitKind::Slithering);
    harness_on_bus(bus, pacer, table, gait, false, failsafe, 16)
}

#[test]
fn the_loop_drives_an_imitation_group_and_the_failsafe_catches_a_stalled_stream() {
    let bus = crate::bus::hebi::tests::imitation_bus(18);
    let switch = bus.feedback_switch();
    let mut h = real_time_loop(Box::new(bus));
    steps(&mut h, 800);
    assert_eq!(h.control.mode(), Mode::Running);
    // The imitation echoes the loop's commands: the feedback follows the gait.
    let c = h.control.bus().counters();
    assert!(c.feedback_received > 18 * 400, "{c:?}");
    let commands = h.control.commands().to_vec();
    assert!(
        commands.iter().any(|c| c.position_rad.abs() > 0.01),
        "the gait moves"
    );
    let s = h.control.stats().report();
    assert!(s.bus_io.count >= 800);

    // The stream stops: hold within the feedback timeout (plus a few periods), then
    // limp after limp_after_s.
    switch.set_rate_hz(0.0);
    let stalled = std::time::Instant::now();
    let mut held_after = None;
    for k in 0..600 {
        h.control.step();
        if h.control.mode() == Mode::Hold {
            held_after = Some(k);
            break;
        }
    }
    let held_after = held_after.expect("held when the feedback stopped");
    // Not before the timeout (a lower bound a loaded machine cannot break).
    let waited = stalled.elapsed().as_secs_f64();
    assert!(
        waited >= 0.18,
        "held {waited} s after the stall ({held_after} cycles)"
    );
    let telemetry = h.telemetry.latest();
    assert_eq!(telemetry.reason, Reason::FeedbackTimeout);
    steps(&mut h, 400);
    assert_eq!(h.control.mode(), Mode::Limp);
    assert!(h.control.commands().iter().all(|c| c.is_limp()));

    // The stream comes back; the robot stays limp until the operator arms.
    switch.set_rate_hz(1000.0);
    steps(&mut h, 100);
    assert_eq!(h.control.mode(), Mode::Limp);
}

/// The loop over the fake group, in real time: what an imitation group cannot show.
fn fake_loop(n: usize) -> (Harness, std::sync::Arc<crate::bus::hebi::fake::FakeControl>) {
    let (bus, control) = crate::bus::hebi::tests::fake_bus(n, (0..n).collect());
    // The fake answers each command at once, so its feedback is fresh in real time.
    (real_time_loop(Box::new(bus)), control)
}

#[test]
fn e_stop_reaches_the_modules_as_explicit_limp_commands() {
    use crate::rt::messages::{Envelope, LoopRequest};
    let (mut h, control) = fake_loop(6);
    steps(&mut h, 200);
    assert_eq!(h.control.mode(), Mode::Running);
    let before = control.log.lock().unwrap().limp_commands;
    h.requests
        .try_send(Envelope::new(1, LoopRequest::EStop))
        .unwrap();
    steps(&mut h, 5);
    assert_eq!(h.control.mode(), Mode::EStop);
    let log = control.log.lock().unwrap().clone();
    assert!(log.limp_commands >= before + 4, "{log:?}");
    assert!(log.last_commands.iter().all(|c| c.is_limp()));
    // The lifetime the modules were given stops them if the daemon dies now.
    assert_eq!(
        control
            .lifetime_ms
            .load(std::sync::atomic::Ordering::Relaxed),
        50
    );
}

#[test]
fn a_module_lost_while_running_holds_then_goes_limp() {
    use std::sync::atomic::Ordering::Relaxed;
    let (mut h, control) = fake_loop(6);
    steps(&mut h, 200);
    assert_eq!(h.control.mode(), Mode::Running);
    control.lost[4].store(true, Relaxed);
    let lost = std::time::Instant::now();
    let mut held = false;
    for _ in 0..1000 {
        h.control.step();
        if h.control.mode() == Mode::Hold {
            held = true;
            break;
        }
    }
    assert!(held, "held when module 4 stopped answering");
    assert!(lost.elapsed().as_secs_f64() >= 0.18);
    assert_eq!(h.telemetry.latest().reason, Reason::FeedbackTimeout);
    assert!(h.control.bus().counters().feedback_lost > 0);
    steps(&mut h, 400);
    assert_eq!(h.control.mode(), Mode::Limp);
}

#[test]
fn a_missing_imu_is_invalid_input_never_a_number() {
    use std::sync::atomic::Ordering::Relaxed;
    let (mut h, control) = fake_loop(6);
    steps(&mut h, 200);
    assert_eq!(h.control.mode(), Mode::Running);
    control.no_imu[2].store(true, Relaxed);
    steps(&mut h, 5);
    assert_eq!(h.control.mode(), Mode::Hold);
    assert_eq!(h.telemetry.latest().reason, Reason::NonFiniteFeedback);
}
