//! The head's attitude from every module's IMU, fused through the kinematics: a
//! complementary filter (gyros short term, the accelerometers' gravity long term).
//!
//! Each cycle every module's gyro turns its own attitude (the head's last attitude
//! carried to the module by the last joint angles); carried back to the head by the
//! new joint angles, the modules' answers are averaged, so the joints' own motion
//! cancels and the gyros' noise averages out. Then the accelerometers, turned into
//! the head's frame and averaged, pull the estimated up towards the measured one
//! (Mahony's correction) at `1/time constant`; a module accelerating (its specific
//! force off g by more than [`ACCEL_GATE`]) is left out. Yaw has no gravity to correct
//! it and follows the gyros: the frame's yaw is zero where the filter started.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::controller_interface::Imu;

/// Largest |‖a‖ − g| / g of a module whose accelerometer is read as gravity.
pub const ACCEL_GATE: f64 = 0.2;
const G: f64 = 9.81;

/// The fused filter's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusedAttitude {
    /// Head link frame → world (z up, yaw zero at the start).
    pub head: UnitQuaternion<f64>,
    initialised: bool,
    /// Accelerometer correction rate, 1/s (one over the filter's time constant).
    gain_per_s: f64,
}

/// The measured up (gravity reaction) in the head frame, averaged over the modules
/// that are not accelerating; `None` if all are.
fn measured_up(rel: &[UnitQuaternion<f64>], imu: &[Imu]) -> Option<Vector3<f64>> {
    let mut sum = Vector3::zeros();
    for (r, m) in rel.iter().zip(imu) {
        let a = Vector3::from(m.accel_m_s2);
        if ((a.norm() - G) / G).abs() <= ACCEL_GATE {
            sum += r * a.normalize();
        }
    }
    (sum.norm() > 1e-9).then(|| sum.normalize())
}

impl FusedAttitude {
    pub fn new(time_constant_s: f64) -> Self {
        Self {
            head: UnitQuaternion::identity(),
            initialised: false,
            gain_per_s: 1.0 / time_constant_s,
        }
    }

    pub fn initialised(&self) -> bool {
        self.initialised
    }

    /// Advances by `dt_s`: `rel_before` / `rel_now` are module `i`'s IMU link in the
    /// head frame at the last and this cycle's joint angles, `imu` its readings.
    pub fn update(
        &mut self,
        dt_s: f64,
        rel_before: &[UnitQuaternion<f64>],
        rel_now: &[UnitQuaternion<f64>],
        imu: &[Imu],
    ) {
        if !self.initialised {
            // Tilt from gravity alone, yaw zero.
            if let Some(up) = measured_up(rel_now, imu) {
                self.head =
                    UnitQuaternion::rotation_between(&up, &Vector3::z()).unwrap_or_else(|| {
                        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                    });
                self.initialised = true;
            }
            return;
        }
        let mut sum = Quaternion::new(0.0, 0.0, 0.0, 0.0);
        for ((before, now), m) in rel_before.iter().zip(rel_now).zip(imu) {
            let module = self.head * before;
            let turned =
                module * UnitQuaternion::from_scaled_axis(Vector3::from(m.gyro_rad_s) * dt_s);
            let head = (turned * now.inverse()).into_inner();
            // q and −q are one attitude: add them on the same side.
            sum += if head.dot(self.head.quaternion()) < 0.0 {
                -head
            } else {
                head
            };
        }
        if sum.norm() > 1e-12 {
            self.head = UnitQuaternion::new_normalize(sum);
        }
        if let Some(up) = measured_up(rel_now, imu) {
            let estimated = self.head.inverse() * Vector3::z();
            let correction = up.cross(&estimated) * (self.gain_per_s * dt_s);
            self.head *= UnitQuaternion::from_scaled_axis(correction);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(n: usize, up_in_module: Vector3<f64>) -> Vec<Imu> {
        vec![
            Imu {
                accel_m_s2: (up_in_module * G).into(),
                gyro_rad_s: [0.0; 3]
            };
            n
        ]
    }

    #[test]
    fn it_starts_from_gravity_and_a_gyro_turn_shows_up_while_the_tilt_stays() {
        let rel = vec![UnitQuaternion::identity(); 4];
        // Rolled 30° about x: up in the head frame is tilted.
        let roll = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.5);
        let mut f = FusedAttitude::new(1.0);
        let imu = still(4, roll.inverse() * Vector3::z());
        f.update(1e-3, &rel, &rel, &imu);
        assert!(f.initialised());
        assert!(f.head.angle_to(&roll) < 1e-9, "{:?}", f.head);
        // A yaw turn at 1 rad/s for 1 s (about world z: in the head frame roll⁻¹·z).
        let w = roll.inverse() * Vector3::z();
        let turning: Vec<Imu> = still(4, roll.inverse() * Vector3::z())
            .into_iter()
            .map(|m| Imu {
                gyro_rad_s: w.into(),
                ..m
            })
            .collect();
        for _ in 0..1000 {
            f.update(1e-3, &rel, &rel, &turning);
        }
        let expect = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 1.0) * roll;
        assert!(
            f.head.angle_to(&expect) < 1e-3,
            "{:?}",
            f.head.euler_angles()
        );
    }

    #[test]
    fn the_accelerometers_pull_a_wrong_tilt_back_and_the_joints_motion_cancels() {
        let n = 3;
        let bend = |a: f64| {
            (0..n)
                .map(|i| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a * (i + 1) as f64))
                .collect::<Vec<_>>()
        };
        let mut f = FusedAttitude::new(0.5);
        f.update(1e-3, &bend(0.0), &bend(0.0), &still(n, Vector3::z()));
        f.head = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.2);
        // The body bends in its plane at 1 rad/s per joint (module i turns at i + 1
        // rad/s about its z); the head does not move.
        for k in 0..3000 {
            let (a0, a1) = (k as f64 * 1e-3, (k + 1) as f64 * 1e-3);
            let imu: Vec<Imu> = (0..n)
                .map(|i| Imu {
                    accel_m_s2: [0.0, 0.0, G],
                    gyro_rad_s: [0.0, 0.0, (i + 1) as f64],
                })
                .collect();
            f.update(1e-3, &bend(a0), &bend(a1), &imu);
        }
        let tilt = (f.head.inverse() * Vector3::z()).angle(&Vector3::z());
        assert!(tilt < 0.2 * (-6.0f64).exp() + 1e-3, "tilt {tilt}");
        let (_, _, yaw) = f.head.euler_angles();
        assert!(
            yaw.abs() < 1e-3,
            "the joints' turn leaked into the head: {yaw}"
        );
    }
}
