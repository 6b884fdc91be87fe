//! Controllers in the loop, over the echo bus: takeover, torques, hand-back,
//! replacement, parameters, the set-point guard.
//! Many tests run a twin loop without a controller beside the one with it: without
//! torques the two must send the same set-points (the takeover is seamless).
use crate::bus::echo::{EchoBus, TorqueModel};
use crate::controller_interface::Selection;
use crate::gait::{GaitKind, GaitTable, ParamPatch};
use crate::rt::controller_slots::{Engagement, Installed};
use crate::rt::harness::{Harness, PERIOD_NS, build_installed, echo_harness_on};
use crate::rt::messages::{Envelope, LoopRequest, Rejection};
use crate::safety::failsafe::FailsafeConfig;

const N: usize = 18;
/// Largest set-point step per cycle the loop allows (max joint speed × period).
pub(super) const MAX_STEP_RAD: f64 = 3.46e-3 * 1.001;

pub(super) fn table() -> GaitTable {
    let mut t = GaitTable::default();
    let s = t.get_mut(GaitKind::Slithering);
    // Steering offsets too: the controller's wave is added to them (within what every
    // controller takes: directional compliance's 1.5 rad windows leave 0.07 rad).
    s.offset_lat_rad = 0.05;
    s.offset_dor_rad = -0.05;
    t
}

pub(super) fn harness(torque: Option<TorqueModel>) -> Harness {
    let mut bus = EchoBus::new(N, PERIOD_NS);
    if let Some(m) = torque {
        bus = bus.with_torque(m);
    }
    let cfg = FailsafeConfig::default();
    echo_harness_on(bus, table(), GaitKind::Slithering, false, cfg)
}

/// Obstacles against the bend of joints 0, 4 and 8 (protocol sign: the reported torque
/// has the sign of the bend).
pub(super) fn pegs(i: usize, position_rad: f32) -> f32 {
    if i.is_multiple_of(4) && i <= 8 && position_rad.abs() > 0.05 {
        3.0 * position_rad.signum()
    } else {
        0.0
    }
}

/// The named controller of slithering for the harness's body and `table()`.
pub(super) fn build(h: &Harness, name: &str) -> Installed {
    let sel = Selection::named(name);
    build_installed(&h.catalog, &h.layout, &table(), GaitKind::Slithering, &sel)
}

pub(super) const SET: LoopRequest = LoopRequest::SetController {
    gait: GaitKind::Slithering,
};

/// Sends a request (with a controller) and runs the cycle that applies it.
pub(super) fn request(
    h: &mut Harness,
    request: LoopRequest,
    controller: Option<Installed>,
) -> Result<(), Rejection> {
    answer(h, request, controller).map(|_| ())
}

/// [`request`], with what became of the gait's controller.
pub(super) fn answer(
    h: &mut Harness,
    request: LoopRequest,
    controller: Option<Installed>,
) -> crate::rt::messages::LoopResult {
    let envelope = Envelope {
        ticket: 7,
        request,
        controller,
    };
    h.requests.try_send(envelope).expect("queue has room");
    h.control.step();
    h.acks.try_recv().expect("answered within the cycle").result
}

pub(super) fn setpoints(h: &Harness) -> Vec<f64> {
    h.control
        .commands()
        .iter()
        .map(|c| c.position_rad as f64)
        .collect()
}

pub(super) fn engagement(h: &Harness) -> Engagement {
    h.telemetry.latest().controller.engagement
}

/// The presets of the controllers the loop sent back, in order.
pub(super) fn retired(h: &Harness) -> Vec<&'static str> {
    h.retired
        .try_iter()
        .map(|c| h.catalog.get(c.id).expect("named").preset)
        .collect()
}

pub(super) fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Steps `h` (and `twin`, if given) `k` cycles; returns the largest set-point step of
/// `h` and the largest difference from the twin.
pub(super) fn run(h: &mut Harness, mut twin: Option<&mut Harness>, k: usize) -> (f64, f64) {
    let (mut step, mut diff) = (0.0f64, 0.0f64);
    let mut last = setpoints(h);
    for _ in 0..k {
        h.control.step();
        let now = setpoints(h);
        step = step.max(max_diff(&now, &last));
        if let Some(t) = twin.as_deref_mut() {
            t.control.step();
            diff = diff.max(max_diff(&now, &setpoints(t)));
        }
        last = now;
    }
    (step, diff)
}

#[test]
fn every_gait_runs_its_open_loop_controller_exactly_as_the_selector() {
    // The harness installs `open_loop` for every gait, as the daemon does.
    let mut h = harness(None);
    run(&mut h, None, 100);
    for gait in GaitKind::ALL {
        request(&mut h, LoopRequest::SetGait { gait }, None).unwrap();
        run(&mut h, None, 2100);
        let snap = h.telemetry.latest();
        assert_eq!(snap.controller.engagement, Engagement::Engaged, "{gait:?}");
        let info = h.catalog.get(snap.controller.active_id).unwrap();
        assert_eq!((info.controller, info.gait), ("open_loop", gait));
        // Driving, it continues the selector's serpenoid: the selector (still
        // updated every cycle) and the controller agree.
        let (step, _) = run(&mut h, None, 500);
        assert!(step <= MAX_STEP_RAD, "{gait:?}: {step}");
        assert_eq!(snap.guard.non_finite, 0);
    }
}

#[test]
fn a_controller_takes_over_seamlessly_and_without_torque_sends_the_serpenoid() {
    let (mut h, mut twin) = (harness(None), harness(None));
    run(&mut h, Some(&mut twin), 2500);
    assert_eq!(engagement(&h), Engagement::Engaged, "open loop drives");
    let c = build(&h, "a_ws_omega");
    assert_eq!(request(&mut h, SET, Some(c)), Ok(()));
    twin.control.step();
    // The selector blends from what was sent into the gait, then it takes over.
    assert_eq!(engagement(&h), Engagement::Waiting);
    let (_, diff) = run(&mut h, Some(&mut twin), 1999);
    assert!(diff < 1e-5, "the hand-back blend moved nothing: {diff}");
    run(&mut h, Some(&mut twin), 2);
    assert_eq!(engagement(&h), Engagement::Engaged);
    let (step, diff) = run(&mut h, Some(&mut twin), 3000);
    let snap = h.telemetry.latest();
    assert_eq!(snap.controller.takeovers, 1);
    assert!(
        snap.controller.report.signals[2].abs() < 1e-9,
        "no phase lag"
    );
    assert!(diff < 1e-5, "differs from the open-loop gait by {diff} rad");
    assert!(
        step < 1e-3,
        "largest step {step} rad (the wave moves ≤ A·ωT·dt)"
    );
}

#[test]
fn a_controller_installed_mid_blend_waits_and_takes_over_at_its_end() {
    let (mut h, mut twin) = (harness(None), harness(None));
    run(&mut h, Some(&mut twin), 500);
    let c = build(&h, "a_ws_omega_central");
    assert_eq!(request(&mut h, SET, Some(c)), Ok(()));
    twin.control.step();
    run(&mut h, Some(&mut twin), 1400);
    assert_eq!(engagement(&h), Engagement::Waiting);
    let (_, diff) = run(&mut h, Some(&mut twin), 200);
    assert_eq!(engagement(&h), Engagement::Engaged);
    assert!(diff < 1e-5, "{diff}");
}

#[test]
fn torques_reported_by_the_bus_shape_the_wave() {
    let (mut h, mut twin) = (harness(Some(pegs)), harness(Some(pegs)));
    run(&mut h, Some(&mut twin), 100);
    let c = build(&h, "a_ws_omega");
    request(&mut h, SET, Some(c)).unwrap();
    twin.control.step();
    let (step, diff) = run(&mut h, Some(&mut twin), 6000);
    assert!(diff > 0.05, "the torques changed nothing ({diff} rad)");
    assert!(step <= MAX_STEP_RAD, "{step}");
    let r = h.telemetry.latest().controller.report;
    let amp = &r.fields[0];
    let nominal = table().get(GaitKind::Slithering).amplitude_lat_rad;
    assert!(
        amp.columns[1][..amp.len()].iter().any(|f| f.abs() > 0.05),
        "{amp:?}"
    );
    assert!(
        amp.columns[0][..amp.len()]
            .iter()
            .any(|v| (v - nominal).abs() > 0.02),
        "{amp:?}"
    );
    assert!(r.signals[2].abs() > 1e-3, "the phase complies too");
}

#[test]
fn another_gait_takes_the_joints_back_smoothly() {
    let (mut h, mut twin) = (harness(Some(pegs)), harness(Some(pegs)));
    run(&mut h, Some(&mut twin), 100);
    let c = build(&h, "a_ws_omega");
    request(&mut h, SET, Some(c)).unwrap();
    twin.control.step();
    let (_, diff) = run(&mut h, Some(&mut twin), 5000);
    assert!(diff > 0.05, "{diff}");
    let side = LoopRequest::SetGait {
        gait: GaitKind::Sidewinding,
    };
    request(&mut h, side, None).unwrap();
    request(&mut twin, side, None).unwrap();
    assert_eq!(
        engagement(&h),
        Engagement::Waiting,
        "sidewinding's open loop waits"
    );
    let (step, _) = run(&mut h, Some(&mut twin), 1000);
    // Well inside the slew limit: a blend, not a clamped jump.
    assert!(step < 2e-3, "{step}");
    // Once the blend is over both run the same sidewinding (the re-sync's cycle
    // advances no phase: 1 ms of ωT behind).
    run(&mut h, Some(&mut twin), 1100);
    let (_, diff) = run(&mut h, Some(&mut twin), 400);
    assert!(diff < 1.5e-3, "{diff}");
    // Back to slithering: the controller takes over again after the blend.
    request(
        &mut h,
        LoopRequest::SetGait {
            gait: GaitKind::Slithering,
        },
        None,
    )
    .unwrap();
    run(&mut h, None, 2100);
    let c = h.telemetry.latest().controller;
    assert_eq!((c.engagement, c.takeovers), (Engagement::Engaged, 2));
}

#[test]
fn a_replaced_controller_goes_back() {
    let mut h = harness(Some(pegs));
    run(&mut h, None, 100);
    {
        let c = build(&h, "a");
        request(&mut h, SET, Some(c))
    }
    .unwrap();
    run(&mut h, None, 3000);
    assert_eq!(engagement(&h), Engagement::Engaged);
    let c = build(&h, "cpg");
    let cpg_id = c.id;
    request(&mut h, SET, Some(c)).unwrap();
    assert_eq!(
        engagement(&h),
        Engagement::Waiting,
        "the selector blends first"
    );
    let (step, _) = run(&mut h, None, 2100);
    assert!(step <= MAX_STEP_RAD, "{step}");
    let snap = h.telemetry.latest();
    assert_eq!(snap.controller.active_id, cpg_id);
    assert_eq!(snap.controller.engagement, Engagement::Engaged);
    {
        let c = build(&h, "open_loop");
        request(&mut h, SET, Some(c))
    }
    .unwrap();
    let (step, _) = run(&mut h, None, 2500);
    assert!(step <= MAX_STEP_RAD, "{step}");
    assert_eq!(engagement(&h), Engagement::Engaged);
    assert_eq!(
        retired(&h),
        ["default", "a", "default"],
        "open loop, a, the CPG"
    );
    assert_eq!(h.telemetry.latest().controller.freed_in_loop, 0);
}

#[test]
fn parameters_are_checked_against_the_gait_s_controller() {
    let mut h = harness(None);
    run(&mut h, None, 100);
    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.6),
        ..ParamPatch::default()
    };
    let set = LoopRequest::SetParams {
        gait: GaitKind::Slithering,
        patch,
    };
    assert_eq!(request(&mut h, set, None), Ok(()), "open loop follows any");
    assert_eq!(request(&mut h, SET, None), Err(Rejection::NoController));
    {
        let c = build(&h, "a_ws");
        request(&mut h, SET, Some(c))
    }
    .unwrap();
    // ωS beyond a_ws's compliance range: refused by the controller, table unchanged.
    let wide = LoopRequest::SetParams {
        gait: GaitKind::Slithering,
        patch: ParamPatch {
            spatial_freq_rad: Some(4.5 * std::f64::consts::PI),
            ..ParamPatch::default()
        },
    };
    match request(&mut h, wide, None) {
        Err(Rejection::ControllerRefuses(m)) => assert_eq!(m.field, "spatial_freq_rad"),
        other => panic!("{other:?}"),
    }
    // With a controller that follows it, attached: both change together.
    assert_eq!(
        {
            let c = build(&h, "a");
            request(&mut h, wide, Some(c))
        },
        Ok(())
    );
    // A refused request's controller and one attached to another request come back.
    let bad = ParamPatch {
        amplitude_lat_rad: Some(f64::NAN),
        ..ParamPatch::default()
    };
    let bad = LoopRequest::SetParams {
        gait: GaitKind::Slithering,
        patch: bad,
    };
    assert_eq!(
        {
            let c = build(&h, "cpg");
            request(&mut h, bad, Some(c))
        },
        Err(Rejection::InvalidParams)
    );
    {
        let c = build(&h, "a_ws_omega");
        request(&mut h, LoopRequest::Hold, Some(c))
    }
    .unwrap();
    assert_eq!(retired(&h), ["default", "a_ws", "default", "a_ws_omega"]);
    let snap = h.telemetry.latest();
    let active = h.catalog.get(snap.controller.active_id).unwrap();
    assert_eq!(active.preset, "a");
    let p = snap.params.get(GaitKind::Slithering);
    assert_eq!(
        (p.amplitude_lat_rad, p.spatial_freq_rad),
        (0.6, 4.5 * std::f64::consts::PI)
    );
}

/// A registered controller that, `after_s` into its engagement, sends a NaN at one
/// joint (what an unguarded bug or a runaway parameter would do).
struct Poisoned {
    inner: Box<dyn crate::controller_interface::Controller>,
    after_s: f64,
    t0: f64,
}

impl crate::controller_interface::Controller for Poisoned {
    fn accepts(
        &self,
        p: &crate::gait::GaitParams,
    ) -> Result<(), crate::controller_interface::NominalMismatch> {
        self.inner.accepts(p)
    }
    fn engage(&mut self, h: &crate::controller_interface::Handover<'_>) {
        self.t0 = h.t_s;
        self.inner.engage(h);
    }
    fn step(
        &mut self,
        tick: crate::controller_interface::Tick,
        obs: &crate::controller_interface::Observation<'_>,
        out: &mut [f64],
    ) {
        let t = tick.t_s;
        self.inner.step(tick, obs, out);
        if t - self.t0 >= self.after_s {
            out[3] = f64::NAN;
        }
    }
    fn report(&self, out: &mut crate::controller_interface::report::ControllerReport) {
        self.inner.report(out);
    }
}

#[test]
fn a_non_finite_set_point_from_any_registered_controller_holds_with_the_reason() {
    use crate::controller_interface::registry::{BuildContext, for_gait};
    use crate::controllers::REGISTRY;
    use crate::safety::failsafe::{Mode, Reason};
    let mut checked = 0;
    for gait in GaitKind::ALL {
        let ctx_table = table();
        for family in for_gait(REGISTRY, gait) {
            for (preset, _) in family.presets() {
                let mut h = harness(None);
                let ctx = BuildContext {
                    gait,
                    layout: &h.layout,
                    params: ctx_table.get(gait),
                };
                let built = family.build(preset, None, &ctx).unwrap();
                let what = format!("{gait:?} {}/{preset}", family.name());
                run(&mut h, None, 100);
                request(&mut h, LoopRequest::SetGait { gait }, None).unwrap();
                let poisoned = Installed {
                    id: 99,
                    controller: Box::new(Poisoned {
                        inner: built.controller,
                        after_s: 0.3,
                        t0: 0.0,
                    }),
                };
                request(&mut h, LoopRequest::SetController { gait }, Some(poisoned)).unwrap();
                run(&mut h, None, 2100);
                assert_eq!(engagement(&h), Engagement::Engaged, "{what}");
                let sent = setpoints(&h);
                run(&mut h, None, 400);
                let snap = h.telemetry.latest();
                assert_eq!(
                    (snap.mode, snap.reason),
                    (Mode::Hold, Reason::NonFiniteSetpoint),
                    "{what}"
                );
                assert_eq!(snap.guard.non_finite, 1, "{what}");
                // Held, not limp: every joint still driven, at finite set-points near
                // where it was, and it stays so.
                let (step, _) = run(&mut h, None, 1000);
                let held = setpoints(&h);
                assert!(held.iter().all(|x| x.is_finite()), "{what}: {held:?}");
                assert!(max_diff(&held, &sent) < 1.0, "{what}");
                assert_eq!(step, 0.0, "{what}: held still");
                assert_eq!(h.telemetry.latest().mode, Mode::Hold, "{what}");
                checked += 1;
            }
        }
    }
    assert!(checked >= 13, "every family's presets: {checked}");
}

/// A controller that makes its own way into its gait (the rolling helix getting on a
/// pole) takes over at the switch, from where the joints were, and moves them no
/// faster than the loop allows; one that does not waits for the blend's end.
#[test]
fn a_controller_that_makes_its_own_way_takes_over_at_the_switch() {
    let mut h = harness(None);
    run(&mut h, None, 3000);
    let helix = GaitKind::RollingHelix;
    // Installed one after the other: the open-loop controller replaces helix_radius.
    for preset in ["windowed_adaptive", "open_loop"] {
        let sel = Selection::named(preset);
        let c = build_installed(&h.catalog, &h.layout, &table(), helix, &sel);
        assert_eq!(
            request(&mut h, LoopRequest::SetController { gait: helix }, Some(c)),
            Ok(())
        );
    }
    let before = setpoints(&h);
    assert_eq!(
        request(&mut h, LoopRequest::SetGait { gait: helix }, None),
        Ok(())
    );
    let (step, _) = run(&mut h, None, 1);
    assert!(max_diff(&setpoints(&h), &before) <= MAX_STEP_RAD, "no jump");
    assert!(step <= MAX_STEP_RAD);
    // The open-loop controller was installed last: it replaced helix_radius and waits.
    assert_eq!(engagement(&h), Engagement::Waiting);
    let sel = Selection::named("windowed_adaptive");
    let c = build_installed(&h.catalog, &h.layout, &table(), helix, &sel);
    assert_eq!(
        request(&mut h, LoopRequest::SetController { gait: helix }, Some(c)),
        Ok(())
    );
    assert_eq!(engagement(&h), Engagement::Engaged, "engaged mid-blend");
    let (step, _) = run(&mut h, None, 4000);
    assert!(step <= MAX_STEP_RAD, "{step}");
}
