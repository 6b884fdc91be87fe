//! Compliant slithering in the loop, over the echo bus: takeover, torques, hand-back.
//! Many tests run a twin loop without a controller beside the one with it: without
//! torques the two must send the same set-points (the takeover is seamless).
use crate::bus::echo::{EchoBus, TorqueModel};
use crate::gait::{BodyLayout, GaitKind, GaitTable, ParamPatch, Plane};
use crate::rt::compliance::{ComplianceSetting, ControllerChange, Engagement};
use crate::rt::harness::{Harness, MODULE_LENGTH_M, PERIOD_NS, echo_harness_on};
use crate::rt::messages::{Envelope, LoopRequest, Rejection};
use crate::safety::failsafe::FailsafeConfig;

const N: usize = 18;
/// Largest set-point step per cycle the loop allows (max joint speed × period).
const MAX_STEP_RAD: f64 = 3.46e-3 * 1.001;

fn table() -> GaitTable {
    let mut t = GaitTable::default();
    let s = t.get_mut(GaitKind::Slithering);
    // Steering offsets too: the controller's wave is added to them.
    s.offset_lat_rad = 0.1;
    s.offset_dor_rad = -0.05;
    t
}

fn harness(torque: Option<TorqueModel>) -> Harness {
    let mut bus = EchoBus::new(N, PERIOD_NS);
    if let Some(m) = torque {
        bus = bus.with_torque(m);
    }
    let cfg = FailsafeConfig::default();
    echo_harness_on(bus, table(), GaitKind::Slithering, false, cfg)
}

/// Obstacles against the bend of joints 0, 4 and 8 (protocol sign: the reported torque
/// has the sign of the bend).
fn pegs(i: usize, position_rad: f32) -> f32 {
    if i.is_multiple_of(4) && i <= 8 && position_rad.abs() > 0.05 {
        3.0 * position_rad.signum()
    } else {
        0.0
    }
}

/// The named controller for the harness's body and `table()`'s slithering.
fn build(name: &str) -> ControllerChange {
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let params = *table().get(GaitKind::Slithering);
    ComplianceSetting::named(name)
        .unwrap()
        .build(&layout, &params)
        .unwrap()
}

/// Sends a request (with a controller change) and runs the cycle that applies it.
fn request(
    h: &mut Harness,
    request: LoopRequest,
    controller: Option<ControllerChange>,
) -> Result<(), Rejection> {
    let envelope = Envelope {
        ticket: 7,
        request,
        controller,
    };
    h.requests.try_send(envelope).expect("queue has room");
    h.control.step();
    h.acks.try_recv().expect("answered within the cycle").result
}

fn setpoints(h: &Harness) -> Vec<f64> {
    h.control
        .commands()
        .iter()
        .map(|c| c.position_rad as f64)
        .collect()
}

fn engagement(h: &Harness) -> Engagement {
    h.telemetry.latest().compliance.engagement
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Steps `h` (and `twin`, if given) `k` cycles; returns the largest set-point step of
/// `h` and the largest difference from the twin.
fn run(h: &mut Harness, mut twin: Option<&mut Harness>, k: usize) -> (f64, f64) {
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
fn a_controller_takes_over_seamlessly_and_without_torque_sends_the_serpenoid() {
    let (mut h, mut twin) = (harness(None), harness(None));
    run(&mut h, Some(&mut twin), 2500);
    let c = build("a_ws_omega");
    assert_eq!(request(&mut h, LoopRequest::SetCompliance, Some(c)), Ok(()));
    twin.control.step();
    // The start-up blend is over: it takes over at once.
    assert_eq!(engagement(&h), Engagement::Engaged);
    let first = max_diff(&setpoints(&h), &setpoints(&twin));
    assert!(
        first < 1e-6,
        "takeover cycle: {first} rad from the open-loop gait"
    );
    let (step, diff) = run(&mut h, Some(&mut twin), 3000);
    let snap = h.telemetry.latest();
    assert_eq!(snap.compliance.engagement, Engagement::Engaged);
    assert_eq!(snap.compliance.takeovers, 1);
    assert!(snap.compliance.report.available);
    assert!(snap.compliance.report.phase_lag_rad.abs() < 1e-9);
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
    let c = build("a_ws_omega_central");
    assert_eq!(request(&mut h, LoopRequest::SetCompliance, Some(c)), Ok(()));
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
    run(&mut h, Some(&mut twin), 2100);
    let c = build("a_ws_omega");
    request(&mut h, LoopRequest::SetCompliance, Some(c)).unwrap();
    twin.control.step();
    let (step, diff) = run(&mut h, Some(&mut twin), 4000);
    assert!(diff > 0.05, "the torques changed nothing ({diff} rad)");
    assert!(step <= MAX_STEP_RAD, "{step}");
    let r = h.telemetry.latest().compliance.report;
    let amp = &r.fields[0];
    let nominal = table().get(GaitKind::Slithering).amplitude_lat_rad;
    assert!(
        amp.force[..amp.len()].iter().any(|f| f.abs() > 0.05),
        "{amp:?}"
    );
    assert!(
        amp.value[..amp.len()]
            .iter()
            .any(|v| (v - nominal).abs() > 0.02),
        "{amp:?}"
    );
    assert!(r.phase_lag_rad.abs() > 1e-3, "the phase complies too");
}

#[test]
fn another_gait_takes_the_joints_back_smoothly() {
    let (mut h, mut twin) = (harness(Some(pegs)), harness(Some(pegs)));
    run(&mut h, Some(&mut twin), 2100);
    let c = build("a_ws_omega");
    request(&mut h, LoopRequest::SetCompliance, Some(c)).unwrap();
    twin.control.step();
    let (_, diff) = run(&mut h, Some(&mut twin), 3000);
    assert!(diff > 0.05, "{diff}");
    let side = LoopRequest::SetGait(GaitKind::Sidewinding);
    request(&mut h, side, None).unwrap();
    request(&mut twin, side, None).unwrap();
    assert_eq!(engagement(&h), Engagement::Waiting);
    let (step, _) = run(&mut h, Some(&mut twin), 1000);
    // Well inside the slew limit: a blend, not a clamped jump.
    assert!(step < 2e-3, "{step}");
    // Once the blend is over both run the same sidewinding (the re-sync's cycle
    // advances no phase: 1 ms of ωT behind).
    run(&mut h, Some(&mut twin), 1100);
    let (_, diff) = run(&mut h, Some(&mut twin), 400);
    assert!(diff < 1.5e-3, "{diff}");
    // Back to slithering: the controller takes over again after the blend.
    request(&mut h, LoopRequest::SetGait(GaitKind::Slithering), None).unwrap();
    run(&mut h, None, 2100);
    let c = h.telemetry.latest().compliance;
    assert_eq!((c.engagement, c.takeovers), (Engagement::Engaged, 2));
}

#[test]
fn a_replaced_controller_goes_back_and_open_loop_hands_back() {
    let mut h = harness(Some(pegs));
    run(&mut h, None, 2100);
    request(&mut h, LoopRequest::SetCompliance, Some(build("a"))).unwrap();
    run(&mut h, None, 1000);
    assert_eq!(engagement(&h), Engagement::Engaged);
    let c = build("cpg");
    request(&mut h, LoopRequest::SetCompliance, Some(c)).unwrap();
    assert_eq!(
        engagement(&h),
        Engagement::Waiting,
        "the selector blends first"
    );
    let (step, _) = run(&mut h, None, 2100);
    assert!(step <= MAX_STEP_RAD, "{step}");
    let snap = h.telemetry.latest();
    assert_eq!(snap.compliance.setting.controller, "cpg");
    assert_eq!(snap.compliance.engagement, Engagement::Engaged);
    let open = ControllerChange::OpenLoop;
    request(&mut h, LoopRequest::SetCompliance, Some(open)).unwrap();
    assert_eq!(engagement(&h), Engagement::Off);
    let (step, _) = run(&mut h, None, 500);
    assert!(step <= MAX_STEP_RAD, "{step}");
    let names: Vec<_> = h.retired.try_iter().map(|c| c.name()).collect();
    assert_eq!(names, ["a", "cpg"]);
}

#[test]
fn parameters_and_controller_stay_consistent() {
    let mut h = harness(None);
    run(&mut h, None, 100);
    let patch = ParamPatch {
        amplitude_lat_rad: Some(0.6),
        ..ParamPatch::default()
    };
    let set = LoopRequest::SetParams(GaitKind::Slithering, patch);
    assert_eq!(request(&mut h, set, None), Ok(()), "no controller: plain");
    assert_eq!(
        request(&mut h, LoopRequest::SetCompliance, None),
        Err(Rejection::NoController)
    );
    request(&mut h, LoopRequest::SetCompliance, Some(build("a"))).unwrap();
    assert_eq!(request(&mut h, set, None), Err(Rejection::StaleController));
    assert_eq!(request(&mut h, set, Some(build("a_ws"))), Ok(()));
    // A refused request's controller and one attached to another request come back.
    let bad = ParamPatch {
        amplitude_lat_rad: Some(f64::NAN),
        ..ParamPatch::default()
    };
    let bad = LoopRequest::SetParams(GaitKind::Slithering, bad);
    assert_eq!(
        request(&mut h, bad, Some(build("cpg"))),
        Err(Rejection::InvalidParams)
    );
    request(&mut h, LoopRequest::Hold, Some(build("a_ws_omega"))).unwrap();
    let names: Vec<_> = h.retired.try_iter().map(|c| c.name()).collect();
    assert_eq!(names, ["a", "cpg", "a_ws_omega"]);
    let snap = h.telemetry.latest();
    assert_eq!(snap.compliance.setting.controller, "a_ws");
    assert_eq!(snap.params.get(GaitKind::Slithering).amplitude_lat_rad, 0.6);
}
