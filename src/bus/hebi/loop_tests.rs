//! The daemon's own loop over HEBI's imitation group (the library's thread delivering
//! the feedback), paced in real time: it runs the gait, and the failsafe holds and then
//! goes limp when the group's feedback stream stops.

use crate::gait::{GaitKind, GaitTable};
use crate::rt::harness::{Harness, harness_on_bus};
use crate::rt::pacer::RealTimePacer;
use crate::safety::failsafe::{FailsafeConfig, Mode, Reason};

fn steps(h: &mut Harness, k: usize) {
    for _ in 0..k {
        h.control.step();
    }
}

#[test]
fn the_loop_drives_an_imitation_group_and_the_failsafe_catches_a_stalled_stream() {
    let bus = super::tests::imitation_bus(18);
    let switch = bus.feedback_switch();
    let failsafe = FailsafeConfig {
        // Generous: a loaded CI machine must not starve the library's thread into a
        // hold while the stream runs.
        feedback_timeout_s: 0.2,
        limp_after_s: 0.3,
        auto_resume: false,
        shutdown_hold_s: 0.05,
    };
    let pacer = Box::new(RealTimePacer::new(crate::rt::harness::PERIOD_NS));
    let mut h = harness_on_bus(
        Box::new(bus),
        pacer,
        GaitTable::default(),
        GaitKind::Slithering,
        false,
        failsafe,
        16,
    );
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
