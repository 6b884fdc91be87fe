use crate::controller_interface::TickClock;
use std::f64::consts::PI;

use super::*;
use crate::controller_interface::testing::engage_at;
use crate::controller_interface::{BodyEstimate, Imu};
use crate::controllers::open_loop::OpenLoop;
use crate::gait::{GaitKind, Plane};
use crate::module::MODULE_LENGTH_M;

const N: usize = 18;

fn layout() -> BodyLayout {
    BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M)
}

fn params() -> GaitParams {
    GaitParams::default_for(GaitKind::Sidewinding)
}

fn preset(name: &str) -> AntiCompliantSidewinding {
    AntiCompliantSidewinding::new(
        &layout(),
        &params(),
        SidewindingConfig::preset(name).unwrap(),
    )
}

fn body(heading_rad: f64) -> BodyEstimate {
    BodyEstimate {
        valid: true,
        heading_rad,
        ..BodyEstimate::default()
    }
}

/// Runs `c` (engaged at `t0`) for `seconds` with the estimate's heading `heading(t)` and
/// lateral torques `torque(t)`; returns every step's set-points.
fn run(
    c: &mut dyn Controller,
    t0: f64,
    seconds: f64,
    heading: impl Fn(f64) -> f64,
    torque: impl Fn(f64) -> [f64; N],
) -> Vec<Vec<f64>> {
    let (pos, vel, imu) = ([0.0; N], [0.0; N], [Imu::default(); N]);
    let mut out = vec![0.0; N];
    let mut all = Vec::new();
    let mut clock = TickClock::default();
    for k in 0..(seconds * 1000.0) as usize {
        let t = t0 + k as f64 * 1e-3;
        let (b, tau) = (body(heading(t)), torque(t));
        let obs = Observation {
            position_rad: &pos,
            velocity_rad_s: &vel,
            torque_nm: &tau,
            imu: &imu,
            body: &b,
        };
        c.step(clock.tick(t), &obs, &mut out);
        all.push(out.clone());
    }
    all
}

fn signal(c: &dyn Controller, k: usize) -> f64 {
    let mut r = ControllerReport::EMPTY;
    c.report(&mut r);
    r.signals[k]
}

const BETA: usize = 0;
const TAPER: usize = 4;
const REVERSALS: usize = 5;
const AMPLITUDE: usize = 7;

#[test]
fn every_preset_accepts_the_default_gait_and_refuses_no_room_for_the_taper() {
    for (name, _) in SidewindingConfig::PRESETS {
        preset(name).accepts(&params()).unwrap();
    }
    let mut wide = params();
    wide.offset_lat_rad = 0.2; // 1.1 × 1.4 + 0.2 > π/2
    let e = preset("ac_sfc").accepts(&wide).unwrap_err();
    assert_eq!(e.field, "offset_lat_rad");
}

#[test]
fn at_its_heading_without_torque_every_preset_is_the_open_loop_gait() {
    let (l, p) = (layout(), params());
    let mut open = OpenLoop::new(GaitKind::Sidewinding, &l, &p);
    engage_at(&mut open, &l, &p, 1.0);
    let reference = run(&mut open, 1.0, 7.0, |_| 0.3, |_| [0.0; N]);
    for (name, _) in SidewindingConfig::PRESETS {
        let mut c = preset(name);
        engage_at(&mut c, &l, &p, 1.0);
        // The heading it holds: the nominal turned by its lead (towards the travel).
        let lead = SidewindingConfig::preset(name).unwrap().heading.lead_rad;
        let nominal = crate::controller_interface::ControllerCommand::SetHeading {
            heading_rad: Some(0.3 + lead),
        };
        c.command(nominal).unwrap();
        let got = run(&mut c, 1.0, 7.0, |_| 0.3, |_| [0.0; N]);
        // The reversal reads the heading from the nominal, not from the held one, so
        // with a lead β rests a little off its well (−0.19 rad after 7 s at 0.4), and the
        // dorsal wave shifts by that.
        let tolerance = if lead == 0.0 { 1e-9 } else { 0.1 };
        for (a, b) in got.iter().zip(&reference) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() < tolerance, "{name}: {x} vs {y}");
            }
        }
        let beta = wrap_pi(signal(&c, BETA));
        assert!(beta.abs() < 2.5 * tolerance, "{name}: β {beta}");
        assert_eq!(signal(&c, TAPER), 0.0);
    }
}

#[test]
fn a_body_turned_round_reverses_the_dorsal_wave_without_a_jump() {
    let (l, p) = (layout(), params());
    let mut c = preset("sw_open_loop");
    engage_at(&mut c, &l, &p, 0.0);
    // The heading holds for 2 s, then a peg turns the body round.
    let heading = |t: f64| if t < 2.0 { 0.1 } else { 0.1 + PI };
    let all = run(&mut c, 0.0, 12.0, heading, |_| [0.0; N]);
    assert!(
        wrap_pi(c.beta_rad() - PI).abs() < 0.05,
        "β {}",
        c.beta_rad()
    );
    assert_eq!(signal(&c, REVERSALS), 1.0);
    // The dorsal wave is the nominal one shifted by π: every dorsal joint inverted
    // about its offset, the lateral wave untouched (the taper is back to 0 by now,
    // the heading being on the reversed nominal).
    let mut open = OpenLoop::new(GaitKind::Sidewinding, &l, &p);
    engage_at(&mut open, &l, &p, 0.0);
    let reference = run(&mut open, 0.0, 12.0, |_| 0.0, |_| [0.0; N]);
    let (last, nominal) = (all.last().unwrap(), reference.last().unwrap());
    assert!(c.taper().abs() < 1e-9, "taper {}", c.taper());
    for (i, plane) in l.planes.iter().enumerate() {
        let expect = match plane {
            Plane::Lateral => nominal[i],
            Plane::Dorsal => -nominal[i],
        };
        assert!(
            (last[i] - expect).abs() < 0.02,
            "joint {i}: {} vs {expect}",
            last[i]
        );
    }
    // Smoothly: no set-point moves more per millisecond than the gait itself does
    // plus β's rate limit through the dorsal amplitude.
    let limit = (p.amplitude_lat_rad * p.temporal_freq_rad_s
        + p.amplitude_dor_rad * SidewindingConfig::full().reversal.max_rate_rad_s)
        * 1e-3
        * 1.01;
    for w in all.windows(2) {
        for (a, b) in w[0].iter().zip(&w[1]) {
            assert!((a - b).abs() <= limit, "{} per ms", (a - b).abs());
        }
    }
}

#[test]
fn off_its_heading_it_tapers_into_conical_sidewinding_and_back() {
    let (l, p) = (layout(), params());
    let mut c = preset("ac_sfc");
    engage_at(&mut c, &l, &p, 0.0);
    let turn = SidewindingConfig::full().heading;
    // Nominal heading 0 (the first), then 0.6 rad off (outside the 0.35 dead-band,
    // inside the reversal's switch), then back.
    run(&mut c, 0.0, 0.5, |_| 0.0, |_| [0.0; N]);
    run(&mut c, 0.5, 6.0, |_| 0.6, |_| [0.0; N]);
    let want = -turn.turn_sign * turn.turn_taper;
    assert!((c.taper() - want).abs() < 1e-9, "taper {}", c.taper());
    assert_eq!(signal(&c, REVERSALS), 0.0, "0.6 rad does not reverse");
    run(&mut c, 6.5, 6.0, |_| 0.05, |_| [0.0; N]);
    assert!(c.taper().abs() < 1e-9, "back to straight: {}", c.taper());
}

#[test]
fn anti_compliance_pushes_back_where_compliance_gives_way() {
    let (l, p) = (layout(), params());
    // A steady push on the middle lateral joints, against the wave's sign there.
    let push = |t: f64| {
        let mut tau = [0.0; N];
        for (i, x) in tau.iter_mut().enumerate().take(12).skip(6) {
            if i % 2 == 0 {
                *x = 2.0 * (3.0 * PI * (i as f64 / N as f64) - t).sin().signum();
            }
        }
        tau
    };
    let mut anti = preset("ac");
    let mut cfg = SidewindingConfig::preset("ac").unwrap();
    cfg.sign = crate::shape::admittance::AdmittanceSign::Compliant;
    let mut soft = AntiCompliantSidewinding::new(&l, &p, cfg);
    engage_at(&mut anti, &l, &p, 0.0);
    engage_at(&mut soft, &l, &p, 0.0);
    run(&mut anti, 0.0, 3.0, |_| 0.0, push);
    run(&mut soft, 0.0, 3.0, |_| 0.0, push);
    let (a, s) = (signal(&anti, AMPLITUDE), signal(&soft, AMPLITUDE));
    let nominal = p.amplitude_lat_rad;
    assert!(
        (a - nominal) * (s - nominal) < 0.0 && (a - nominal).abs() > 1e-3,
        "anti {a}, compliant {s}, nominal {nominal}"
    );
}

#[test]
fn the_nominal_heading_is_an_operator_command() {
    let (l, p) = (layout(), params());
    let mut c = preset("ac_sfc");
    engage_at(&mut c, &l, &p, 0.0);
    assert_eq!(
        c.command(ControllerCommand::SetHeading {
            heading_rad: Some(f64::NAN)
        }),
        Err(CommandRefused::BadHeading)
    );
    assert_eq!(
        c.command(ControllerCommand::Calibrate { duration_s: 1.0 }),
        Err(CommandRefused::NothingToCalibrate)
    );
    // Nominal 1.0 while the body heads at 0: outside the dead-band, it turns.
    c.command(ControllerCommand::SetHeading {
        heading_rad: Some(1.0),
    })
    .unwrap();
    run(&mut c, 0.0, 3.0, |_| 0.0, |_| [0.0; N]);
    assert!(c.taper().abs() > 0.3, "{}", c.taper());
    assert!((signal(&c, 2) - 1.0).abs() < 1e-12, "reported nominal");
    // "Here": the heading now becomes the nominal, and the taper blends out.
    c.command(ControllerCommand::SetHeading { heading_rad: None })
        .unwrap();
    run(&mut c, 3.0, 4.0, |_| 0.0, |_| [0.0; N]);
    assert!(signal(&c, 2).abs() < 1e-9);
    assert!(c.taper().abs() < 1e-9);
}

#[test]
fn without_a_valid_estimate_it_sidewinds_straight_and_holds_beta() {
    let (l, p) = (layout(), params());
    let mut c = preset("ac_sfc");
    engage_at(&mut c, &l, &p, 0.0);
    let (pos, vel, imu, tau) = ([0.0; N], [0.0; N], [Imu::default(); N], [0.0; N]);
    let invalid = BodyEstimate::default();
    let mut out = [0.0; N];
    let mut clock = TickClock::default();
    for k in 0..3000 {
        let obs = Observation {
            position_rad: &pos,
            velocity_rad_s: &vel,
            torque_nm: &tau,
            imu: &imu,
            body: &invalid,
        };
        c.step(clock.tick(k as f64 * 1e-3), &obs, &mut out);
    }
    assert_eq!((c.beta_rad(), c.taper()), (0.0, 0.0));
    assert!(c.heading_rad().is_none());
    assert_eq!(signal(&c, 6), 0.0, "heading_valid");
    assert!(signal(&c, 1).is_nan(), "no heading to report");
}

#[test]
fn a_leading_head_is_held_turned_towards_the_travel_either_way_round() {
    let (l, p) = (layout(), params());
    let mut config = SidewindingConfig::preset("ac_sfc").unwrap();
    config.heading.lead_rad = 0.5;
    let mut c = AntiCompliantSidewinding::new(&l, &p, config);
    engage_at(&mut c, &l, &p, 0.0);
    const ERROR: usize = 3;
    // Nominal 0 (the first heading). At the nominal, the held heading (0.5 rad towards
    // the travel, which is clockwise of the head) is behind: the error reads +0.5 and
    // the body turns clockwise, as it does 0.5 rad anticlockwise of a plain nominal.
    run(&mut c, 0.0, 0.5, |_| 0.0, |_| [0.0; N]);
    assert!(
        (signal(&c, ERROR) - 0.5).abs() < 1e-6,
        "{}",
        signal(&c, ERROR)
    );
    run(&mut c, 0.5, 6.0, |_| 0.0, |_| [0.0; N]);
    let mut plain = preset("ac_sfc");
    engage_at(&mut plain, &l, &p, 0.0);
    run(&mut plain, 0.0, 0.5, |_| 0.0, |_| [0.0; N]);
    run(&mut plain, 0.5, 6.0, |_| 0.5, |_| [0.0; N]);
    assert!(c.taper().abs() > 0.1, "turning: {}", c.taper());
    assert!((c.taper() - plain.taper()).abs() < 1e-9);
    // Turned round (reversed, the π well), the travel lies anticlockwise of the head:
    // the lead is mirrored, so the body held 0.5 rad anticlockwise of π is on course.
    run(&mut c, 6.5, 10.0, |_| PI, |_| [0.0; N]);
    assert_eq!(signal(&c, REVERSALS), 1.0, "β {}", c.beta_rad());
    run(&mut c, 16.5, 5.0, |_| PI + 0.5, |_| [0.0; N]);
    assert!(signal(&c, ERROR).abs() < 0.01, "{}", signal(&c, ERROR));
}
