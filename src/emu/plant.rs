//! `JointSpacePlant`: N independent series-elastic servos plus a kinematic body for
//! the IMUs. No contact with the ground and no coupling between joints: the world
//! acts only through scripted external torques (constant pushes and one-sided
//! "obstacle" springs). Rigid-body physics replaces this behind the same [`Plant`]
//! trait later.
//!
//! # Body frames
//! The head is fixed and level in the world: world = head frame, x forward (toward
//! the head's nose), y left, z up. Joint `i` rotates module `i` (its output side,
//! where the IMU sits) relative to module `i − 1` (the head for joint 0) about the
//! body's z axis when lateral (yaw) and about −y when dorsal (pitch), as `gait::kinematics::axis_of` and the physics plant have it.
//! Positive joint angles follow the right-hand rule about those axes.
//! - Accelerometer: specific force, quasi-static (gravity reaction only, the links'
//!   own accelerations are not modelled): world `(0, 0, +9.81)` in the module frame.
//! - Gyro: the module's angular velocity (sum of the joint rates up to it) in its frame.

use nalgebra::{Rotation3, Vector3};
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::servo::{Servo, ServoParamError, ServoParams};
use super::{GroundTruth, Plant};
use crate::gait::Plane;
use crate::protocol::{Command, ControlStrategy, Feedback};

/// Standard gravity, m/s².
pub const GRAVITY_M_S2: f64 = 9.81;

/// Standard deviations of the sensor noise (Gaussian, zero mean). Zero = exact.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseConfig {
    pub encoder_rad: f64,
    pub velocity_rad_s: f64,
    pub torque_nm: f64,
    pub accel_m_s2: f64,
    pub gyro_rad_s: f64,
}

impl Default for NoiseConfig {
    fn default() -> Self {
        Self {
            encoder_rad: 2e-4,
            velocity_rad_s: 5e-3,
            torque_nm: 0.02,
            accel_m_s2: 0.05,
            gyro_rad_s: 5e-3,
        }
    }
}

impl NoiseConfig {
    /// No noise at all.
    pub const NONE: NoiseConfig = NoiseConfig {
        encoder_rad: 0.0,
        velocity_rad_s: 0.0,
        torque_nm: 0.0,
        accel_m_s2: 0.0,
        gyro_rad_s: 0.0,
    };
}

/// A constant external torque on one joint while `start_s <= t < end_s`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScriptedTorque {
    pub joint: usize,
    pub torque_nm: f64,
    pub start_s: f64,
    pub end_s: f64,
}

/// Which way a joint must move to press into an obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ObstacleSide {
    /// Contact when the angle exceeds `angle_rad`.
    Positive,
    /// Contact when the angle falls below `angle_rad`.
    Negative,
}

/// A one-sided spring (with damping while in contact) on one joint: past `angle_rad`
/// on `side`, the torque `−k·penetration − c·velocity` pushes the joint back out.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    pub joint: usize,
    pub angle_rad: f64,
    pub side: ObstacleSide,
    #[serde(default = "default_obstacle_stiffness")]
    pub stiffness_nm_per_rad: f64,
    #[serde(default = "default_obstacle_damping")]
    pub damping_nm_s_per_rad: f64,
}

fn default_obstacle_stiffness() -> f64 {
    50.0
}
fn default_obstacle_damping() -> f64 {
    0.2
}

impl Obstacle {
    /// External torque on the joint at `pos_rad` moving at `vel_rad_s`, N·m.
    pub fn torque_nm(&self, pos_rad: f64, vel_rad_s: f64) -> f64 {
        let penetration = match self.side {
            ObstacleSide::Positive => (pos_rad - self.angle_rad).max(0.0),
            ObstacleSide::Negative => (pos_rad - self.angle_rad).min(0.0),
        };
        if penetration == 0.0 {
            0.0
        } else {
            -self.stiffness_nm_per_rad * penetration - self.damping_nm_s_per_rad * vel_rad_s
        }
    }
}

/// Everything that defines a [`JointSpacePlant`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlantConfig {
    pub modules: usize,
    /// Plane of joint 0; the others alternate.
    pub first_plane: Plane,
    pub servo: ServoParams,
    pub noise: NoiseConfig,
    /// Seed of the noise generator: equal seeds give equal runs.
    pub seed: u64,
    pub temperature_c: f32,
    pub voltage_v: f32,
    pub torques: Vec<ScriptedTorque>,
    pub obstacles: Vec<Obstacle>,
}

impl PlantConfig {
    /// `modules` servos with default parameters and noise, seed 0, no scripted world.
    pub fn new(modules: usize) -> Self {
        Self {
            modules,
            first_plane: Plane::Lateral,
            servo: ServoParams::default(),
            noise: NoiseConfig::default(),
            seed: 0,
            temperature_c: 35.0,
            voltage_v: 48.0,
            torques: Vec::new(),
            obstacles: Vec::new(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlantError {
    #[error("a plant needs at least one module")]
    NoModules,
    #[error(transparent)]
    Servo(#[from] ServoParamError),
    #[error("{what} refers to joint {joint}, but there are only {modules} modules")]
    NoSuchJoint {
        what: &'static str,
        joint: usize,
        modules: usize,
    },
    #[error("{0} must be finite (and non-negative where it is a size)")]
    BadValue(&'static str),
}

/// N series-elastic servos and the kinematic IMU body (see the module docs).
pub struct JointSpacePlant {
    config: PlantConfig,
    servos: Vec<Servo>,
    /// Rotation axis of each joint in its parent's frame.
    axes: Vec<Vector3<f64>>,
    feedback: Vec<Feedback>,
    time_ns: u64,
    rng: Pcg64,
}

impl JointSpacePlant {
    pub fn new(config: PlantConfig) -> Result<Self, PlantError> {
        validate(&config)?;
        let n = config.modules;
        // The one joint-axis convention (the physics plant and the estimator share it).
        let axes = (0..n)
            .map(|i| crate::gait::kinematics::axis_of(plane_of(config.first_plane, i)).into_inner())
            .collect();
        let mut plant = Self {
            servos: vec![Servo::new(config.servo, 0.0); n],
            axes,
            feedback: vec![Feedback::default(); n],
            time_ns: 0,
            rng: Pcg64::seed_from_u64(config.seed),
            config,
        };
        plant.update_feedback();
        Ok(plant)
    }

    pub fn config(&self) -> &PlantConfig {
        &self.config
    }

    /// Exact state of servo `i`.
    pub fn servo(&self, i: usize) -> &Servo {
        &self.servos[i]
    }

    /// Place joint `i` at `angle_rad` at rest (scenario set-up and tests).
    pub fn set_joint(&mut self, i: usize, angle_rad: f64) {
        self.servos[i] = Servo::new(self.config.servo, angle_rad);
        self.update_feedback();
    }

    /// Recompute every module's (noisy) feedback from the exact state.
    fn update_feedback(&mut self) {
        let g_world = Vector3::new(0.0, 0.0, GRAVITY_M_S2);
        let mut frame = Rotation3::identity();
        let mut omega_world = Vector3::zeros();
        let time_us = self.time_ns / 1_000;
        let noise = self.config.noise;
        for i in 0..self.servos.len() {
            let s = self.servos[i];
            let axis = self.axes[i];
            // The joint axis is the same before and after its own rotation.
            omega_world += frame * axis * s.velocity_rad_s();
            frame *= Rotation3::from_scaled_axis(axis * s.position_rad());
            let accel = frame.inverse() * g_world;
            let gyro = frame.inverse() * omega_world;
            let rng = &mut self.rng;
            let mut noisy = |x: f64, sigma: f64| (x + sigma * gaussian(rng)) as f32;
            self.feedback[i] = Feedback {
                module_time_us: time_us,
                last_command_seq: 0,
                position_rad: noisy(s.position_rad(), noise.encoder_rad),
                velocity_rad_s: noisy(s.velocity_rad_s(), noise.velocity_rad_s),
                torque_nm: noisy(s.torque_nm(), noise.torque_nm),
                deflection_rad: noisy(
                    s.deflection_rad(),
                    noise.torque_nm / self.config.servo.spring_stiffness_nm_per_rad,
                ),
                accel_m_s2: [
                    noisy(accel.x, noise.accel_m_s2),
                    noisy(accel.y, noise.accel_m_s2),
                    noisy(accel.z, noise.accel_m_s2),
                ],
                gyro_rad_s: [
                    noisy(gyro.x, noise.gyro_rad_s),
                    noisy(gyro.y, noise.gyro_rad_s),
                    noisy(gyro.z, noise.gyro_rad_s),
                ],
                temperature_c: self.config.temperature_c,
                voltage_v: self.config.voltage_v,
            };
        }
    }
}

/// Plane of joint `i` when joint 0 lies in `first`.
pub fn plane_of(first: Plane, i: usize) -> Plane {
    match (i.is_multiple_of(2), first) {
        (true, p) => p,
        (false, Plane::Lateral) => Plane::Dorsal,
        (false, Plane::Dorsal) => Plane::Lateral,
    }
}

/// Standard normal sample (Marsaglia's polar method: no trigonometry, which matters
/// at 18 modules x 4 channels per millisecond; the second sample is discarded).
pub(crate) fn gaussian<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    loop {
        let u = 2.0 * rng.random::<f64>() - 1.0;
        let v = 2.0 * rng.random::<f64>() - 1.0;
        let s = u * u + v * v;
        if s > 0.0 && s < 1.0 {
            return u * (-2.0 * s.ln() / s).sqrt();
        }
    }
}

fn validate(c: &PlantConfig) -> Result<(), PlantError> {
    if c.modules == 0 {
        return Err(PlantError::NoModules);
    }
    c.servo.validate()?;
    let n = c.noise;
    for (name, v) in [
        ("noise.encoder_rad", n.encoder_rad),
        ("noise.velocity_rad_s", n.velocity_rad_s),
        ("noise.torque_nm", n.torque_nm),
        ("noise.accel_m_s2", n.accel_m_s2),
        ("noise.gyro_rad_s", n.gyro_rad_s),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(PlantError::BadValue(name));
        }
    }
    if !(c.temperature_c.is_finite() && c.voltage_v.is_finite()) {
        return Err(PlantError::BadValue("temperature_c / voltage_v"));
    }
    let check_joint = |what, joint| {
        if joint >= c.modules {
            Err(PlantError::NoSuchJoint {
                what,
                joint,
                modules: c.modules,
            })
        } else {
            Ok(())
        }
    };
    for t in &c.torques {
        check_joint("a scripted torque", t.joint)?;
        if !(t.torque_nm.is_finite() && t.start_s.is_finite() && t.end_s >= t.start_s) {
            return Err(PlantError::BadValue("torque (torque_nm, start_s <= end_s)"));
        }
    }
    for o in &c.obstacles {
        check_joint("an obstacle", o.joint)?;
        if !(o.angle_rad.is_finite()
            && o.stiffness_nm_per_rad.is_finite()
            && o.stiffness_nm_per_rad >= 0.0
            && o.damping_nm_s_per_rad.is_finite()
            && o.damping_nm_s_per_rad >= 0.0)
        {
            return Err(PlantError::BadValue(
                "obstacle (angle_rad, stiffness, damping)",
            ));
        }
    }
    Ok(())
}

impl Plant for JointSpacePlant {
    fn module_count(&self) -> usize {
        self.servos.len()
    }

    fn step(&mut self, dt_s: f64, commands: &[Command]) {
        let t_s = self.time_s();
        for (i, servo) in self.servos.iter_mut().enumerate() {
            let cmd = commands.get(i).copied().unwrap_or(Command::LIMP);
            // Scripted pushes are constant over one plant step.
            let push_nm: f64 = self
                .config
                .torques
                .iter()
                .filter(|t| t.joint == i && t.start_s <= t_s && t_s < t.end_s)
                .map(|t| t.torque_nm)
                .sum();
            let obstacles = &self.config.obstacles;
            servo.step(dt_s, &cmd, ControlStrategy::Cascaded, |x, v| {
                push_nm
                    + obstacles
                        .iter()
                        .filter(|o| o.joint == i)
                        .map(|o| o.torque_nm(x, v))
                        .sum::<f64>()
            });
        }
        if dt_s.is_finite() && dt_s > 0.0 {
            self.time_ns += (dt_s * 1e9).round() as u64;
        }
        self.update_feedback();
    }

    fn time_s(&self) -> f64 {
        self.time_ns as f64 * 1e-9
    }

    fn feedback(&self, i: usize) -> Feedback {
        self.feedback[i]
    }

    fn ground_truth(&self, i: usize) -> GroundTruth {
        let s = &self.servos[i];
        GroundTruth {
            position_rad: s.position_rad(),
            torque_nm: s.torque_nm(),
        }
    }
}

#[cfg(test)]
#[path = "plant_tests.rs"]
mod tests;
