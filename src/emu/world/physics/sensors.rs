//! Module sensors from the simulated motion: encoder, spring torque and an IMU on each
//! module's output link (link `i + 1`), with Gaussian noise and constant IMU biases.
//! - Accelerometer: specific force `R⁻¹ (a − g)` of the link's centre, with `a` the
//!   change of its velocity over the plant step (at rest: `(0, 0, +9.81)` rotated into
//!   the module frame, as in the joint-space plant).
//! - Gyro: the link's angular velocity in its frame.

use rand::Rng;

use super::{ImuBias, PhysicsPlant};
use crate::emu::plant::{GRAVITY_M_S2, gaussian};
use crate::module::Feedback;

/// Per-module IMU state: biases and the velocity at the start of the step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuState {
    pub accel_bias_m_s2: [f64; 3],
    pub gyro_bias_rad_s: [f64; 3],
    pub last_linvel_m_s: [f64; 3],
}

/// One bias set per module, drawn from `bias`'s standard deviations.
pub fn draw_biases<R: Rng + ?Sized>(rng: &mut R, bias: &ImuBias, n: usize) -> Vec<ImuState> {
    (0..n)
        .map(|_| ImuState {
            accel_bias_m_s2: [0; 3].map(|_| bias.accel_m_s2 * gaussian(rng)),
            gyro_bias_rad_s: [0; 3].map(|_| bias.gyro_rad_s * gaussian(rng)),
            last_linvel_m_s: [0.0; 3],
        })
        .collect()
}

impl PhysicsPlant {
    pub(super) fn remember_velocities(&mut self) {
        for i in 0..self.config.modules {
            let v = self.world.bodies[self.chain.links[i + 1]].linvel();
            self.imu[i].last_linvel_m_s = [v.x, v.y, v.z].map(f64::from);
        }
    }

    /// Recompute every module's (noisy) feedback; `dt_s` is the step just taken (0 at
    /// construction: no acceleration yet).
    pub(super) fn update_feedback(&mut self, dt_s: f64) {
        let time_us = self.time_ns / 1_000;
        let noise = self.config.noise;
        let k = self.config.servo.spring_stiffness_nm_per_rad;
        for i in 0..self.config.modules {
            let body = &self.world.bodies[self.chain.links[i + 1]];
            let v = body.linvel();
            let imu = self.imu[i];
            let mut a = [0.0; 3];
            if dt_s > 0.0 {
                for (j, x) in [v.x, v.y, v.z].into_iter().enumerate() {
                    a[j] = (f64::from(x) - imu.last_linvel_m_s[j]) / dt_s;
                }
            }
            a[2] += GRAVITY_M_S2;
            let rot = *body.rotation();
            let inv = rot.inverse();
            let f = inv * rapier3d::math::Vector::new(a[0] as f32, a[1] as f32, a[2] as f32);
            let g = inv * body.angvel();
            let torque = self.spring_torque_nm(i);
            let deflection = torque / k;
            let accel = [f.x, f.y, f.z].map(f64::from);
            let gyro = [g.x, g.y, g.z].map(f64::from);
            let rng = &mut self.rng;
            let mut noisy = |x: f64, sigma: f64| (x + sigma * gaussian(rng)) as f32;
            let position_rad = noisy(self.joint_rad[i], noise.encoder_rad);
            let velocity_rad_s = noisy(self.joint_rad_s[i], noise.velocity_rad_s);
            let torque_nm = noisy(torque, noise.torque_nm);
            let deflection_rad = noisy(deflection, noise.torque_nm / k);
            let mut accel_m_s2 = [0.0f32; 3];
            let mut gyro_rad_s = [0.0f32; 3];
            for j in 0..3 {
                accel_m_s2[j] = noisy(accel[j] + imu.accel_bias_m_s2[j], noise.accel_m_s2);
                gyro_rad_s[j] = noisy(gyro[j] + imu.gyro_bias_rad_s[j], noise.gyro_rad_s);
            }
            self.feedback[i] = Feedback {
                module_time_us: time_us,
                last_command_seq: 0,
                position_rad,
                velocity_rad_s,
                torque_nm,
                deflection_rad,
                accel_m_s2,
                gyro_rad_s,
                temperature_c: self.config.temperature_c,
                voltage_v: self.config.voltage_v,
            };
        }
    }
}
