use super::*;
use crate::controller_interface::ControllerKind;
use crate::controller_interface::TickClock;
use crate::controller_interface::testing::{ObservationBuf, engage_at};
use crate::controllers::directional_compliance::{
    DirectionalComplianceKind, FrictionOffset, SectionValues,
};
use crate::controllers::open_loop::OpenLoop;
use crate::gait::GaitKind;

const N: usize = 16;

fn setup() -> (BodyLayout, GaitParams) {
    (
        BodyLayout::alternating(N, Plane::Lateral, 0.064),
        GaitParams::default_for(GaitKind::Slithering),
    )
}

fn preset(name: &str) -> DirectionalComplianceConfig {
    DirectionalComplianceKind::preset(name).expect("a preset")
}

fn engaged(name: &str) -> (DirectionalCompliance, BodyLayout, GaitParams) {
    let (layout, params) = setup();
    let mut c = DirectionalCompliance::new(&layout, &params, preset(name));
    engage_at(&mut c, &layout, &params, 0.0);
    (c, layout, params)
}

/// Runs `c` from `t0` for `seconds`; the reported torques are `torque(t, set_points)`;
/// `each` sees the controller after every step.
fn run(
    c: &mut DirectionalCompliance,
    t0: f64,
    seconds: f64,
    torque: impl Fn(f64, &[f64]) -> [f64; N],
    mut each: impl FnMut(&DirectionalCompliance),
) -> Vec<f64> {
    let buf = ObservationBuf::new(N);
    let (pos, mut tau, mut out) = ([0.0; N], [0.0; N], vec![0.0; N]);
    let mut clock = TickClock::default();
    for k in 0..(seconds * 1000.0).round() as usize {
        let t = t0 + k as f64 * 1e-3;
        c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut out);
        each(c);
        tau = torque(t, &out);
    }
    out
}

fn none(_: f64, _: &[f64]) -> [f64; N] {
    [0.0; N]
}

/// Reported torque that bends every lateral joint further than commanded by the
/// environment (the reported spring torque opposes the bend: `τ_ext = −τ_reported`).
fn bend_further(sp: &[f64]) -> [f64; N] {
    let mut tau = [0.0; N];
    for (i, t) in tau.iter_mut().enumerate() {
        if i % 2 == 0 && sp[i].abs() > 0.05 {
            *t = -1.5 * sp[i].signum();
        }
    }
    tau
}

/// `name`'s preset with the windows' spatial frequency complying.
fn with_spatial_freq(name: &str) -> DirectionalCompliance {
    let (layout, params) = setup();
    let mut config = preset(name);
    config.spatial_freq.enabled = true;
    config.check().unwrap();
    let mut c = DirectionalCompliance::new(&layout, &params, config);
    engage_at(&mut c, &layout, &params, 0.0);
    c
}

#[test]
fn without_torque_the_planar_controllers_are_open_loop_slithering() {
    let presets = ["dc_switching", "dc_nc", "dc_pdc", "dc_ndc"];
    let spatial = presets.map(|name| (name, with_spatial_freq(name)));
    let plain = presets.map(|name| (name, engaged(name).0));
    for (name, mut c) in plain.into_iter().chain(spatial) {
        let (layout, params) = setup();
        let mut open = OpenLoop::new(GaitKind::Slithering, &layout, &params);
        engage_at(&mut open, &layout, &params, 0.0);
        let buf = ObservationBuf::new(N);
        let (pos, tau) = ([0.0; N], [0.0; N]);
        let (mut a, mut b) = (vec![0.0; N], vec![0.0; N]);
        let (mut clock, mut open_clock) = (TickClock::default(), TickClock::default());
        for k in 0..5000 {
            let t = k as f64 * 1e-3;
            open.step(open_clock.tick(t), &buf.observe(&pos, &tau), &mut a);
            c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut b);
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-9, "{name} at {t}: {x} vs {y}");
            }
        }
        assert_eq!(c.switches(), 0);
    }
}

/// Joint speeds never exceed what the wave itself asks, rad per 1 ms step.
const NO_JUMP_RAD: f64 = 0.01;

#[test]
fn a_push_along_the_phase_gradient_adds_waves_where_the_spatial_frequency_complies() {
    // The environment pushes each lateral joint along ∂θ/∂ωS (`+A·cos φ`, reported with
    // the spring's opposite sign), then against it: the windows take more waves, then
    // fewer, within the range, and the joints never jump.
    let ws0 = GaitParams::default_for(GaitKind::Slithering).spatial_freq_rad;
    for (sign, more) in [(1.0, true), (-1.0, false)] {
        let mut c = with_spatial_freq("dc_nc");
        let buf = ObservationBuf::new(N);
        let (pos, mut tau) = ([0.0; N], [0.0; N]);
        let (mut out, mut last) = (vec![0.0; N], vec![0.0; N]);
        let mut clock = TickClock::default();
        let g = c.config().spatial_freq.gains;
        for k in 0..4000 {
            let t = k as f64 * 1e-3;
            c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut out);
            if k > 0 {
                for (x, y) in out.iter().zip(&last) {
                    assert!((x - y).abs() < NO_JUMP_RAD, "a jump at {t}: {y} to {x}");
                }
            }
            last.copy_from_slice(&out);
            for (i, t) in tau.iter_mut().enumerate() {
                let (plane, phi, a, _) = c.joint_wave(i);
                *t = if plane == LAT {
                    -3.0 * sign * a * phi.cos()
                } else {
                    0.0
                };
            }
            for (_, w) in c.windows() {
                let ws = ws0 + w.spatial_freq.deviation;
                assert!((g.min - 1e-9..=g.max + 1e-9).contains(&ws), "{ws}");
            }
        }
        let body: Vec<f64> = c.windows().map(|(_, w)| w.spatial_freq.deviation).collect();
        let mean = body.iter().sum::<f64>() / body.len() as f64;
        if more {
            assert!(mean > 0.3, "more waves: {body:?}");
        } else {
            assert!(mean < -0.3, "fewer waves: {body:?}");
        }
    }
    // Off (all presets but `dc_full_*`), the spatial frequency stays nominal.
    let (mut c, ..) = engaged("dc_nc");
    assert!(!c.config().spatial_freq.enabled);
    run(&mut c, 0.0, 2.0, |_, sp| bend_further(sp), |_| {});
    assert!(
        c.windows()
            .all(|(_, w)| w.spatial_freq == ParamState::default())
    );
}

#[test]
fn a_push_along_the_bend_opens_nc_and_pdc_windows_but_not_ndc_ones() {
    let mean = |name: &str| {
        let (mut c, ..) = engaged(name);
        run(&mut c, 0.0, 3.0, |_, sp| bend_further(sp), |_| {});
        c.mean_amplitude(LAT)
    };
    let a0 = GaitParams::default_for(GaitKind::Slithering).amplitude_lat_rad;
    let (nc, pdc, ndc) = (mean("dc_nc"), mean("dc_pdc"), mean("dc_ndc"));
    assert!(nc > a0 + 0.1, "NC complies: {nc}");
    assert!(pdc > a0 + 0.1, "PDC admits increases: {pdc}");
    assert!((ndc - a0).abs() < 1e-9, "NDC refuses them: {ndc}");
}

#[test]
fn windows_are_born_at_the_head_at_nominal_and_the_held_section_switches() {
    let (mut c, ..) = engaged("dc_switching");
    let mut born = 0;
    let mut switched = 0;
    // Pegs in the middle third push the body flatter there, steadily.
    let flatten_mid = |_: f64, sp: &[f64]| {
        let mut tau = [0.0; N];
        for (i, t) in tau.iter_mut().enumerate() {
            let s = (i as f64 + 1.0) / (N as f64 + 1.0);
            if i % 2 == 0 && (0.33..0.67).contains(&s) {
                *t = 2.0 * sp[i].signum();
            }
        }
        tau
    };
    run(&mut c, 0.0, 30.0, flatten_mid, |c| {
        if c.window_events().born_at_head > 0 {
            born += 1;
            let (_, head) = c.windows().next().unwrap();
            for p in head.amplitude {
                assert_eq!(p, AmplitudeState::default(), "a new head window");
            }
        }
        switched = c.switches();
    });
    assert!(born >= 3, "windows travel: {born} born");
    assert!(switched > 0, "the flattened middle switches");
    // The jam stays with the middle section while the windows pass it: the middle is
    // directional, the head (no pegs) is not. (The tail may follow: the windows carry
    // the flattened amplitude on down the body.)
    let s = c.sections();
    assert_eq!(s.get(1, LAT).absition.mode, Mode::Pdc, "{s:?}");
    assert_eq!(s.get(0, LAT).absition.mode, Mode::Nc, "{s:?}");
    let mut report = ControllerReport::default();
    c.report(&mut report);
    assert!(report.signals[10] >= 1.0, "sections in PDC");
}

/// The modes the sections of `c` are in now (lateral).
fn section_modes(c: &DirectionalCompliance, modes: &mut Vec<Mode>) {
    for k in 0..c.sections().count() {
        let m = c.sections().get(k, LAT).absition.mode;
        if !modes.contains(&m) {
            modes.push(m);
        }
    }
}

#[test]
fn a_body_flattened_for_long_switches_to_pdc() {
    let (mut c, ..) = engaged("dc_switching");
    let mut modes = Vec::new();
    // Every lateral joint is pushed flatter, steadily: every section's absition falls
    // once two spans have shown the sections still (the hold).
    let flatten = |_: f64, sp: &[f64]| bend_further(sp).map(|t| -t);
    run(&mut c, 0.0, 25.0, flatten, |c| section_modes(c, &mut modes));
    assert!(modes.contains(&Mode::Pdc), "{modes:?}");
    assert!(!modes.contains(&Mode::Ndc), "{modes:?}");
    // And bent further for long: NDC.
    let (mut c, ..) = engaged("dc_switching");
    let mut modes = Vec::new();
    run(
        &mut c,
        0.0,
        25.0,
        |_, sp| bend_further(sp),
        |c| section_modes(c, &mut modes),
    );
    assert!(modes.contains(&Mode::Ndc), "{modes:?}");
    assert!(!modes.contains(&Mode::Pdc), "{modes:?}");
}

#[test]
fn planar_keeps_the_dorsal_joints_straight_and_3d_fades_its_dorsal_wave_in() {
    let (mut c, ..) = engaged("dc_nc");
    let out = run(&mut c, 0.0, 3.0, none, |_| {});
    assert!(out.iter().skip(1).step_by(2).all(|&x| x == 0.0), "{out:?}");
    let (mut c, ..) = engaged("dc3d_nc");
    let mut first = None;
    let mut max_step: f64 = 0.0;
    let mut last = vec![0.0; N];
    let buf = ObservationBuf::new(N);
    let (pos, tau) = ([0.0; N], [0.0; N]);
    let mut out = vec![0.0; N];
    let mut clock = TickClock::default();
    for k in 0..4000 {
        c.step(
            clock.tick(k as f64 * 1e-3),
            &buf.observe(&pos, &tau),
            &mut out,
        );
        let dorsal: Vec<f64> = out.iter().skip(1).step_by(2).copied().collect();
        first.get_or_insert(dorsal.clone());
        if k > 0 {
            for (x, y) in out.iter().zip(&last) {
                max_step = max_step.max((x - y).abs());
            }
        }
        last.clone_from(&out);
    }
    assert!(
        first.unwrap().iter().all(|&x| x == 0.0),
        "no jump at the takeover"
    );
    let dorsal_peak = out
        .iter()
        .skip(1)
        .step_by(2)
        .fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(dorsal_peak > 0.15, "the dorsal wave runs: {dorsal_peak}");
    assert!(
        max_step < 3.46e-3,
        "within the joints' speed per 1 ms: {max_step}"
    );
}

#[test]
fn the_3d_planes_comply_independently() {
    // Only the dorsal joints are pushed along their bend.
    let dorsal_push = |_: f64, sp: &[f64]| {
        let mut tau = [0.0; N];
        for (i, t) in tau.iter_mut().enumerate() {
            if i % 2 == 1 && sp[i].abs() > 0.02 {
                *t = -1.5 * sp[i].signum();
            }
        }
        tau
    };
    let (mut c, ..) = engaged("dc3d_nc");
    run(&mut c, 0.0, 6.0, dorsal_push, |_| {});
    let a0 = GaitParams::default_for(GaitKind::Slithering).amplitude_lat_rad;
    assert!(
        (c.mean_amplitude(LAT) - a0).abs() < 1e-9,
        "lateral untouched"
    );
    assert!(c.mean_amplitude(DOR) > c.config().dorsal.amplitude_rad + 0.05);
}

#[test]
fn calibration_measures_the_open_ground_offset_and_then_the_absition_stays_near_zero() {
    // "Open ground": a steady drag that bends every lateral joint a little further.
    let drag = |_: f64, sp: &[f64]| bend_further(sp).map(|t| t * 0.5);
    let signal = |c: &DirectionalCompliance, k: usize| {
        let mut r = ControllerReport::default();
        c.report(&mut r);
        r.signals[k]
    };
    let (mut c, ..) = engaged("dc_switching");
    assert_eq!(signal(&c, 6), 0.0, "uncalibrated");
    assert_eq!(
        c.command(ControllerCommand::Calibrate { duration_s: -1.0 }),
        Err(CommandRefused::BadDuration)
    );
    c.command(ControllerCommand::Calibrate { duration_s: 12.0 })
        .unwrap();
    run(&mut c, 0.0, 6.0, drag, |_| {});
    assert_eq!(signal(&c, 6), 1.0, "running");
    assert!((signal(&c, 7) - 0.5).abs() < 0.01);
    run(&mut c, 6.0, 6.5, drag, |_| {});
    assert_eq!(signal(&c, 6), 2.0, "calibrated");
    let o = c.calibration().offsets();
    assert!(
        o.lateral_rad.as_slice().iter().all(|&x| x > 0.02),
        "the drag opens the wave: {o:?}"
    );
    // The same ground afterwards: the absitions stay well inside the thresholds.
    let mut worst: f64 = 0.0;
    run(&mut c, 12.5, 20.0, drag, |c| {
        for k in 0..c.sections().count() {
            worst = worst.max(c.sections().get(k, LAT).absition.absition.abs());
        }
    });
    assert!(worst < 0.3, "{worst}");
    assert_eq!(c.switches(), 0);
    // Uncalibrated, the same drag reads as an obstruction.
    let (mut c, ..) = engaged("dc_switching");
    run(&mut c, 0.0, 30.0, drag, |_| {});
    assert!(c.switches() > 0);
    // Cleared: back to none.
    c.command(ControllerCommand::ClearCalibration).unwrap();
    assert_eq!(signal(&c, 6), 0.0);
}

#[test]
fn the_configuration_is_checked_field_by_field() {
    let err = |f: &dyn Fn(&mut DirectionalComplianceConfig)| {
        let mut c = preset("dc_switching");
        f(&mut c);
        c.check().unwrap_err().to_string()
    };
    assert!(err(&|c| c.thresholds.low_rad_s = 0.5).contains("thresholds.low_rad_s"));
    assert!(err(&|c| c.thresholds.high_rad_s = f64::NAN).contains("thresholds.high_rad_s"));
    assert!(err(&|c| c.lateral.max = 3.0).contains("lateral.max"));
    assert!(err(&|c| c.dorsal.gains.stiffness = 1e9).contains("dorsal.gains.stiffness"));
    assert!(err(&|c| c.sections.mean_cycles = 0.0).contains("sections.mean_cycles"));
    assert!(err(&|c| c.sections.count = 0).contains("sections.count"));
    assert!(err(&|c| c.sections.count = 5).contains("sections.count"));
    assert!(
        err(&|c| {
            c.friction_offset = Some(FrictionOffset {
                lateral_rad: SectionValues::zeros(2),
                dorsal_rad: SectionValues::zeros(2),
            })
        })
        .contains("one per body section (3)")
    );
    assert!(
        err(&|c| {
            c.dorsal.enabled = true;
            c.dorsal.amplitude_rad = 1.0;
        })
        .contains("dorsal.amplitude_rad")
    );
    assert!(
        err(&|c| {
            c.friction_offset = Some(FrictionOffset {
                lateral_rad: SectionValues::from_slice(&[0.0, 9.0, 0.0]),
                dorsal_rad: SectionValues::zeros(3),
            })
        })
        .contains("friction_offset.lateral_rad[1]")
    );
    for (name, _) in DirectionalComplianceKind::PRESETS {
        preset(name).check().unwrap();
    }
    // A nominal amplitude outside the windows' range is refused.
    let (c, _, mut params) = engaged("dc_nc");
    params.amplitude_lat_rad = 1.4;
    c.accepts(&params).unwrap();
    params.amplitude_lat_rad = 1.55;
    assert_eq!(c.accepts(&params).unwrap_err().field, "amplitude_lat_rad");
    // A steering offset the widest window would carry past the joint limit is too.
    params.amplitude_lat_rad = 1.2;
    params.offset_lat_rad = 0.1;
    assert_eq!(c.accepts(&params).unwrap_err().field, "offset_lat_rad");
    // With a complying spatial frequency (`dc_full_*`), the nominal must lie in its
    // range (2π..4π); without, anything from π/4 to 8π.
    params.offset_lat_rad = 0.0;
    params.spatial_freq_rad = 1.5 * std::f64::consts::PI;
    c.accepts(&params).unwrap();
    let (c, ..) = engaged("dc_full_nc");
    assert_eq!(c.accepts(&params).unwrap_err().field, "spatial_freq_rad");
    params.spatial_freq_rad = 2.0 * std::f64::consts::PI;
    c.accepts(&params).unwrap();
    // Its gains are checked as the others' are.
    let mut config = preset("dc_switching");
    config.spatial_freq.gains.max = 30.0;
    let e = config.check().unwrap_err().to_string();
    assert!(e.contains("spatial_freq.gains.max"), "{e}");
}

/// Issue 25: the dorsal wave's nominal amplitude is checked while the wave is off too
/// (a planar preset stores and echoes it; turning the wave on later must not find 1e308).
#[test]
fn the_dorsal_amplitude_is_checked_while_the_dorsal_wave_is_off() {
    for bad in [1e308, -1.0, f64::NAN] {
        let mut c = preset("dc_switching");
        assert!(!c.dorsal.enabled);
        c.dorsal.amplitude_rad = bad;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("dorsal.amplitude_rad"), "{bad}: {e}");
        assert!(e.len() < 120, "{bad}: a readable message: {e}");
    }
}

/// The `dc_full_*` presets are the planar ones with the phase and the windows' spatial
/// frequency complying (what the lab measured as variants of them).
#[test]
fn the_full_presets_are_the_planar_ones_with_phase_and_spatial_frequency_complying() {
    for (full, base) in [
        ("dc_full_switching", "dc_switching"),
        ("dc_full_nc", "dc_nc"),
    ] {
        let mut b = preset(base);
        assert!(!b.phase.enabled && !b.spatial_freq.enabled, "{base}");
        b.phase.enabled = true;
        b.spatial_freq.enabled = true;
        assert_eq!(preset(full), b, "{full}");
    }
}
