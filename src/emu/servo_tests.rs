use super::*;

const DT: f64 = 1e-3;

fn run(servo: &mut Servo, cmd: Command, steps: usize, ext_nm: f64) {
    for _ in 0..steps {
        servo.step(DT, &cmd, ControlStrategy::Cascaded, |_, _| ext_nm);
    }
}

#[test]
fn default_params_are_valid() {
    ServoParams::default().validate().unwrap();
    let bad = ServoParams {
        spring_stiffness_nm_per_rad: f64::NAN,
        ..ServoParams::default()
    };
    assert_eq!(
        bad.validate().unwrap_err().name,
        "spring_stiffness_nm_per_rad"
    );
}

#[test]
fn small_step_tracks_within_tens_of_ms() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    let cmd = Command::position(0.05);
    let mut settled_at = None;
    for i in 0..300 {
        run(&mut s, cmd, 1, 0.0);
        if settled_at.is_none() && (s.position_rad() - 0.05).abs() < 0.0025 {
            settled_at = Some(i);
        }
    }
    let settled_at = settled_at.expect("never reached 5 % of the step");
    assert!(settled_at < 40, "took {settled_at} ms");
    // Stays there: no oscillation, no steady-state error.
    assert!(
        (s.position_rad() - 0.05).abs() < 5e-4,
        "{}",
        s.position_rad()
    );
    assert!(s.velocity_rad_s().abs() < 1e-2);
}

#[test]
fn large_step_is_speed_limited_and_settles() {
    let p = ServoParams::default();
    let mut s = Servo::new(p, 0.0);
    let cmd = Command::position(1.0);
    let mut max_motor = 0.0f64;
    let mut max_out = 0.0f64;
    for _ in 0..1000 {
        run(&mut s, cmd, 1, 0.0);
        max_motor = max_motor.max(s.motor_rad_s().abs());
        max_out = max_out.max(s.velocity_rad_s().abs());
    }
    assert!(max_motor <= p.max_motor_speed_rad_s + 1e-9, "{max_motor}");
    // The output cannot outrun the motor by more than the spring lets it.
    assert!(max_out < p.max_motor_speed_rad_s * 1.1, "{max_out}");
    assert!(
        max_out > p.max_motor_speed_rad_s * 0.9,
        "never reached full speed: {max_out}"
    );
    assert!(
        (s.position_rad() - 1.0).abs() < 1e-3,
        "{}",
        s.position_rad()
    );
}

#[test]
fn large_step_takes_at_least_the_speed_limited_time() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    // 1 rad at 3.46 rad/s needs at least 289 ms.
    run(&mut s, Command::position(1.0), 250, 0.0);
    assert!(s.position_rad() < 0.9, "{}", s.position_rad());
}

#[test]
fn external_torque_shows_up_with_documented_sign() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    // Push the joint negative while it holds position zero (5 s: the slow position
    // integral takes the push off the error with a 1 s time constant).
    run(&mut s, Command::position(0.0), 5000, -2.0);
    assert!(
        (s.torque_nm() - 2.0).abs() < 0.05,
        "torque {}",
        s.torque_nm()
    );
    assert!(s.deflection_rad() > 0.0);
    // The integrator holds the output at the set-point.
    assert!(s.position_rad().abs() < 2e-3, "{}", s.position_rad());
}

#[test]
fn torque_limit_respected_under_overload() {
    let p = ServoParams::default();
    let mut s = Servo::new(p, 0.0);
    let mut max_torque = 0.0f64;
    for _ in 0..500 {
        run(&mut s, Command::position(0.0), 1, 20.0);
        max_torque = max_torque.max(s.torque_nm().abs());
    }
    assert!(max_torque <= p.max_torque_nm + 1e-9, "{max_torque}");
    // Overloaded, the joint gives way in the push's direction.
    assert!(s.position_rad() > 0.5, "{}", s.position_rad());
    assert!(
        (s.torque_nm() + p.max_torque_nm).abs() < 0.1,
        "{}",
        s.torque_nm()
    );
}

#[test]
fn torque_command_is_clamped() {
    let p = ServoParams::default();
    let mut s = Servo::new(p, 0.0);
    let cmd = Command {
        torque_nm: 50.0,
        ..Command::LIMP
    };
    // Hold the output with an opposing external torque larger than the limit.
    for _ in 0..200 {
        run(&mut s, cmd, 1, -30.0);
        assert!(s.torque_nm().abs() <= p.max_torque_nm + 1e-9);
    }
}

#[test]
fn torque_only_command_tracks_torque_against_a_wall() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    let cmd = Command {
        torque_nm: 1.5,
        ..Command::LIMP
    };
    // A stiff wall at zero holds the output.
    for _ in 0..200 {
        s.step(DT, &cmd, ControlStrategy::Cascaded, |x, v| {
            -1000.0 * x - 1.0 * v
        });
    }
    assert!((s.torque_nm() - 1.5).abs() < 0.05, "{}", s.torque_nm());
}

/// Output speed after 0.5 s of a 1 rad/s velocity command.
fn speed_under_a_velocity_command(p: ServoParams) -> f64 {
    let mut s = Servo::new(p, 0.0);
    let cmd = Command {
        velocity_rad_s: 1.0,
        ..Command::LIMP
    };
    run(&mut s, cmd, 500, 0.0);
    s.velocity_rad_s()
}

#[test]
fn velocity_command_moves_at_that_speed() {
    let v = speed_under_a_velocity_command(ServoParams::default());
    assert!((v - 1.0).abs() < 0.02, "{v}");
}

#[test]
fn limp_has_no_spring_torque() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    run(&mut s, Command::position(0.0), 500, -3.0);
    assert!(s.torque_nm() > 2.5);
    for _ in 0..50 {
        s.step(DT, &Command::LIMP, ControlStrategy::Cascaded, |_, _| -3.0);
    }
    assert!(s.torque_nm().abs() < 0.05, "{}", s.torque_nm());
    // And the push now moves the joint freely.
    assert!(s.velocity_rad_s() < -1.0, "{}", s.velocity_rad_s());
}

#[test]
fn strategy_off_is_limp_whatever_is_commanded() {
    let mut s = Servo::new(ServoParams::default(), 0.3);
    for _ in 0..200 {
        s.step(DT, &Command::position(0.0), ControlStrategy::Off, |_, _| {
            0.0
        });
    }
    assert!((s.position_rad() - 0.3).abs() < 1e-9);
    assert!(s.torque_nm().abs() < 1e-9);
}

#[test]
fn stable_at_one_ms_with_a_stiff_obstacle() {
    let mut s = Servo::new(ServoParams::default(), 0.0);
    let wall = |x: f64, _v: f64| if x > 0.2 { -500.0 * (x - 0.2) } else { 0.0 };
    for _ in 0..2000 {
        s.step(DT, &Command::position(0.5), ControlStrategy::Cascaded, wall);
        assert!(s.position_rad().is_finite());
    }
    // Rests against the wall, pushing with a bounded torque.
    assert!(
        (s.position_rad() - 0.2).abs() < 0.02,
        "{}",
        s.position_rad()
    );
    assert!(s.torque_nm() > 0.0 && s.torque_nm() <= 7.0 + 1e-9);
}

fn profiled() -> ServoParams {
    ServoParams {
        position_loop: PositionLoop::Profiled,
        ..ServoParams::default()
    }
}

/// Peak output speed over each of 12 seconds of holding 0.3 rad against gravity on a
/// lifted load of `inertia` kg·m².
fn hold_peaks(params: ServoParams, inertia: f64) -> Vec<f64> {
    let p = ServoParams {
        output_inertia_kg_m2: inertia,
        ..params
    };
    let mut s = Servo::new(p, 0.0);
    (0..12)
        .map(|_| {
            let mut peak = 0.0f64;
            for _ in 0..1000 {
                run(&mut s, Command::position(0.3), 1, -1.5);
                peak = peak.max(s.velocity_rad_s().abs());
            }
            peak
        })
        .collect()
}

/// The heaviest load a joint can lift (about 7 modules held out, 0.12 kg·m², at the
/// torque limit) must not make the cascade oscillate. The speed-clamped loop does
/// (Routh: `Kv·(Kv·Kp + Ki) > J·Ki·Kp` fails past 0.005 kg·m² with Ki = 10), which is
/// why a held sidewinding pose thrashed in the physics; the profiled loop does not.
#[test]
fn a_heavy_lifted_load_settles_in_the_profiled_loop_only() {
    // The heaviest rings longest (the damping Kv/2J is what the light links allow),
    // but it dies away.
    let heavy = hold_peaks(profiled(), 0.12);
    assert!(heavy[11] < 0.5 * heavy[3] && heavy[11] < 0.1, "{heavy:.3?}");
    for inertia in [0.03, 0.005] {
        let p = hold_peaks(profiled(), inertia);
        assert!(p[3] < 0.05, "J {inertia}: {p:.3?}");
    }
    let clamped = hold_peaks(
        ServoParams {
            position_loop: PositionLoop::SpeedClamped,
            ..ServoParams::default()
        },
        0.12,
    );
    assert!(
        clamped[11] > 1.0,
        "the speed-clamped loop settled: {clamped:.3?}"
    );
}

#[test]
fn the_profiled_loop_is_speed_limited_holds_against_a_push_and_tracks_velocity() {
    let p = profiled();
    let mut s = Servo::new(p, 0.0);
    let mut max_out = 0.0f64;
    for _ in 0..1000 {
        run(&mut s, Command::position(1.0), 1, 0.0);
        max_out = max_out.max(s.velocity_rad_s().abs());
    }
    assert!(max_out < p.max_motor_speed_rad_s * 1.1, "{max_out}");
    assert!(max_out > p.max_motor_speed_rad_s * 0.9, "{max_out}");
    assert!(
        (s.position_rad() - 1.0).abs() < 1e-3,
        "{}",
        s.position_rad()
    );
    // A push: the stiffness Kv·Kp (30 N·m/rad) takes it at once, the slow integrator
    // (Kv/Ki = 1 s) closes the gap, and the spring reports the push.
    let mut s = Servo::new(p, 0.0);
    run(&mut s, Command::position(0.0), 200, -2.0);
    assert!(
        (-0.08..-0.03).contains(&s.position_rad()),
        "{}",
        s.position_rad()
    );
    run(&mut s, Command::position(0.0), 10_000, -2.0);
    assert!(s.position_rad().abs() < 2e-3, "{}", s.position_rad());
    assert!((s.torque_nm() - 2.0).abs() < 0.05, "{}", s.torque_nm());
    // Velocity commands keep the fast integrator (stable for any load without a
    // position loop).
    let v = speed_under_a_velocity_command(p);
    assert!((v - 1.0).abs() < 0.02, "{v}");
}
