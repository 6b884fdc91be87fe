//! Hardware-in-loop: `snake-emu` and `snaked` as separate processes on loopback,
//! in lockstep. Gaits are switched through the control socket; the emulator's
//! ground-truth recording shows that the joints follow each serpenoid and that
//! no switch ever steps a joint set-point.
use crate::support::rig;

use std::time::Duration;

use crate::support::fit::{fit_sine, wrap};
use rig::{Client, Recording, Rig};
use serde_json::json;
use snaked::gait::serpenoid::Serpenoid;
use snaked::gait::{BodyLayout, GaitKind, GaitParams, Plane};

const N: usize = 18;
const MAX_SPEED_RAD_S: f64 = 3.46;
const DT_S: f64 = 1e-3;
/// Temporal frequency every gait is switched to, rad/s: a period of π s keeps the run short.
const OMEGA_T: f64 = 2.0;

struct Window {
    kind: GaitKind,
    params: GaitParams,
    t0: f64,
    t1: f64,
}

fn wait_until_t(c: &mut Client, t: f64) -> f64 {
    let s = c.wait_status(Duration::from_secs(120), "loop time", |s| {
        s["t_s"].as_f64().unwrap() >= t
    });
    s["t_s"].as_f64().unwrap()
}

#[test]
fn gaits_follow_the_serpenoid_and_switches_never_step_a_joint() {
    let mut rig = Rig::start(
        N,
        &["--mode", "lockstep"],
        "",
        "[loop]\npacing = \"lockstep\"\nlockstep_timeout_s = 2.0\n[gait]\ninitial = \"sidewinding\"\nstart = \"run\"",
    );
    let c = &mut rig.client;
    c.wait_status(Duration::from_secs(30), "running", |s| {
        s["mode"] == "running"
    });

    // Every gait a little faster, set while inactive: a parameter change must not move
    // the running gait, and is validated on the way in.
    for kind in GaitKind::ALL {
        c.call(
            "params.set",
            json!({"gait": kind.name(), "temporal_freq_rad_s": OMEGA_T}),
        );
    }
    let bad = c.call_raw(
        "params.set",
        json!({"gait": "slithering", "amplitude_lat_rad": 3.0}),
    );
    assert!(
        bad.get("error").is_some(),
        "an out-of-range amplitude is refused: {bad}"
    );

    let schedule = [
        GaitKind::Slithering,
        GaitKind::Rolling,
        GaitKind::LinearProgression,
        GaitKind::ConicalSidewinding,
        GaitKind::RollingHelix,
        GaitKind::Sidewinding,
    ];
    let mut windows = Vec::new();
    for kind in schedule {
        c.call("gait.set", json!({"gait": kind.name()}));
        let s = c.call("status", json!({}));
        assert_eq!(s["gait"], kind.name());
        let blend = s["blend_time_s"].as_f64().unwrap();
        // The switch happened at or before this status' time: the blend is over by t0.
        let t0 = s["t_s"].as_f64().unwrap() + blend + 0.3;
        let period = std::f64::consts::TAU / OMEGA_T;
        let t1 = wait_until_t(c, t0 + 1.2 * period);
        let p = c.call("params.get", json!({"gait": kind.name()}));
        let params: GaitParams = serde_json::from_value(p["params"].clone()).unwrap();
        windows.push(Window {
            kind,
            params,
            t0,
            t1,
        });
    }

    // A safe stop: SIGTERM, exit 0, socket gone.
    let rec = rig.stop(N);
    check_no_steps(&rec);
    let layout = BodyLayout::alternating(N, Plane::Lateral, 0.064);
    for w in &windows {
        check_window(&rec, &layout, w);
    }
    // The stop ended limp: the last commands the modules applied are "not commanded".
    let last = rec.t.len() - 1;
    assert!((0..N).all(|i| rec.cmd[i][last].is_nan()), "limp at the end");
}

/// No set-point moves faster than the joint can, over the whole run, and the first
/// set-point the modules get (coming out of limp) is where the joint was.
fn check_no_steps(rec: &Recording) {
    let bound = MAX_SPEED_RAD_S * DT_S * 1.02 + 1e-5;
    for i in 0..N {
        let (cmd, pos) = (&rec.cmd[i], &rec.pos[i]);
        let first = cmd
            .iter()
            .position(|c| c.is_finite())
            .expect("joint driven");
        let start = if first > 0 { pos[first - 1] } else { 0.0 };
        let gap = (cmd[first] - start).abs();
        assert!(
            gap < 0.01,
            "joint {i} armed {gap} rad away from where it was"
        );
        for k in 1..cmd.len() {
            if cmd[k].is_finite() && cmd[k - 1].is_finite() {
                let step = (cmd[k] - cmd[k - 1]).abs();
                assert!(
                    step <= bound,
                    "joint {i} set-point stepped {step} rad at t = {}",
                    rec.t[k]
                );
            }
        }
    }
}

/// Fit each joint's measured output over the window and compare with the serpenoid
/// the gait defines: amplitude, offset, relative phase along the body, residual.
fn check_window(rec: &Recording, layout: &BodyLayout, w: &Window) {
    let range = rec.span(w.t0, w.t1);
    assert!(
        range.len() > 2000,
        "{:?}: window too short ({} rows)",
        w.kind,
        range.len()
    );
    let t = &rec.t[range.clone()];
    let gait = Serpenoid::for_layout(w.kind, &w.params, layout);
    let mut expected = vec![0.0; N];
    let mut unused = vec![0.0; N];
    // Expected trajectory: the gait sampled at the same times with ψ = ωT·t (phase origin free).
    let mut exp_series: Vec<Vec<f64>> = vec![Vec::new(); N];
    for &ti in t {
        gait.evaluate_with_velocity(layout, OMEGA_T * ti, OMEGA_T, &mut expected, &mut unused);
        for (series, &e) in exp_series.iter_mut().zip(&expected) {
            series.push(e);
        }
    }
    let exp_fits: Vec<_> = exp_series.iter().map(|x| fit_sine(t, x, OMEGA_T)).collect();
    let got_fits: Vec<_> = rec
        .pos
        .iter()
        .map(|x| fit_sine(t, &x[range.clone()], OMEGA_T))
        .collect();
    let name = w.kind.name();
    // Independent checks of SPEC §2 on the expected shape itself.
    let lat: Vec<usize> = (0..N)
        .filter(|&i| layout.planes[i] == Plane::Lateral)
        .collect();
    let dor: Vec<usize> = (0..N)
        .filter(|&i| layout.planes[i] == Plane::Dorsal)
        .collect();
    match w.kind {
        GaitKind::Slithering => {
            assert!(
                dor.iter().all(|&i| got_fits[i].amplitude < 0.02),
                "{name}: dorsal joints straight"
            );
            let a = w.params.amplitude_lat_rad;
            assert!(
                lat.iter()
                    .all(|&i| (got_fits[i].amplitude - a).abs() < 0.1 * a),
                "{name}: lateral amplitude"
            );
        }
        GaitKind::LinearProgression => {
            assert!(
                lat.iter().all(|&i| got_fits[i].amplitude < 0.02),
                "{name}: lateral joints straight"
            );
        }
        GaitKind::Rolling => {
            for set in [&lat, &dor] {
                let p0 = got_fits[set[0]].phase;
                assert!(
                    set.iter()
                        .all(|&i| wrap(got_fits[i].phase - p0).abs() < 0.1),
                    "{name}: in phase"
                );
            }
            let shift = wrap(got_fits[dor[0]].phase - got_fits[lat[0]].phase).abs();
            assert!(
                (shift - std::f64::consts::FRAC_PI_2).abs() < 0.15,
                "{name}: planes a quarter apart ({shift})"
            );
        }
        GaitKind::ConicalSidewinding => {
            let (head, tail) = (
                got_fits[lat[0]].amplitude,
                got_fits[*lat.last().unwrap()].amplitude,
            );
            assert!(
                tail < head * 0.85,
                "{name}: amplitude tapers ({head} -> {tail})"
            );
        }
        _ => {}
    }
    // Measured follows expected, joint by joint; phases relative to the joint that moves most.
    let r = (0..N)
        .max_by(|&a, &b| exp_fits[a].amplitude.total_cmp(&exp_fits[b].amplitude))
        .unwrap();
    let p_ref = got_fits[r].phase - exp_fits[r].phase;
    for i in 0..N {
        let (e, g) = (exp_fits[i], got_fits[i]);
        let tol = 0.1 * e.amplitude + 0.02;
        assert!(
            (g.amplitude - e.amplitude).abs() < tol,
            "{name} joint {i}: amplitude {} vs {}",
            g.amplitude,
            e.amplitude
        );
        assert!(
            (g.offset - e.offset).abs() < 0.03,
            "{name} joint {i}: offset {} vs {}",
            g.offset,
            e.offset
        );
        if e.amplitude > 0.05 {
            let dphi = wrap(g.phase - e.phase - p_ref);
            assert!(
                dphi.abs() < 0.15,
                "{name} joint {i}: phase off by {dphi} rad relative to joint {r}"
            );
        }
        assert!(
            g.rms_residual < 0.03 + 0.05 * e.amplitude,
            "{name} joint {i}: residual {}",
            g.rms_residual
        );
    }
}
