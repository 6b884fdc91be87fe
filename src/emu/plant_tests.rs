use super::*;
use std::f64::consts::FRAC_PI_2;

const DT: f64 = 1e-3;

fn exact(n: usize) -> PlantConfig {
    PlantConfig {
        noise: NoiseConfig::NONE,
        ..PlantConfig::new(n)
    }
}

fn hold_all(n: usize) -> Vec<Command> {
    vec![Command::position(0.0); n]
}

fn close(a: f32, b: f64, tol: f64) -> bool {
    (f64::from(a) - b).abs() < tol
}

#[test]
fn straight_snake_at_rest_reads_gravity() {
    let mut p = JointSpacePlant::new(exact(6)).unwrap();
    p.step(DT, &hold_all(6));
    for i in 0..6 {
        let f = p.feedback(i);
        assert!(close(f.accel_m_s2[0], 0.0, 1e-6), "{i}: {:?}", f.accel_m_s2);
        assert!(close(f.accel_m_s2[1], 0.0, 1e-6));
        assert!(close(f.accel_m_s2[2], GRAVITY_M_S2, 1e-6));
        assert!(f.gyro_rad_s.iter().all(|g| g.abs() < 1e-6));
        assert_eq!(f.module_time_us, 1000);
        assert_eq!(f.voltage_v, 48.0);
    }
}

#[test]
fn planes_alternate_from_the_configured_one() {
    assert_eq!(plane_of(Plane::Lateral, 0), Plane::Lateral);
    assert_eq!(plane_of(Plane::Lateral, 1), Plane::Dorsal);
    assert_eq!(plane_of(Plane::Dorsal, 0), Plane::Dorsal);
    assert_eq!(plane_of(Plane::Dorsal, 3), Plane::Lateral);
}

#[test]
fn yaw_joint_rate_shows_on_downstream_gyros_only() {
    let n = 4;
    let mut p = JointSpacePlant::new(exact(n)).unwrap();
    let mut cmds = hold_all(n);
    // Joint 2 is lateral (joint 0 lateral, alternating).
    cmds[2] = Command {
        velocity_rad_s: 1.0,
        ..Command::LIMP
    };
    for _ in 0..200 {
        p.step(DT, &cmds);
    }
    for i in 0..2 {
        assert!(
            p.feedback(i).gyro_rad_s.iter().all(|g| g.abs() < 1e-3),
            "{i}"
        );
    }
    for i in 2..n {
        let g = p.feedback(i).gyro_rad_s;
        assert!(close(g[2], 1.0, 0.02), "{i}: {g:?}");
        // Yaw leaves the gravity direction alone.
        assert!(close(p.feedback(i).accel_m_s2[2], GRAVITY_M_S2, 1e-3));
    }
}

#[test]
fn pitch_joint_tilts_downstream_accelerometers() {
    let n = 3;
    let mut p = JointSpacePlant::new(exact(n)).unwrap();
    p.set_joint(1, FRAC_PI_2);
    let mut cmds = hold_all(n);
    cmds[1] = Command::position(FRAC_PI_2);
    cmds[0] = Command {
        velocity_rad_s: 0.5,
        ..Command::LIMP
    };
    for _ in 0..100 {
        p.step(DT, &cmds);
    }
    // Module 0 is upstream of the pitch joint: level.
    let a0 = p.feedback(0).accel_m_s2;
    assert!(close(a0[2], GRAVITY_M_S2, 1e-3), "{a0:?}");
    // Modules 1 and 2 are pitched by +90° about the dorsal axis (−y): their x axis
    // (towards the head) points up, so the gravity reaction is along +x.
    for i in 1..n {
        let a = p.feedback(i).accel_m_s2;
        assert!(close(a[0], GRAVITY_M_S2, 0.01), "{i}: {a:?}");
        assert!(close(a[2], 0.0, 0.01), "{i}: {a:?}");
        // The head-side yaw rate now appears about the module's +x axis.
        let g = p.feedback(i).gyro_rad_s;
        assert!(close(g[0], 0.5, 0.02), "{i}: {g:?}");
        assert!(close(g[2], 0.0, 0.02), "{i}: {g:?}");
    }
}

#[test]
fn obstacle_pushes_back_against_penetration() {
    let pos = Obstacle {
        joint: 0,
        angle_rad: 0.2,
        side: ObstacleSide::Positive,
        stiffness_nm_per_rad: 50.0,
        damping_nm_s_per_rad: 0.0,
    };
    assert_eq!(pos.torque_nm(0.1, 0.0), 0.0);
    assert!((pos.torque_nm(0.3, 0.0) + 5.0).abs() < 1e-12);
    let neg = Obstacle {
        side: ObstacleSide::Negative,
        angle_rad: -0.2,
        ..pos
    };
    assert_eq!(neg.torque_nm(0.0, 0.0), 0.0);
    assert!((neg.torque_nm(-0.3, 0.0) - 5.0).abs() < 1e-12);
}

#[test]
fn joint_driven_into_obstacle_reports_torque_of_the_right_sign() {
    let mut c = exact(3);
    c.obstacles.push(Obstacle {
        joint: 1,
        angle_rad: 0.2,
        side: ObstacleSide::Positive,
        stiffness_nm_per_rad: 50.0,
        damping_nm_s_per_rad: 0.2,
    });
    let mut p = JointSpacePlant::new(c).unwrap();
    let mut cmds = hold_all(3);
    cmds[1] = Command::position(0.4);
    for _ in 0..1000 {
        p.step(DT, &cmds);
    }
    let f = p.feedback(1);
    // Stopped near the obstacle; the wall pushes negative, so the spring torque is positive.
    assert!(
        f.position_rad > 0.2 && f.position_rad < 0.4,
        "{}",
        f.position_rad
    );
    assert!(f.torque_nm > 1.0, "{}", f.torque_nm);
    assert!(p.feedback(0).torque_nm.abs() < 1e-3);
}

#[test]
fn scripted_torque_acts_only_in_its_window() {
    let mut c = exact(4);
    c.torques.push(ScriptedTorque {
        joint: 3,
        torque_nm: -2.0,
        start_s: 0.1,
        end_s: 0.3,
    });
    let mut p = JointSpacePlant::new(c).unwrap();
    let cmds = hold_all(4);
    for _ in 0..250 {
        p.step(DT, &cmds);
    }
    assert!(
        close(p.feedback(3).torque_nm, 2.0, 0.05),
        "{}",
        p.feedback(3).torque_nm
    );
    assert!(p.ground_truth(3).torque_nm > 1.9);
    for _ in 0..250 {
        p.step(DT, &cmds);
    }
    assert!(
        close(p.feedback(3).torque_nm, 0.0, 0.05),
        "{}",
        p.feedback(3).torque_nm
    );
    assert!((p.time_s() - 0.5).abs() < 1e-9);
}

#[test]
fn same_seed_same_run_other_seed_differs() {
    let run = |seed| {
        let mut c = PlantConfig::new(5);
        c.seed = seed;
        let mut p = JointSpacePlant::new(c).unwrap();
        let cmds = vec![Command::position(0.3); 5];
        for _ in 0..100 {
            p.step(DT, &cmds);
        }
        (0..5).map(|i| p.feedback(i)).collect::<Vec<_>>()
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
}

#[test]
fn noise_has_roughly_the_configured_spread() {
    let mut c = PlantConfig::new(1);
    c.noise.torque_nm = 0.1;
    let mut p = JointSpacePlant::new(c).unwrap();
    let cmds = [Command::LIMP];
    let samples: Vec<f64> = (0..2000)
        .map(|_| {
            p.step(DT, &cmds);
            f64::from(p.feedback(0).torque_nm)
        })
        .collect();
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    let sd =
        (samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / samples.len() as f64).sqrt();
    assert!(mean.abs() < 0.02, "{mean}");
    assert!((sd - 0.1).abs() < 0.02, "{sd}");
}

#[test]
fn bad_configs_are_refused() {
    let mut c = exact(2);
    c.obstacles.push(Obstacle {
        joint: 2,
        angle_rad: 0.0,
        side: ObstacleSide::Negative,
        stiffness_nm_per_rad: 1.0,
        damping_nm_s_per_rad: 0.0,
    });
    assert!(matches!(
        JointSpacePlant::new(c),
        Err(PlantError::NoSuchJoint { joint: 2, .. })
    ));
    assert!(matches!(
        JointSpacePlant::new(exact(0)),
        Err(PlantError::NoModules)
    ));
    let mut c = exact(2);
    c.noise.gyro_rad_s = -1.0;
    assert!(JointSpacePlant::new(c).is_err());
}

#[test]
fn gaussian_has_zero_mean_unit_variance_and_normal_tails() {
    let mut rng = Pcg64::seed_from_u64(7);
    let n = 200_000;
    let xs: Vec<f64> = (0..n).map(|_| gaussian(&mut rng)).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
    let beyond_2 = xs.iter().filter(|x| x.abs() > 2.0).count() as f64 / n as f64;
    assert!(mean.abs() < 0.01, "{mean}");
    assert!((var - 1.0).abs() < 0.02, "{var}");
    // P(|x| > 2) = 4.55 % for a standard normal.
    assert!((beyond_2 - 0.0455).abs() < 0.003, "{beyond_2}");
}
