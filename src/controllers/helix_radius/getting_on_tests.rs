use super::*;
use crate::gait::Plane;

const N: usize = 18;

fn setup() -> (BodyLayout, GaitParams) {
    (
        BodyLayout::alternating(N, Plane::Lateral, 0.064),
        GaitParams::default_for(GaitKind::RollingHelix),
    )
}

fn imu(up: [f64; 3]) -> Vec<Imu> {
    vec![
        Imu {
            accel_m_s2: up.map(|x| 9.81 * x),
            gyro_rad_s: [0.0; 3],
        };
        N
    ]
}

/// Runs the sequence from a straight handover at t = 0 to `until_s` with the IMUs
/// reading `up` and the grip given; returns the last output.
fn run(g: &mut GettingOn, until_s: f64, up: [f64; 3], grip: f64) -> Vec<f64> {
    let (imu, pos) = (imu(up), [0.0; N]);
    let mut out = vec![0.0; N];
    let mut last = out.clone();
    let steps = (until_s * 1000.0) as usize;
    for k in 0..=steps {
        let t = k as f64 * 1e-3;
        g.update(t, &pos, &imu, grip);
        out.fill(0.3);
        g.mix(t, &mut out);
        let jump = out
            .iter()
            .zip(&last)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Straight at the takeover, then nothing faster than the SEA's joints.
        assert!(
            jump < 3e-3 || k == 0,
            "a jump of {jump} rad at {t} s in {:?}",
            g.stage()
        );
        last.copy_from_slice(&out);
    }
    out
}

/// Where the lap bends the middle, as a unit vector in the middle link's frame.
fn bend(layout: &BodyLayout, angles: &[f64]) -> Vector3<f64> {
    let mut poses = vec![Isometry3::identity(); N + 1];
    link_poses(Isometry3::identity(), layout, angles, &mut poses);
    let m = N / 2;
    let inv = poses[m].inverse();
    let at = |p: &Isometry3<f64>| inv * Point3::from(p.translation.vector);
    let c = at(&poses[m - 1]).coords + at(&poses[m + 1]).coords;
    Vector3::new(0.0, c.y, c.z).normalize()
}

#[test]
fn the_lap_bends_the_middle_towards_the_pole_whatever_the_roll() {
    let (layout, params) = setup();
    for side in [PoleSide::Left, PoleSide::Right] {
        for k in 0..8 {
            let roll = k as f64 * std::f64::consts::FRAC_PI_4;
            // The body rolled by `roll` about its axis: up in its frame turns by −roll.
            let up = [0.0, roll.sin(), roll.cos()];
            let config = GettingOnConfig {
                side,
                ..GettingOnConfig::default()
            };
            let mut g = GettingOn::new(config, &layout);
            assert_eq!(g.engage(0.0, &[0.0; N], &params), Stage::Straighten);
            let c = config;
            let lapped = run(&mut g, c.straighten_s + c.measure_s + c.lap_s, up, 0.0);
            assert_eq!(g.stage(), Stage::Open);
            // Left of the body (x towards the head): up × x.
            let left = Vector3::new(0.0, up[2], -up[1]);
            let toward = if side == PoleSide::Left { left } else { -left };
            let b = bend(&layout, &lapped);
            assert!(
                b.dot(&toward) > 0.99,
                "{side:?} roll {roll:.2}: bends {b:?}, the pole is {toward:?}"
            );
        }
    }
}

#[test]
fn the_sequence_opens_into_the_coil_and_climbs_with_the_head_up_or_down() {
    let (layout, params) = setup();
    let mut g = GettingOn::new(GettingOnConfig::default(), &layout);
    g.engage(0.0, &[0.0; N], &params);
    let c = GettingOnConfig::default();
    let end = c.straighten_s + c.measure_s + c.lap_s + c.open_s;
    assert!((g.roll_start_s() - end).abs() < 1e-12);
    // The coil mixed in is 0.3 everywhere: after the opening the output is it.
    let out = run(&mut g, end + 0.01, [0.0, 0.0, 1.0], 2.0);
    assert_eq!(g.stage(), Stage::Climb);
    assert!(out.iter().all(|&x| (x - 0.3).abs() < 1e-12), "{out:?}");
    assert_eq!(g.attempts(), 0);
    // A straight body level with gravity: the tail is not above the head.
    assert_eq!(g.direction(), 1.0);
}

#[test]
fn a_missed_lap_is_tried_again_wider_then_given_up() {
    let (layout, params) = setup();
    let c = GettingOnConfig::default();
    let mut g = GettingOn::new(c, &layout);
    g.engage(0.0, &[0.0; N], &params);
    let once = c.straighten_s + c.measure_s + c.lap_s + c.open_s;
    run(&mut g, once + 0.01, [0.0, 0.0, 1.0], 0.1);
    assert_eq!((g.stage(), g.attempts()), (Stage::Straighten, 1));
    // The retries restart the clock; after the last the coil climbs whatever the grip.
    let mut g = GettingOn::new(c, &layout);
    g.engage(0.0, &[0.0; N], &params);
    run(&mut g, 3.0 * once + 0.1, [0.0, 0.0, 1.0], 0.1);
    assert_eq!((g.stage(), g.attempts()), (Stage::Climb, c.retries));
}

#[test]
fn a_coiled_handover_resumes_at_its_own_phase_without_lapping() {
    let (layout, params) = setup();
    let coil = Serpenoid::for_layout(GaitKind::RollingHelix, &params, &layout);
    let mut pose = vec![0.0; N];
    coil.evaluate(&layout, 1.0, &mut pose);
    let mut g = GettingOn::new(GettingOnConfig::default(), &layout);
    assert_eq!(g.engage(5.0, &pose, &params), Stage::Resume);
    assert!((g.coil_phase() - 1.0).abs() <= std::f64::consts::PI / PHASES as f64 + 1e-9);
    assert_eq!(g.roll_start_s(), 5.0);
    // Off: nothing of it.
    let off = GettingOnConfig {
        enabled: false,
        ..GettingOnConfig::default()
    };
    let mut g = GettingOn::new(off, &layout);
    assert_eq!(g.engage(5.0, &[0.0; N], &params), Stage::Off);
    assert!(g.coil_active());
}

#[test]
fn the_configuration_is_checked() {
    assert!(GettingOnConfig::default().check().is_ok());
    let bad = GettingOnConfig {
        lap_s: 0.0,
        ..GettingOnConfig::default()
    };
    let e = bad.check().unwrap_err().to_string();
    assert!(e.contains("getting_on") && e.contains("lap_s"), "{e}");
}
