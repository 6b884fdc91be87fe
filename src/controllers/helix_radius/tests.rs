use super::*;
use crate::controller_interface::report::ControllerReport;
use crate::controller_interface::testing::{engage_at, run_with_torques};
use crate::controllers::open_loop::OpenLoop;

const N: usize = 18;

/// The coil alone: no slip guard (these tests have no pole to hold).
fn bare(mut c: HelixRadiusConfig) -> HelixRadiusConfig {
    c.slip.enabled = false;
    c
}

fn setup() -> (BodyLayout, GaitParams) {
    (
        BodyLayout::alternating(N, Plane::Lateral, 0.064),
        GaitParams::default_for(GaitKind::RollingHelix),
    )
}

#[test]
fn without_torque_or_squeeze_it_is_the_open_loop_helix() {
    let (layout, params) = setup();
    for mut config in [
        bare(HelixRadiusConfig::central().on_the_pole()),
        bare(HelixRadiusConfig::windowed().on_the_pole()),
    ] {
        config.gains.bias_force = 0.0;
        let mut open = OpenLoop::new(GaitKind::RollingHelix, &layout, &params);
        let mut c = HelixRadius::new(config, &layout, &params);
        engage_at(&mut open, &layout, &params, 0.0);
        engage_at(&mut c, &layout, &params, 0.0);
        // 13 s: more than a roll period, so half turns are born and dropped.
        let a = run_with_torques(&mut open, 13.0, |_| [0.0; N]);
        let b = run_with_torques(&mut c, 13.0, |_| [0.0; N]);
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() < 1e-9,
                "windowed {}: {x} vs {y}",
                config.windowed
            );
        }
        assert!(
            c.window_count() >= usize::from(config.windowed) * 2 + 1 - usize::from(config.windowed)
        );
    }
}

/// Windowed, a push on the head's joints tightens the half turns there, not the
/// tail's: each window collects only its joints' torques.
#[test]
fn a_window_answers_only_its_own_joints() {
    let (layout, params) = setup();
    let mut config = HelixRadiusConfig::windowed().on_the_pole();
    config.gains.bias_force = 0.0;
    let mut c = HelixRadius::new(config, &layout, &params);
    engage_at(&mut c, &layout, &params, 0.0);
    // The head's joints bent further by the environment (reported against the bend):
    // compliant, those windows tighten.
    run_with_torques(&mut c, 0.5, |sp| {
        let mut tau = [0.0; N];
        for (i, (t, &x)) in tau.iter_mut().zip(sp).enumerate() {
            if i < 6 {
                *t = -2.0 * x.signum();
            }
        }
        tau
    });
    let mut report = ControllerReport::EMPTY;
    c.report(&mut report);
    let f = &report.fields[0];
    assert!(f.len() >= 3, "{}", f.len());
    let rho = &f.columns[0][..f.len()];
    // The windows over the pushed joints (s < 0.32) tighten; the tail's stays.
    let pushed = (0..f.len()).filter(|&k| f.a[k] < 0.3).map(|k| rho[k]);
    assert!(pushed.fold(0.0f64, f64::max) > 1.05, "{rho:?}");
    assert!((rho[f.len() - 1] - 1.0).abs() < 1e-3, "tail window {rho:?}");
}

/// In the air the squeeze tightens the coil to `1 + τ_D/K` (here past its bound, so to
/// the bound); a pole pushing back on the bend stops it short, and the harder it
/// pushes the less the coil tightens.
#[test]
fn the_squeeze_tightens_the_coil_until_the_pole_pushes_back() {
    let (layout, params) = setup();
    let config = bare(HelixRadiusConfig::central().on_the_pole());
    let tightened = |push_nm: f64| {
        let mut c = HelixRadius::new(config, &layout, &params);
        engage_at(&mut c, &layout, &params, 0.0);
        // The pole resists the bend: the environment's torque opposes each joint's
        // angle, so the reported (spring) torque is along it.
        run_with_torques(&mut c, 6.0, |sp| {
            let mut tau = [0.0; N];
            for (t, &x) in tau.iter_mut().zip(sp) {
                *t = push_nm * x.signum() * f64::from(u8::from(x.abs() > 0.05));
            }
            tau
        });
        c.radius_scale()
    };
    let (air, soft, hard) = (tightened(0.0), tightened(0.5), tightened(1.5));
    assert!((air - config.gains.max).abs() < 1e-9, "{air}");
    assert!(soft > 1.0 && soft < air, "{soft} vs {air}");
    assert!(hard < soft, "{hard} vs {soft}");
}

#[test]
fn a_coil_the_bound_would_tighten_past_the_joints_is_refused() {
    let (layout, mut params) = setup();
    let c = HelixRadius::new(HelixRadiusConfig::central().on_the_pole(), &layout, &params);
    assert!(c.accepts(&params).is_ok());
    params.helix_radius_m = 0.07;
    params.helix_pitch_m = 0.028;
    let e = c.accepts(&params).unwrap_err();
    assert_eq!(e.field, "helix_radius_m");
    assert!(e.min > 0.07 && e.min < 0.1, "{e}");
    // The suggested radius is accepted.
    params.helix_pitch_m *= e.min / params.helix_radius_m;
    params.helix_radius_m = e.min;
    assert!(c.accepts(&params).is_ok(), "{:?}", c.accepts(&params));
}

#[test]
fn the_configuration_is_checked() {
    let mut c = HelixRadiusConfig::central().on_the_pole();
    assert!(c.check().is_ok());
    c.gains.min = 1.1;
    assert!(c.check().unwrap_err().to_string().contains("gains"));
    let mut c = HelixRadiusConfig::central().on_the_pole();
    c.gains.max = 5.0;
    assert!(c.check().unwrap_err().to_string().contains("gains.max"));
    let mut c = HelixRadiusConfig::central().on_the_pole();
    c.torque_cutoff_hz = f64::NAN;
    assert!(c.check().is_err());
}

/// A pole the coil fits at ρ = `fit`: tighter than that, every bent joint is pushed
/// back (reported torque along its bend) in proportion to how much tighter. Returns ρ,
/// its set point and the grip after `seconds`.
fn on_a_modelled_pole(config: HelixRadiusConfig, fit: f64, seconds: f64) -> (f64, f64, f64) {
    let (layout, params) = setup();
    let a0 = nominal_wave(&layout, &params).0;
    let mut c = HelixRadius::new(config, &layout, &params);
    engage_at(&mut c, &layout, &params, 0.0);
    run_with_torques(&mut c, seconds, |sp| {
        let rho = sp.iter().fold(0.0f64, |m, x| m.max(x.abs())) / a0;
        let push = 20.0 * (rho - fit).max(0.0);
        let mut tau = [0.0; N];
        for (t, &x) in tau.iter_mut().zip(sp) {
            *t = push * x.signum() * f64::from(u8::from(x.abs() > 0.05));
        }
        tau
    });
    let mut report = ControllerReport::EMPTY;
    c.report(&mut report);
    (c.radius_scale(), report.signals[6], report.signals[7])
}

/// The adaptive set point follows the pole: on a thinner one (the coil fits only at
/// ρ 1.2) the plain squeeze spends much of itself on the spring and grips lightly
/// (below the band), the adaptive set point tightens until the grip is inside its band;
/// a crushing grip (every bent joint pushed back by 4 N·m) opens it at its rate.
#[test]
fn the_adaptive_set_point_keeps_the_grip_in_its_band() {
    let (plain, adaptive) = (
        bare(HelixRadiusConfig::central().on_the_pole()),
        bare(HelixRadiusConfig::central_adaptive().on_the_pole()),
    );
    let a = adaptive.adaptive;
    let (_, set_plain, grip_plain) = on_a_modelled_pole(plain, 1.2, 60.0);
    let (rho, set, grip) = on_a_modelled_pole(adaptive, 1.2, 60.0);
    assert_eq!(set_plain, 1.0);
    assert!(grip_plain < a.low_nm, "plain grip {grip_plain}");
    assert!(
        (a.low_nm..=a.high_nm).contains(&grip) && set > 1.1,
        "adaptive grip {grip}, ρ {rho}, set point {set}"
    );

    let (layout, params) = setup();
    let mut c = HelixRadius::new(adaptive, &layout, &params);
    engage_at(&mut c, &layout, &params, 0.0);
    run_with_torques(&mut c, 5.0, |sp| {
        let mut tau = [0.0; N];
        for (t, &x) in tau.iter_mut().zip(sp) {
            *t = 4.0 * x.signum() * f64::from(u8::from(x.abs() > 0.05));
        }
        tau
    });
    let mut report = ControllerReport::EMPTY;
    c.report(&mut report);
    let (set, grip) = (report.signals[6], report.signals[7]);
    assert!(grip > a.high_nm, "{grip}");
    assert!(
        (set - (1.0 - 5.0 * a.rate_per_s)).abs() < 0.01,
        "set point {set}"
    );
}

/// Safety on the pole: the grip lost (no torque from the pole) the roll holds and the
/// squeeze rises; the grip back, the roll resumes. A fall (the IMUs' specific force
/// near zero) acts at once.
#[test]
fn a_lost_grip_holds_the_roll_and_squeezes_until_it_is_back() {
    use crate::controller_interface::{BodyEstimate, Imu};
    let (layout, params) = setup();
    let config = HelixRadiusConfig::central().on_the_pole();
    let mut c = HelixRadius::new(config, &layout, &params);
    engage_at(&mut c, &layout, &params, 0.0);
    let resting = [Imu {
        accel_m_s2: [0.0, 0.0, 9.81],
        gyro_rad_s: [0.0; 3],
    }; N];
    let falling = [Imu::default(); N];
    let body = BodyEstimate::default();
    let (pos, vel, mut out) = ([0.0; N], [0.0; N], vec![0.0; N]);
    let mut report = ControllerReport::EMPTY;
    let mut t = 0.0;
    let mut clock = crate::controller_interface::TickClock::default();
    // Steps `seconds` with the pole pushing back by `push_nm` (0: no pole) and the
    // IMUs given; returns the phase advance and the report's slipping, slips, squeeze.
    let mut run = |c: &mut HelixRadius, seconds: f64, push_nm: f64, imu: &[Imu]| {
        let phase = c.phase;
        for _ in 0..(seconds * 1000.0) as usize {
            t += 1e-3;
            let mut tau = [0.0; N];
            for (x, &sp) in tau.iter_mut().zip(&out) {
                *x = push_nm * f64::signum(sp);
            }
            let obs = Observation {
                position_rad: &pos,
                velocity_rad_s: &vel,
                torque_nm: &tau,
                imu,
                body: &body,
            };
            c.step(clock.tick(t), &obs, &mut out);
        }
        c.report(&mut report);
        let sig = |name: &str| {
            let i = HelixRadiusKind::report_spec(&config, &ctx(&layout, &params))
                .signals
                .iter()
                .position(|s| s.name == name)
                .unwrap();
            report.signals[i]
        };
        (c.phase - phase, sig("slipping"), sig("slips"))
    };
    let wt = params.temporal_freq_rad_s;
    let (advance, slipping, slips) = run(&mut c, 3.0, 1.0, &resting);
    assert!((advance - 3.0 * wt).abs() < 0.01, "climbing: {advance}");
    assert_eq!((slipping, slips), (0.0, 0.0));
    let rho_held = c.radius_scale();
    let (advance, slipping, slips) = run(&mut c, 2.0, 0.0, &resting);
    // The grace (0.3 s) and the torque filter's lag, then nothing (2 s would be 1 rad).
    assert!(
        advance < 0.5 * wt,
        "the roll holds after the grace: {advance}"
    );
    assert_eq!((slipping, slips), (1.0, 1.0));
    assert!(
        c.radius_scale() > rho_held + 0.05,
        "squeezed: {} vs {rho_held}",
        c.radius_scale()
    );
    let (advance, slipping, _) = run(&mut c, 0.5, 1.0, &resting);
    assert!(
        advance.abs() < 1e-12 && slipping == 1.0,
        "not yet recovered"
    );
    let (advance, slipping, slips) = run(&mut c, 2.0, 1.0, &resting);
    assert!(advance > 0.9 * wt, "rolls on: {advance}");
    assert_eq!((slipping, slips), (0.0, 1.0));
    let (advance, slipping, slips) = run(&mut c, 0.01, 1.0, &falling);
    assert!(
        advance < 0.01 * wt && slipping == 1.0 && slips == 2.0,
        "a fall acts at once"
    );
}

fn ctx<'a>(layout: &'a BodyLayout, params: &'a GaitParams) -> BuildContext<'a> {
    BuildContext {
        gait: GaitKind::RollingHelix,
        layout,
        params,
    }
}

/// Issue 45: a change of speed alone is followed (the coil rolls on, no step); a change
/// of the helix is a fresh takeover.
#[test]
fn it_follows_a_change_of_speed_but_not_of_the_helix() {
    use crate::controller_interface::TickClock;
    use crate::controller_interface::testing::ObservationBuf;
    let (layout, params) = setup();
    let mut config = bare(HelixRadiusConfig::windowed().on_the_pole());
    config.gains.bias_force = 0.0;
    let mut c = HelixRadius::new(config, &layout, &params);
    engage_at(&mut c, &layout, &params, 0.0);
    let buf = ObservationBuf::new(N);
    let (pos, tau) = ([0.0; N], [0.0; N]);
    let (mut out, mut last) = (vec![0.0; N], vec![0.0; N]);
    let mut clock = TickClock::default();
    let mut largest = 0.0f64;
    for k in 0..6000 {
        let t = k as f64 * 1e-3;
        if k == 2000 || k == 4000 {
            let mut faster = params;
            faster.temporal_freq_rad_s *= if k == 2000 { 1.5 } else { 0.5 };
            c.follow(t, &faster).expect("a change of speed is followed");
        }
        c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut out);
        if k > 0 {
            let step = out.iter().zip(&last).map(|(a, b)| (a - b).abs());
            largest = largest.max(step.fold(0.0, f64::max));
        }
        last.copy_from_slice(&out);
    }
    assert!(
        largest < 3.46e-3,
        "a set-point jumped {largest} rad in 1 ms"
    );
    let mut wider = params;
    wider.helix_radius_m *= 1.1;
    assert!(c.follow(6.0, &wider).is_err(), "a new helix is a takeover");
}
