//! The real-time path allocates nothing: a counting global allocator watches whole
//! control cycles (feedback, requests, failsafe, gait blend, compliant controllers,
//! commands, telemetry). Allocations and frees are counted per thread, so the tests
//! can run in parallel.

use snaked::bus::echo::EchoBus;
use snaked::controller_interface::registry::{BuildContext, for_gait};
use snaked::controllers::REGISTRY;
use snaked::gait::{GaitKind, GaitTable, ParamPatch};
use snaked::rt::controller_slots::{Engagement, Installed};
use snaked::rt::harness::{Harness, PERIOD_NS, echo_harness, echo_harness_on};
use snaked::rt::messages::{Envelope, LoopRequest};
use snaked::safety::failsafe::{FailsafeConfig, Mode};

use crate::support::counting_alloc;
use counting_alloc::allocator_calls;

fn steps(h: &mut Harness, k: usize) {
    for _ in 0..k {
        h.control.step();
    }
}

#[test]
fn control_cycles_allocate_nothing() {
    let mut h = echo_harness(
        18,
        None,
        GaitKind::Sidewinding,
        false,
        FailsafeConfig::default(),
    );
    steps(&mut h, 100);
    assert!(
        allocator_calls(|| drop(std::hint::black_box(vec![1u8; 8]))) >= 2,
        "the counter counts"
    );
    let reqs = [
        LoopRequest::SetGait {
            gait: GaitKind::Slithering,
        },
        LoopRequest::SetParams {
            gait: GaitKind::Slithering,
            patch: ParamPatch {
                temporal_freq_rad_s: Some(1.0),
                ..Default::default()
            },
        },
        LoopRequest::StopGait { within_s: 0.3 },
        LoopRequest::ResumeGait { within_s: 0.3 },
        LoopRequest::Hold,
        LoopRequest::Arm,
        LoopRequest::SetGait {
            gait: GaitKind::RollingHelix,
        },
    ];
    let n = allocator_calls(|| {
        for (k, r) in reqs.iter().enumerate() {
            h.requests.try_send(Envelope::new(k as u64, *r)).unwrap();
            steps(&mut h, 700);
            let _ = h.acks.try_recv();
        }
        h.faults.set_silent(3, true);
        steps(&mut h, 1000);
    });
    assert_eq!(n, 0, "{n} allocator calls in the real-time path");
    // The loop really did go through those states.
    assert!(h.telemetry.latest().cycle > 4000);
}

/// Environment torques against the bend on every other lateral joint.
fn pegs(i: usize, position_rad: f32) -> f32 {
    if i.is_multiple_of(4) && position_rad.abs() > 0.05 {
        2.0 * position_rad.signum()
    } else {
        0.0
    }
}

/// Every registered controller, every preset, on every gait it runs: installed while
/// running, taking over after the hand-back blend, stepped with torques coming in
/// (windows born and dropped), replaced by the next; for compliant slithering also
/// handing back to another gait and to hold, and taking over again. None of it
/// allocates or frees in the loop: controllers are built before and freed after.
#[test]
fn every_registered_controller_in_the_loop_allocates_nothing() {
    let mut table = GaitTable::default();
    // A faster wave: windows are born and dropped every ~1 s.
    table.get_mut(GaitKind::Slithering).temporal_freq_rad_s = 3.0;
    let bus = EchoBus::new(18, PERIOD_NS).with_torque(pegs);
    let mut h = echo_harness_on(
        bus,
        table,
        GaitKind::Slithering,
        false,
        FailsafeConfig::default(),
    );
    steps(&mut h, 100);
    let mut ticket = 0;
    let mut send = |h: &mut Harness, request: LoopRequest, controller| {
        ticket += 1;
        let envelope = Envelope {
            ticket,
            request,
            controller,
        };
        h.requests.try_send(envelope).unwrap();
    };
    let mut calls = 0;
    let mut runs = 0;
    let layout = h.layout.clone();
    for gait in GaitKind::ALL {
        let ctx = BuildContext {
            gait,
            layout: &layout,
            params: table.get(gait),
        };
        calls += allocator_calls(|| {
            send(&mut h, LoopRequest::SetGait { gait }, None);
            steps(&mut h, 2100);
        });
        for family in for_gait(REGISTRY, gait) {
            for (preset, _) in family.presets() {
                let built = family.build(preset, None, &ctx).unwrap();
                let info = h.catalog.insert(built.info);
                let c = Installed {
                    id: info.id,
                    controller: built.controller,
                };
                let compliant = family.name() == "compliant_slithering";
                calls += allocator_calls(|| {
                    send(&mut h, LoopRequest::SetController { gait }, Some(c));
                    steps(&mut h, 4500);
                    // A controlled stop and a restart: the controller keeps driving
                    // through ticks of (nearly) no time, its set-points finite.
                    send(&mut h, LoopRequest::StopGait { within_s: 0.3 }, None);
                    steps(&mut h, 500);
                    send(&mut h, LoopRequest::ResumeGait { within_s: 0.3 }, None);
                    steps(&mut h, 500);
                    if compliant && *preset == "a_ws_omega" {
                        send(
                            &mut h,
                            LoopRequest::SetGait {
                                gait: GaitKind::Rolling,
                            },
                            None,
                        );
                        steps(&mut h, 700);
                        send(&mut h, LoopRequest::SetGait { gait }, None);
                        steps(&mut h, 2500);
                        send(&mut h, LoopRequest::Hold, None);
                        steps(&mut h, 100);
                        send(&mut h, LoopRequest::Arm, None);
                        steps(&mut h, 2500);
                    }
                    while h.acks.try_recv().is_ok() {}
                });
                let snap = h.telemetry.latest();
                let what = format!("{gait:?} {}/{preset}", family.name());
                assert_eq!(snap.mode, Mode::Running, "{what}");
                let ctl = &snap.controller;
                assert_eq!(
                    (ctl.active_id, ctl.engagement),
                    (info.id, Engagement::Engaged),
                    "{what}"
                );
                if compliant && *preset == "a_ws_omega" {
                    assert_eq!(ctl.takeovers, 3, "after install, back from rolling, hold");
                    let born = ctl.report.signals[4];
                    assert!(
                        born >= 1.0,
                        "windows were born since the last takeover: {born}"
                    );
                }
                assert_eq!(snap.guard.non_finite, 0, "{what}");
                // Freed here, off the loop.
                while let Ok(old) = h.retired.try_recv() {
                    drop(old);
                }
                runs += 1;
            }
        }
    }
    assert_eq!(calls, 0, "{calls} allocator calls in the real-time path");
    assert!(runs >= 13, "every family's presets: {runs}");
    assert_eq!(h.telemetry.latest().controller.freed_in_loop, 0);
}
