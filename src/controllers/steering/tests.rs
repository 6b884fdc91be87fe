use super::*;

use std::f64::consts::TAU;

const DT: f64 = 1e-3;

fn body(heading_rad: f64) -> BodyEstimate {
    BodyEstimate {
        valid: true,
        heading_rad,
        ..BodyEstimate::default()
    }
}

fn engaged(config: SteeringConfig, omega: f64) -> HeadingHold {
    let mut h = HeadingHold::new(config);
    let params = GaitParams {
        temporal_freq_rad_s: omega,
        ..GaitParams::default()
    };
    h.engage(&params);
    h
}

/// Steps `h` for `seconds` at a fixed `heading`, from `t0`; the last offset.
fn run(h: &mut HeadingHold, t0: f64, seconds: f64, est: &BodyEstimate) -> f64 {
    let n = (seconds / DT).round() as usize;
    let mut last = 0.0;
    let mut prev = h.offset_rad();
    for k in 0..n {
        let dt = if k == 0 && t0 == 0.0 { 0.0 } else { DT };
        last = h.step(
            Tick {
                t_s: t0 + k as f64 * DT,
                dt_s: dt,
            },
            est,
            std::f64::consts::FRAC_PI_4,
        );
        let limit = h.config.rate_rad_s * DT + 1e-12;
        assert!((last - prev).abs() <= limit, "jumped {prev} -> {last}");
        prev = last;
    }
    last
}

#[test]
fn without_a_heading_it_does_not_steer() {
    let mut h = engaged(SteeringConfig::DEFAULT, 1.0);
    assert_eq!(run(&mut h, 0.0, 10.0, &body(1.0)), 0.0);
    assert_eq!(h.signals()[2], SteeringState::Off as u8 as f64);
    assert_eq!(h.signals()[1], 0.0);
}

#[test]
fn it_turns_toward_the_heading_by_the_measured_sign_and_slews() {
    let mut h = engaged(SteeringConfig::DEFAULT, 1.0);
    h.command(ControllerCommand::SetHeading {
        heading_rad: Some(0.5),
    })
    .unwrap();
    // Error +0.5 (left of the body): turn counter-clockwise, so a negative offset,
    // proportional to the error beyond the band less what the offset is already
    // turning (σ·G·φ/2 with the prior G): φ = −k·(e − 0.1), e = 0.5 − G·k·(e − 0.1)/2.
    let c = SteeringConfig::DEFAULT;
    let (g, k) = (
        c.sensitivity_prior,
        c.correct_per_cycle / c.sensitivity_prior,
    );
    let e = (0.5 + g * k * 0.1 / 2.0) / (1.0 + g * k / 2.0);
    let want = -k * (e - 0.1);
    // 0.026 rad at 0.1 rad/s: not there after 0.1 s, there after 1 s (within the
    // first cycle, before anything is learnt).
    let after = run(&mut h, 0.0, 0.1, &body(0.0));
    assert!(after > want + 0.01, "{after}");
    let after = run(&mut h, 0.1, 0.9, &body(0.0));
    assert!((after - want).abs() < 1e-6, "{after} vs {want}");
    assert_eq!(h.signals()[2], SteeringState::Turning as u8 as f64);
    assert!((h.signals()[1] - 0.5).abs() < 1e-9);
}

#[test]
fn backing_up_turns_the_other_way_and_the_band_holds_still() {
    let mut h = engaged(SteeringConfig::DEFAULT, -1.0);
    h.command(ControllerCommand::SetHeading {
        heading_rad: Some(0.5),
    })
    .unwrap();
    assert!(run(&mut h, 0.0, 3.0, &body(0.0)) > 0.02);
    let mut h = engaged(SteeringConfig::DEFAULT, 1.0);
    h.command(ControllerCommand::SetHeading {
        heading_rad: Some(0.05),
    })
    .unwrap();
    assert_eq!(run(&mut h, 0.0, 3.0, &body(0.0)), 0.0);
    assert_eq!(h.signals()[2], SteeringState::Holding as u8 as f64);
}

#[test]
fn the_offset_stays_within_the_joints_room() {
    let mut h = HeadingHold::new(SteeringConfig::DEFAULT);
    let params = GaitParams {
        temporal_freq_rad_s: 1.0,
        ..GaitParams::default()
    };
    h.engage(&params);
    h.command(ControllerCommand::SetHeading {
        heading_rad: Some(3.0),
    })
    .unwrap();
    // The amplitude's reach leaves 0.05 rad of room, then grows to leave 0.02.
    let mut last = 0.0;
    for (k, reach) in [(0, 0.05), (10_000, 0.02)] {
        for j in 0..10_000 {
            let t = (k + j) as f64 * DT;
            last = h.step(
                Tick { t_s: t, dt_s: DT },
                &body(0.0),
                JOINT_LIMIT_RAD - reach,
            );
            assert!(last.abs() <= reach + 1e-12, "{last} beyond {reach}");
        }
        assert!((last.abs() - reach).abs() < 1e-9, "{last}");
    }
}

#[test]
fn here_takes_the_heading_now_and_a_lost_estimate_returns_to_zero() {
    let mut h = engaged(SteeringConfig::DEFAULT, 1.0);
    h.command(ControllerCommand::SetHeading { heading_rad: None })
        .unwrap();
    assert_eq!(run(&mut h, 0.0, 1.0, &body(2.0)), 0.0);
    assert!(h.signals()[1].abs() < 1e-9, "nominal is the heading then");
    // Turned away by 1 rad: it steers back.
    let turning = run(&mut h, 1.0, 10.0, &body(1.0));
    assert!(turning.abs() > 0.04, "{turning}");
    // The estimate is lost: back to zero at the slew rate, and it says why.
    let lost = BodyEstimate::default();
    assert!(run(&mut h, 11.0, 0.5, &lost).abs() > 0.0);
    assert_eq!(run(&mut h, 11.5, 5.0, &lost), 0.0);
    assert_eq!(h.signals()[2], SteeringState::NoEstimate as u8 as f64);
}

#[test]
fn hold_at_engage_holds_the_first_heading_and_bad_headings_are_refused() {
    let config = SteeringConfig {
        hold_at_engage: true,
        ..SteeringConfig::DEFAULT
    };
    let mut h = engaged(config, 1.0);
    run(&mut h, 0.0, 0.1, &body(-0.7));
    assert!(h.signals()[1].abs() < 1e-9);
    assert_eq!(
        h.command(ControllerCommand::SetHeading {
            heading_rad: Some(f64::NAN)
        }),
        Err(CommandRefused::BadHeading)
    );
    assert_eq!(
        h.command(ControllerCommand::ClearCalibration),
        Err(CommandRefused::NothingToCalibrate)
    );
}

#[test]
fn settings_out_of_range_are_named() {
    let bad = SteeringConfig {
        max_offset_rad: 0.9,
        ..SteeringConfig::DEFAULT
    };
    assert!(
        bad.check()
            .unwrap_err()
            .to_string()
            .contains("max_offset_rad")
    );
    let bad = SteeringConfig {
        turn_sign: 0.5,
        ..SteeringConfig::DEFAULT
    };
    assert!(bad.check().unwrap_err().to_string().contains("turn_sign"));
    assert!(SteeringConfig::DEFAULT.check().is_ok());
}

/// A toy body that turns `g` rad per cycle per radian of offset (σ = −1 going
/// forwards, as measured), swaying ±0.2 rad with the wave: the hold learns `g` and
/// settles within the band without overshooting by more than the band, for the
/// default wave's 1.5 and the sleeve wave's 9 alike.
#[test]
fn it_learns_how_hard_the_wave_turns_and_settles_without_overshoot() {
    for g in [1.5, 9.0] {
        let mut h = engaged(SteeringConfig::DEFAULT, 1.0);
        h.command(ControllerCommand::SetHeading {
            heading_rad: Some(0.6),
        })
        .unwrap();
        let cycle = TAU;
        let (mut heading, mut worst_over) = (0.0_f64, 0.0_f64);
        let steps = (12.0 * cycle / DT) as usize;
        for k in 0..steps {
            let t = k as f64 * DT;
            let sway = 0.2 * (t * TAU / cycle).sin();
            let offset = h.step(Tick { t_s: t, dt_s: DT }, &body(heading + sway), 0.8);
            heading += -g * offset / cycle * DT;
            worst_over = worst_over.max(heading - 0.6);
        }
        let learnt = h.signals()[3];
        assert!((learnt - g).abs() < 0.3 * g, "g {g}: learnt {learnt}");
        assert!((heading - 0.6).abs() < 0.15, "g {g}: ended at {heading}");
        assert!(worst_over < 0.1, "g {g}: overshot by {worst_over}");
    }
}

/// A toy body that the terrain turns away at 0.3 rad per cycle while the offset turns
/// it back at G = 9 per radian (the sleeve wave among pegs): the proportional part
/// alone settles 0.3/(0.7·…) off, beyond the band; the integral, running while the
/// error grows, brings it back within the band and holds it there.
#[test]
fn the_integral_meets_a_turn_the_terrain_forces() {
    let run_toy = |integral_cycles: f64| {
        let config = SteeringConfig {
            integral_cycles,
            ..SteeringConfig::DEFAULT
        };
        let mut h = engaged(config, 1.0);
        h.command(ControllerCommand::SetHeading {
            heading_rad: Some(0.0),
        })
        .unwrap();
        let cycle = TAU;
        let mut heading = 0.0_f64;
        let steps = (20.0 * cycle / DT) as usize;
        let mut late = Vec::new();
        for k in 0..steps {
            let t = k as f64 * DT;
            let offset = h.step(Tick { t_s: t, dt_s: DT }, &body(heading), 0.8);
            heading += (0.3 - 9.0 * offset) / cycle * DT;
            if k > steps * 3 / 4 {
                late.push(heading.abs());
            }
        }
        late.iter().cloned().fold(0.0, f64::max)
    };
    let without = run_toy(0.0);
    let with = run_toy(SteeringConfig::DEFAULT.integral_cycles);
    println!("late worst error: proportional {without:.3}, with the integral {with:.3}");
    assert!(without > 0.15, "the proportional part alone: {without}");
    assert!(with < 0.12, "with the integral: {with} (without {without})");
}
