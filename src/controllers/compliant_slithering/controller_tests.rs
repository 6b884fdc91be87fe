use crate::controller_interface::TickClock;
use std::f64::consts::PI;

use super::*;
use crate::controller_interface::testing::ObservationBuf;
use crate::controllers::open_loop::OpenLoop;
use crate::gait::{GaitKind, Plane};
use crate::module::MODULE_LENGTH_M;

const N: usize = 18;

fn layout() -> BodyLayout {
    BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M)
}

fn params() -> GaitParams {
    GaitParams::default_for(GaitKind::Slithering)
}

fn full() -> CompliantSlithering {
    CompliantSlithering::new(&layout(), &params(), CompliantSlitheringConfig::full())
}

/// Signal `k` of the report (`SIGNALS` order: 2 is the phase lag).
fn signal(c: &dyn Controller, k: usize) -> f64 {
    let mut r = ControllerReport::EMPTY;
    c.report(&mut r);
    r.signals[k]
}

/// Runs `c` from `t0` for `seconds` with reported torques from `torque(t, set_points)`.
fn run_from(
    c: &mut dyn Controller,
    t0: f64,
    seconds: f64,
    mut torque: impl FnMut(f64, &[f64]) -> [f64; N],
) -> Vec<f64> {
    let mut out = vec![0.0; N];
    let pos = [0.0; N];
    let mut tau = [0.0; N];
    let buf = ObservationBuf::new(N);
    let mut clock = TickClock::default();
    for k in 0..(seconds * 1000.0) as usize {
        let t = t0 + k as f64 * 1e-3;
        c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut out);
        tau = torque(t, &out);
    }
    out
}

fn run(
    c: &mut dyn Controller,
    seconds: f64,
    torque: impl FnMut(f64, &[f64]) -> [f64; N],
) -> Vec<f64> {
    run_from(c, 0.0, seconds, torque)
}

#[test]
fn without_torque_every_variant_is_the_open_loop_gait() {
    let mut open = OpenLoop::new(GaitKind::Slithering, &layout(), &params());
    let reference = run(&mut open, 7.3, |_, _| [0.0; N]);
    for (name, _) in CompliantSlitheringConfig::PRESETS {
        let config = CompliantSlitheringConfig::preset(name).unwrap();
        let mut c = CompliantSlithering::new(&layout(), &params(), config);
        let ours = run(&mut c, 7.3, |_, _| [0.0; N]);
        for (i, (a, b)) in ours.iter().zip(&reference).enumerate() {
            assert!((a - b).abs() < 1e-6, "{name} joint {i}: {a} vs {b}");
        }
    }
}

/// SPEC §3's sign test: the environment bending every joint further (reported
/// torque against the bend, see `shape::torque`) makes a compliant amplitude grow and an
/// anti-compliant one shrink.
#[test]
fn a_push_that_bends_the_body_further_increases_a_compliant_amplitude() {
    let push = |_: f64, sp: &[f64]| {
        let mut tau = [0.0; N];
        for (t, &x) in tau.iter_mut().zip(sp) {
            *t = -2.0 * x.signum() * (x.abs() > 0.05) as u8 as f64;
        }
        tau
    };
    let mut c = full();
    run(&mut c, 3.0, push);
    let a = c.value_at(Param::Amplitude, 0.5);
    assert!(a > params().amplitude_lat_rad + 0.1, "compliant: {a}");
    let mut anti = CompliantSlitheringConfig::full();
    anti.sign = crate::shape::admittance::AdmittanceSign::AntiCompliant;
    let mut c = CompliantSlithering::new(&layout(), &params(), anti);
    run(&mut c, 3.0, push);
    let a = c.value_at(Param::Amplitude, 0.5);
    assert!(a < params().amplitude_lat_rad - 0.1, "anti-compliant: {a}");
}

/// Torques resisting the wave's travel (against each joint's motion) delay the phase;
/// released, the phase catches up with its nominal.
#[test]
fn resisting_the_wave_delays_the_phase_and_releasing_it_recovers() {
    let mut c = full();
    let mut last = [0.0; N];
    let mut lag_at = |c: &mut CompliantSlithering, t0: f64, secs: f64, resist: bool| {
        run_from(c, t0, secs, |_, sp| {
            let mut tau = [0.0; N];
            for i in 0..N {
                let v = sp[i] - last[i];
                // Environment against the motion: τ_ext = −k·v, reported = +k·v.
                tau[i] = if resist {
                    3.0 * v.signum() * (v.abs() > 1e-6) as u8 as f64
                } else {
                    0.0
                };
                last[i] = sp[i];
            }
            tau
        });
        signal(c, 2)
    };
    let held = lag_at(&mut c, 0.0, 3.0, true);
    assert!(held < -0.2, "{held}");
    let released = lag_at(&mut c, 3.0, 5.0, false);
    assert!(released.abs() < 0.05 * held.abs(), "{held} -> {released}");
}

#[test]
fn windows_stay_half_waves_and_a_learnt_amplitude_travels_off_the_tail() {
    let mut c = full();
    // Push the head half of the body for 1 s, then nothing.
    let push = |t: f64, sp: &[f64]| {
        let mut tau = [0.0; N];
        if t < 1.0 {
            for (i, (t, &x)) in tau.iter_mut().zip(sp).enumerate().take(N / 3) {
                let _ = i;
                *t = -2.0 * x.signum();
            }
        }
        tau
    };
    run(&mut c, 1.0, push);
    let (windows, values, _) = c.field(Param::Amplitude);
    assert!((3..=5).contains(&windows.len()), "{windows:?}");
    let head_a = values[0].max(values[1]);
    assert!(head_a > params().amplitude_lat_rad + 0.05, "{values:?}");
    // A wave period later (2π / ωT), the learnt windows have left: all back to nominal.
    let mut c2 = c;
    run(
        &mut c2,
        2.0 * PI / params().temporal_freq_rad_s + 1.0,
        |_, _| [0.0; N],
    );
    let (_, values, _) = c2.field(Param::Amplitude);
    for v in values {
        assert!((v - params().amplitude_lat_rad).abs() < 0.02, "{values:?}");
    }
}

#[test]
fn signals_and_fields_can_be_read_before_the_first_step() {
    let c = full();
    let mut r = ControllerReport::EMPTY;
    c.report(&mut r);
    for (k, v) in r.signals[..SIGNALS].iter().enumerate() {
        assert!(v.is_finite(), "signal {k} = {v}");
    }
    assert!((r.signals[0] - params().amplitude_lat_rad).abs() < 1e-9);
    assert!((c.value_at(Param::Amplitude, 0.5) - params().amplitude_lat_rad).abs() < 1e-9);
}

#[test]
fn the_report_shows_each_field_and_engaging_starts_afresh() {
    let push = |_: f64, sp: &[f64]| {
        let mut tau = [0.0; N];
        for (t, &x) in tau.iter_mut().zip(sp).take(N / 2) {
            *t = -2.0 * x.signum();
        }
        tau
    };
    let mut c = full();
    let mut report = ControllerReport::EMPTY;
    c.report(&mut report);
    let nominal = &report.fields[Param::Amplitude.index()];
    assert!(nominal.count > 0, "the nominal shape before the first step");
    assert!(
        nominal.columns[0][..nominal.len()]
            .iter()
            .all(|&v| v == params().amplitude_lat_rad)
    );
    run(&mut c, 2.0, push);
    c.report(&mut report);
    let (windows, values, forces) = c.field(Param::Amplitude);
    let amp = &report.fields[Param::Amplitude.index()];
    assert_eq!(amp.count, windows.len());
    assert_eq!(&amp.columns[0][..amp.len()], values);
    assert_eq!(&amp.columns[1][..amp.len()], forces);
    assert_eq!(report.signals[3], windows.len() as f64);
    assert!(report.signals[4] > 0.0, "windows were born");
    let phase = &report.fields[Param::Phase.index()];
    assert_eq!(phase.count, 1, "central phase");
    assert!((phase.columns[0][0] - report.signals[2]).abs() < 1e-9);

    // Engaged again at t = 5 s with the phase the open-loop gait has then: a new
    // controller's behaviour from there, whatever it learnt before.
    crate::controller_interface::testing::engage_at(&mut c, &layout(), &params(), 5.0);
    c.report(&mut report);
    let amp = &report.fields[Param::Amplitude.index()];
    assert!(
        amp.columns[0][..amp.len()]
            .iter()
            .all(|&v| v == params().amplitude_lat_rad)
    );
    let mut fresh = full();
    crate::controller_interface::testing::engage_at(&mut fresh, &layout(), &params(), 5.0);
    let ours = run_from(&mut c, 5.0, 1.0, push);
    let theirs = run_from(&mut fresh, 5.0, 1.0, push);
    assert_eq!(ours, theirs, "an engaged controller is a new one");
    let mut open = OpenLoop::new(GaitKind::Slithering, &layout(), &params());
    let reference = run(&mut open, 5.5, |_, _| [0.0; N]);
    let mut late = full();
    crate::controller_interface::testing::engage_at(&mut late, &layout(), &params(), 5.0);
    let continued = run_from(&mut late, 5.0, 0.5, |_, _| [0.0; N]);
    for (a, b) in continued.iter().zip(&reference) {
        assert!((a - b).abs() < 1e-6, "engaged late, it continues the gait");
    }
}

#[test]
fn nominal_parameters_outside_its_ranges_are_refused() {
    let c = full();
    assert!(c.accepts(&params()).is_ok());
    let mut p = params();
    p.spatial_freq_rad = 5.0 * PI;
    assert_eq!(c.accepts(&p).unwrap_err().field, "spatial_freq_rad");
    let mut p = params();
    p.offset_lat_rad = 0.5;
    assert_eq!(c.accepts(&p).unwrap_err().field, "offset_lat_rad");
    // `a` leaves ωS alone, so any ωS is fine.
    let a = CompliantSlithering::new(
        &layout(),
        &params(),
        CompliantSlitheringConfig::preset("a").unwrap(),
    );
    let mut p = params();
    p.spatial_freq_rad = 5.0 * PI;
    assert!(a.accepts(&p).is_ok());
}
