//! The real-time path allocates nothing: a counting global allocator watches whole
//! control cycles (feedback, requests, failsafe, gait blend, compliant controllers,
//! commands, telemetry). Allocations and frees are counted per thread, so the tests
//! can run in parallel.

use snaked::bus::echo::EchoBus;
use snaked::gait::{GaitKind, GaitTable, ParamPatch};
use snaked::rt::compliance::{ComplianceSetting, ControllerChange, Engagement};
use snaked::rt::harness::{Harness, PERIOD_NS, echo_harness, echo_harness_on};
use snaked::rt::messages::{Envelope, LoopRequest};
use snaked::safety::failsafe::{FailsafeConfig, Mode};

#[path = "support/counting_alloc.rs"]
mod counting_alloc;
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
        LoopRequest::SetGait(GaitKind::Slithering),
        LoopRequest::SetParams(
            GaitKind::Slithering,
            ParamPatch {
                temporal_freq_rad_s: Some(1.0),
                ..Default::default()
            },
        ),
        LoopRequest::Hold,
        LoopRequest::Arm,
        LoopRequest::SetGait(GaitKind::RollingHelix),
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

/// A compliant controller takes over (windows born and dropped, torques shaping
/// them), is replaced, hands back to another gait and to hold, takes over again; then
/// the CPG, then open loop. None of it allocates or frees in the loop: controllers are
/// built before and freed after, off the loop.
#[test]
fn compliant_slithering_allocates_nothing() {
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
    let params = *table.get(GaitKind::Slithering);
    let build = |name: &str| {
        ComplianceSetting::named(name)
            .unwrap()
            .build(&h.layout, &params)
            .unwrap()
    };
    let mut changes = vec![
        build("a_ws_omega"),
        build("a_ws_omega_per_joint"),
        build("cpg"),
        ControllerChange::OpenLoop,
    ]
    .into_iter();
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
    let full = changes.next();
    calls += allocator_calls(|| {
        send(&mut h, LoopRequest::SetCompliance, full);
        steps(&mut h, 7000);
    });
    let snap = h.telemetry.latest();
    let c = &snap.compliance;
    assert_eq!(
        (c.setting.controller, c.engagement),
        ("a_ws_omega", Engagement::Engaged)
    );
    assert!(c.windows_born >= 2 && c.windows_dropped >= 2, "{c:?}");
    let forces = &c.report.fields[0].force[..c.report.fields[0].len()];
    assert!(forces.iter().any(|f| f.abs() > 0.01), "{forces:?}");

    let per_joint = changes.next();
    calls += allocator_calls(|| {
        send(&mut h, LoopRequest::SetCompliance, per_joint);
        steps(&mut h, 2500);
        send(&mut h, LoopRequest::SetGait(GaitKind::Rolling), None);
        steps(&mut h, 700);
        send(&mut h, LoopRequest::SetGait(GaitKind::Slithering), None);
        steps(&mut h, 2500);
        send(&mut h, LoopRequest::Hold, None);
        steps(&mut h, 100);
        send(&mut h, LoopRequest::Arm, None);
        steps(&mut h, 2500);
    });
    let snap = h.telemetry.latest();
    assert_eq!(snap.mode, Mode::Running);
    let c = &snap.compliance;
    assert_eq!(
        (c.setting.controller, c.engagement),
        ("a_ws_omega_per_joint", Engagement::Engaged)
    );
    assert_eq!(
        c.takeovers, 3,
        "after the swap, back from rolling, after hold"
    );

    let (cpg, open) = (changes.next(), changes.next());
    calls += allocator_calls(|| {
        send(&mut h, LoopRequest::SetCompliance, cpg);
        steps(&mut h, 2500);
        send(&mut h, LoopRequest::SetCompliance, open);
        steps(&mut h, 500);
        while h.acks.try_recv().is_ok() {}
    });
    assert_eq!(calls, 0, "{calls} allocator calls in the real-time path");
    let snap = h.telemetry.latest();
    assert_eq!(snap.compliance.engagement, Engagement::Off);
    assert_eq!(snap.compliance.freed_in_loop, 0);
    let retired: Vec<_> = h.retired.try_iter().map(|c| c.name()).collect();
    assert_eq!(retired, ["a_ws_omega", "a_ws_omega_per_joint", "cpg"]);
}
