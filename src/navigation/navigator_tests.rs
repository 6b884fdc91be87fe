//! The navigator's tests: its plan by heading, and to a goal by position.
use super::*;
use crate::navigation::stuck::StuckReason;

fn view(stuck: bool) -> NavView {
    NavView {
        running: true,
        estimate_valid: true,
        heading_rad: 2.0,
        position: None,
        progress: ProgressReport {
            stuck,
            reason: if stuck {
                StuckReason::TorquesRepeat
            } else {
                StuckReason::Changing
            },
            ..ProgressReport::NONE
        },
    }
}

/// Turning in place when the body lies more than 0.6 rad from across (v4-v5; off by
/// default since it measured worse than sidewinding's own slow turn).
const TURNING: NavigatorConfig = NavigatorConfig {
    turn_above_rad: 0.6,
    ..NavigatorConfig::DEFAULT
};

#[test]
fn sidewinds_backs_off_when_stuck_then_slithers_and_returns() {
    let c = NavigatorConfig::DEFAULT;
    let mut n = Navigator::new(c, 0.3);
    // Nothing while the estimate is not valid.
    let mut v = view(false);
    v.estimate_valid = false;
    assert_eq!(n.step(0.0, &v), None);
    let d = n.step(0.1, &view(false)).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Start));
    assert!((d.heading_rad - (0.3 + std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
    // Stuck too soon after a change is not acted on.
    assert_eq!(n.step(1.0, &view(true)), None);
    let d = n.step(0.1 + c.settle_s, &view(true)).unwrap();
    assert_eq!((d.choice, d.why), (Choice::BackOff, Why::Stuck));
    assert!(
        (crate::num::wrap_pi(d.heading_rad - (0.3 - std::f64::consts::FRAC_PI_2))).abs() < 1e-12
    );
    let t = 0.1 + c.settle_s + c.back_off_s;
    let d = n.step(t, &view(false)).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Slither, Why::BackedOff));
    assert!((d.heading_rad - 0.3).abs() < 1e-12);
    let d = n.step(t + c.slither_max_s, &view(false)).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::SlitherTimeUp));
    assert_eq!(n.switches(), 3);
    assert_eq!(n.current(), Some((Choice::Sidewind, Why::SlitherTimeUp)));
}

#[test]
fn a_body_heading_the_way_slithers_first_then_turns_across_and_sidewinds() {
    let c = TURNING;
    let mut n = Navigator::new(c, 0.3);
    let mut v = view(false);
    v.heading_rad = 0.3 + 0.7;
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Slither, Why::Start));
    // Stuck soon: slithering cannot move here, and the body lies along the way, so
    // it turns round (to the nearer of the two ways across) before sidewinding.
    v.progress = view(true).progress;
    let d = n.step(c.settle_s, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Turn, Why::Stuck));
    assert!(n.slither_fails());
    let across = 0.3 + std::f64::consts::FRAC_PI_2;
    assert!((d.heading_rad - across).abs() < 1e-12, "{d:?}");
    assert_eq!(d.choice.controller(), "open_loop");
    // Not yet across: goes on turning.
    v.progress = view(false).progress;
    v.heading_rad = across - 0.5;
    assert_eq!(n.step(c.settle_s + 5.0, &v), None);
    v.heading_rad = across - 0.2;
    let d = n.step(c.settle_s + 10.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Turned));
    assert!((d.heading_rad - across).abs() < 1e-12, "{d:?}");
    // Stuck sidewinding backs off, and then, slithering having failed, sidewinds.
    v.progress = view(true).progress;
    let t = c.settle_s + 10.0 + c.settle_s;
    let d = n.step(t, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::BackOff, Why::Stuck));
    let d = n.step(t + c.back_off_s, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::BackedOff));
    assert_eq!(n.switches(), 4);
    for bad in [
        NavigatorConfig {
            slither_within_rad: 4.0,
            ..c
        },
        NavigatorConfig {
            turn_done_rad: c.turn_above_rad + 0.1,
            ..c
        },
        NavigatorConfig {
            turn_above_rad: 2.0,
            ..c
        },
    ] {
        assert!(bad.check().is_err(), "{bad:?}");
    }
}

#[test]
fn a_turn_goes_round_the_nearer_way_and_ends_when_its_time_is_up() {
    let c = TURNING;
    let mut n = Navigator::new(c, 0.0);
    let mut v = view(false);
    // Facing the way back: 90° from either way across, beyond slithering's reach.
    v.heading_rad = 3.0;
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Turn, Why::Start));
    // Nearer: +π/2 is 1.43 rad away, −π/2 1.71.
    assert!((d.heading_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    v.heading_rad = -2.0;
    let d = n.step(0.0, &v);
    assert_eq!(d, None);
    let d = n.step(c.turn_max_s, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Turned));
    assert!(axis_error(-2.0, std::f64::consts::FRAC_PI_2) > c.turn_done_rad);
    assert!((axis_error(-1.5, std::f64::consts::FRAC_PI_2) - 0.0708).abs() < 1e-3);
    let w = nearer_way(-2.0, std::f64::consts::FRAC_PI_2);
    assert!((w + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
}

#[test]
fn without_slithering_it_turns_sidewinds_and_backs_off_only() {
    let c = NavigatorConfig {
        slither: false,
        ..TURNING
    };
    let mut n = Navigator::new(c, 0.0);
    let mut v = view(false);
    v.heading_rad = 0.1;
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Turn, Why::Start));
    v.heading_rad = std::f64::consts::FRAC_PI_2;
    let d = n.step(1.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Turned));
    v.progress = view(true).progress;
    let d = n.step(1.0 + c.settle_s, &v).unwrap();
    assert_eq!(d.choice, Choice::BackOff);
    let d = n.step(1.0 + c.settle_s + c.back_off_s, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::BackedOff));
}

/// To a goal by position: it starts towards the goal, re-aims as the body leaves
/// the line, falls back to the last direction (reported) when the position goes,
/// takes standing still as stuck, and stops deciding at the goal.
#[test]
fn to_a_goal_it_steers_by_position_falls_back_without_it_and_arrives() {
    let c = NavigatorConfig {
        slither: false,
        ..NavigatorConfig::DEFAULT
    };
    // The source's world is the estimate's turned by ψ = 0.5.
    let psi = 0.5;
    let at = |x: f64, y: f64| PositionView {
        position_m: [x, y],
        yaw_offset_rad: psi,
    };
    let mut n = Navigator::to_goal(c, [3.0, 0.0], 0.0);
    assert_eq!(n.goal(), Some([3.0, 0.0]));
    let mut v = view(false);
    // The body lies across the line (sidewinding travels +x of the source's world).
    v.heading_rad = std::f64::consts::FRAC_PI_2 - psi;
    v.position = Some(at(0.0, 0.0));
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Start));
    assert!((n.travel_rad() + psi).abs() < 1e-12, "{}", n.travel_rad());
    assert!((d.heading_rad - (std::f64::consts::FRAC_PI_2 - psi)).abs() < 1e-12);
    let course = n.course().unwrap();
    assert!((course.distance_m - 3.0).abs() < 1e-12);
    // Drifted 0.4 m left: re-aimed to the right, not a switch.
    v.position = Some(at(1.0, 0.4));
    assert_eq!(n.step(0.5, &v), None, "not before reaim_s");
    let d = n.step(1.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Steer));
    assert!(n.travel_rad() < -psi - 0.3, "{}", n.travel_rad());
    assert_eq!(n.switches(), 0);
    assert_eq!(n.current(), Some((Choice::Sidewind, Why::Start)));
    // The position goes: by heading only, the last direction kept.
    let travel = n.travel_rad();
    v.position = None;
    assert_eq!(n.step(2.0, &v), None);
    assert!(n.course().is_none());
    assert_eq!(n.travel_rad(), travel);
    // Back, standing still for the progress window: stuck, backs off.
    v.position = Some(at(1.0, 0.0));
    let mut decided = None;
    for k in 0..40 {
        let t = 3.0 + k as f64;
        if let Some(d) = n.step(t, &v)
            && d.why != Why::Steer
        {
            decided = Some((t, d));
            break;
        }
    }
    let (t, d) = decided.expect("no progress seen");
    assert_eq!((d.choice, d.why), (Choice::BackOff, Why::NoProgress));
    assert!(t >= 3.0 + c.steering.progress_window_s, "{t}");
    // At the goal: nothing more.
    v.position = Some(at(2.9, 0.0));
    assert_eq!(n.step(t + 1.0, &v), None);
    assert!(n.arrived());
    v.position = Some(at(0.0, 0.0));
    assert_eq!(n.step(t + 20.0, &v), None);
}

#[test]
fn without_backing_off_a_stuck_sidewinding_goes_on() {
    let c = NavigatorConfig {
        slither: false,
        back_off: false,
        ..NavigatorConfig::DEFAULT
    };
    let mut n = Navigator::new(c, 0.0);
    let mut v = view(true);
    v.heading_rad = std::f64::consts::FRAC_PI_2;
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Start));
    assert_eq!(n.step(100.0, &v), None);
}

/// By position: sidewinding far off the line while lying to travel across it turns in
/// place first; slithering that comes no nearer gives way to sidewinding, for good.
#[test]
fn by_position_it_turns_when_off_the_line_and_drops_a_slithering_that_comes_no_nearer() {
    let c = NavigatorConfig {
        steering: SteeringConfig {
            off_line_m: 0.5,
            ..SteeringConfig::DEFAULT
        },
        ..NavigatorConfig::DEFAULT
    };
    let at = |x: f64, y: f64| PositionView {
        position_m: [x, y],
        yaw_offset_rad: 0.0,
    };
    // Lying along the line (+x): sidewinding would travel across it.
    let mut n = Navigator::to_goal(c, [3.0, 0.0], 0.0);
    let mut v = view(false);
    v.heading_rad = 0.0;
    v.position = Some(at(0.0, 0.0));
    let d = n.step(0.0, &v).unwrap();
    assert_eq!((d.choice, d.why), (Choice::Slither, Why::Start));
    // Slithering drifts back: no nearer over the window, so sidewinding, and no more
    // slithering.
    let mut decided = None;
    for k in 1..40 {
        let t = k as f64;
        v.position = Some(at(-0.01 * t, 0.0));
        if let Some(d) = n.step(t, &v)
            && d.why != Why::Steer
        {
            decided = Some((t, d));
            break;
        }
    }
    let (t, d) = decided.expect("slithering given up");
    assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::NoProgress));
    assert!(n.slither_fails());
    // Sidewinding across the line, 0.6 m off it after the settling time: turn.
    let mut turned = None;
    for k in 1..40 {
        let s = t + k as f64;
        v.position = Some(at(-0.4, 0.05 * k as f64));
        if let Some(d) = n.step(s, &v)
            && d.why != Why::Steer
        {
            turned = Some(d);
            break;
        }
    }
    let d = turned.expect("turned");
    assert_eq!((d.choice, d.why), (Choice::Turn, Why::OffLine));
    assert_eq!(
        NavigatorConfig::DEFAULT.steering.off_line_m,
        0.0,
        "off by default"
    );
}
