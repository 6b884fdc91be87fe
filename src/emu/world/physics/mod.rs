//! `PhysicsPlant`: the snake as rapier3d rigid bodies in a [`WorldSpec`] world, behind
//! the emulator's [`Plant`] trait. See `docs/emulator.md` ("Physics plant").
//!
//! - Bodies: `N + 1` capsule links (head, the N modules' output sides) of the module's
//!   length, diameter and mass, joined by revolute impulse joints with ±π/2 limits;
//!   joint `i` joins link `i` to link `i + 1` (frames in [`kinematics`]).
//! - Actuators: each module's motor side is the servo model of [`crate::emu::servo`],
//!   stepped here with the joint's measured angle and rate; its spring + damper
//!   torque is applied equal and opposite to the two links about the joint axis.
//!   Reported torque = spring torque (sign as in `servo.rs`).
//! - Sensors: encoder, torque and an IMU on each module's output link ([`sensors`]).
//! - Contacts: Coulomb friction (isotropic `mu`, optional anisotropy), rapier's cone
//!   where a skin contact sticks and an explicit force opposing the slip where it
//!   slides ([`skin_friction`]);
//!   links not joined by a joint collide with each other, skin on skin at `mu`
//!   ([`self_contact`] counts the contacts).

pub mod build;
pub mod kinematics;
pub mod no_slip_bound;
mod self_contact;
pub mod sensors;
pub mod skin_friction;
mod step;

use nalgebra::Isometry3;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use rapier3d::prelude::*;

use self::build::{Chain, build_chain, build_world, start_poses};
use self::sensors::ImuState;
use super::WorldSpec;
use crate::emu::Plant;
use crate::emu::plant::{GRAVITY_M_S2, NoiseConfig};
use crate::emu::servo::{Servo, ServoParamError, ServoParams};
pub use crate::emu::{ContactSummary, LinkPose};
use crate::gait::Plane;
use crate::module::Feedback;

/// Constant IMU biases: each module draws its own from a zero-mean Gaussian of these
/// standard deviations at construction (seeded).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImuBias {
    pub accel_m_s2: f64,
    pub gyro_rad_s: f64,
}

/// Everything besides the world that defines a [`PhysicsPlant`].
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhysicsConfig {
    pub modules: usize,
    /// Plane of joint 0; the others alternate.
    pub first_plane: Plane,
    pub servo: ServoParams,
    pub noise: NoiseConfig,
    pub imu_bias: ImuBias,
    /// Seed of the sensor noise and biases.
    pub seed: u64,
    /// Rigid-body steps per plant step; the actuator torques are recomputed for each.
    pub substeps: usize,
    /// Solver iterations per rigid-body step (rapier's default is 4; each is a TGS
    /// substep with its own integration). See docs/measurements/physics.md for the trade-off.
    pub solver_iterations: usize,
    /// Projected Gauss-Seidel sweeps inside each solver iteration (rapier's
    /// `num_internal_pgs_iterations`): cheaper than whole iterations, no re-integration.
    pub pgs_iterations: usize,
    /// Unbiased (velocity-only) sweeps after each solver iteration's position update
    /// (rapier's `num_internal_stabilization_iterations`; rapier's default is 1). They
    /// converge the velocities the servos read at the next step: with 1, the end links'
    /// joints oscillated odd–even at the 1 ms step under open-loop rolling (the servo's
    /// velocity feedback is applied explicitly over each step); see docs/emulator.md,
    /// "Joint speeds above the motor's".
    pub stabilization_iterations: usize,
    /// Coulomb: one friction cone per contact point. Simplified: one cone per manifold plus
    /// a twist constraint (faster). Both cap the friction impulse by magnitude (a cone).
    pub coulomb_friction: bool,
    /// Warm-start the joint constraints with the last step's impulses (rapier's
    /// `warmstart_joints`): a stiff chain converges in fewer iterations.
    pub warmstart_joints: bool,
    /// Contact softness: natural frequency, Hz (rapier's default 30), and damping ratio.
    pub contact_natural_frequency_hz: f64,
    pub contact_damping_ratio: f64,
    /// Angular damping of each link (air, skin), 1/s.
    pub link_angular_damping: f64,
    /// Links not joined by a joint collide with each other, skin on skin at the world's
    /// `friction.mu` (only pairs 3 or more apart are tested: 2 apart cannot touch
    /// within the joint limits); false: they pass through each other (the old model).
    pub self_collision: bool,
    /// Skin friction on the world's surfaces while sliding as an explicit force opposing
    /// the slip (true, the default), or rapier's cone alone (false: its sliding friction
    /// is off the slip's opposite and slithering drifts back 0.02-0.04 m per cycle too
    /// far, [`skin_friction`]; every lab table before 2026-12-05).
    pub explicit_sliding_friction: bool,
    pub temperature_c: f32,
    pub voltage_v: f32,
}

impl Default for PhysicsConfig {
    fn default() -> Self {
        Self {
            modules: 18,
            first_plane: Plane::Lateral,
            servo: ServoParams::default(),
            noise: NoiseConfig::default(),
            imu_bias: ImuBias::default(),
            seed: 0,
            substeps: 1,
            solver_iterations: 3,
            pgs_iterations: 1,
            stabilization_iterations: 3,
            coulomb_friction: true,
            warmstart_joints: false,
            contact_natural_frequency_hz: 120.0,
            contact_damping_ratio: 10.0,
            link_angular_damping: 0.05,
            self_collision: true,
            explicit_sliding_friction: true,
            temperature_c: 35.0,
            voltage_v: 48.0,
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhysicsError {
    #[error("a physics plant needs at least one module")]
    NoModules,
    #[error(transparent)]
    Servo(#[from] ServoParamError),
    #[error("{0} must be finite and positive")]
    BadValue(&'static str),
    #[error("a rock's points have no 3-D convex hull")]
    BadRock,
}

/// The rigid-body snake (see the module docs).
pub struct PhysicsPlant {
    config: PhysicsConfig,
    world: PhysicsWorld,
    chain: Chain,
    servos: Vec<Servo>,
    /// Exact joint angle and rate after the last step.
    joint_rad: Vec<f64>,
    joint_rad_s: Vec<f64>,
    imu: Vec<ImuState>,
    feedback: Vec<Feedback>,
    hooks: Option<skin_friction::SkinFriction>,
    self_contacts: self_contact::SelfContacts,
    time_ns: u64,
    rng: Pcg64,
}

impl PhysicsPlant {
    /// Build the world of `spec` with the snake in its start pose.
    pub fn new(spec: &WorldSpec, config: PhysicsConfig) -> Result<Self, PhysicsError> {
        Self::with_head_pose(spec, config, None)
    }

    /// As [`PhysicsPlant::new`], with the head link's pose given instead of the spec's
    /// `start.head_m` / `yaw_rad` (the joint angles still come from the spec).
    pub fn with_head_pose(
        spec: &WorldSpec,
        config: PhysicsConfig,
        head: Option<Isometry3<f64>>,
    ) -> Result<Self, PhysicsError> {
        validate(&config)?;
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -GRAVITY_M_S2 as f32);
        let ip = &mut world.integration_parameters;
        ip.dt = (1e-3 / config.substeps as f64) as f32;
        ip.friction_model = if config.coulomb_friction {
            FrictionModel::Coulomb
        } else {
            FrictionModel::Simplified
        };
        ip.num_solver_iterations = config.solver_iterations;
        ip.num_internal_pgs_iterations = config.pgs_iterations;
        ip.num_internal_stabilization_iterations = config.stabilization_iterations;
        ip.warmstart_joints = config.warmstart_joints;
        // The same softness against fixed bodies (the world) and dynamic ones (another
        // link, with self-collision).
        let soft = SpringCoefficients::new(
            config.contact_natural_frequency_hz as f32,
            config.contact_damping_ratio as f32,
        );
        ip.contact_softness = soft;
        ip.static_contact_softness = soft;
        build_world(&mut world, spec)?;
        let poses = start_poses(spec, &config, head);
        let hooks = skin_hooks(spec, &config);
        let chain = build_chain(
            &mut world,
            &config,
            &poses,
            spec.friction.mu as f32,
            hooks.is_some(),
        );
        let n = config.modules;
        let mut plant = Self {
            servos: Vec::with_capacity(n),
            joint_rad: vec![0.0; n],
            joint_rad_s: vec![0.0; n],
            imu: Vec::new(),
            feedback: vec![Feedback::default(); n],
            hooks,
            self_contacts: self_contact::SelfContacts::new(chain.links.len()),
            time_ns: 0,
            rng: Pcg64::seed_from_u64(config.seed),
            world,
            chain,
            config,
        };
        plant.measure_joints();
        plant.servos = plant
            .joint_rad
            .iter()
            .map(|&a| Servo::new(plant.config.servo, a))
            .collect();
        plant.imu = sensors::draw_biases(&mut plant.rng, &plant.config.imu_bias, n);
        plant.update_feedback(0.0);
        Ok(plant)
    }

    pub fn config(&self) -> &PhysicsConfig {
        &self.config
    }

    /// Exact servo state of module `i`.
    pub fn servo(&self, i: usize) -> &Servo {
        &self.servos[i]
    }

    /// Mass-weighted centre of the links (all of equal mass), m.
    pub fn centre_of_mass_m(&self) -> [f64; 3] {
        let mut c = [0.0; 3];
        for k in 0..self.link_count() {
            let p = self.link_pose(k).position_m;
            for (a, b) in c.iter_mut().zip(p) {
                *a += b;
            }
        }
        c.map(|x| x / self.link_count() as f64)
    }

    /// Exact angular velocity of link `k` in the world frame, rad/s.
    pub fn link_angvel_rad_s(&self, k: usize) -> nalgebra::Vector3<f64> {
        let w = self.world.bodies[self.chain.links[k]].angvel();
        nalgebra::Vector3::new(f64::from(w.x), f64::from(w.y), f64::from(w.z))
    }

    /// The rapier world (read-only; for diagnostics and tests).
    pub fn world(&self) -> &PhysicsWorld {
        &self.world
    }
}

fn validate(c: &PhysicsConfig) -> Result<(), PhysicsError> {
    if c.modules == 0 {
        return Err(PhysicsError::NoModules);
    }
    c.servo.validate()?;
    if c.substeps == 0 || c.substeps > 100 {
        return Err(PhysicsError::BadValue("substeps (1..=100)"));
    }
    if c.solver_iterations == 0 {
        return Err(PhysicsError::BadValue("solver_iterations"));
    }
    if c.pgs_iterations == 0 {
        return Err(PhysicsError::BadValue("pgs_iterations"));
    }
    if c.stabilization_iterations == 0 {
        return Err(PhysicsError::BadValue("stabilization_iterations"));
    }
    for (name, x) in [
        (
            "contact_natural_frequency_hz",
            c.contact_natural_frequency_hz,
        ),
        ("contact_damping_ratio", c.contact_damping_ratio),
    ] {
        if !(x.is_finite() && x > 0.0) {
            return Err(PhysicsError::BadValue(name));
        }
    }
    let n = c.noise;
    for (name, x) in [
        (
            "noise",
            n.encoder_rad + n.velocity_rad_s + n.torque_nm + n.accel_m_s2 + n.gyro_rad_s,
        ),
        ("imu_bias", c.imu_bias.accel_m_s2 + c.imu_bias.gyro_rad_s),
        ("link_angular_damping", c.link_angular_damping),
    ] {
        if !(x.is_finite() && x >= 0.0) {
            return Err(PhysicsError::BadValue(name));
        }
    }
    Ok(())
}

/// The skin-friction hook of `spec`'s friction, or none where rapier's cone does it all
/// (isotropic, no explicit sliding).
fn skin_hooks(spec: &WorldSpec, config: &PhysicsConfig) -> Option<skin_friction::SkinFriction> {
    let f = &spec.friction;
    if f.anisotropic.is_none() && !config.explicit_sliding_friction {
        return None;
    }
    Some(skin_friction::SkinFriction {
        coefficients: f.anisotropic.unwrap_or(super::Anisotropic {
            mu_axial: f.mu,
            mu_lateral: f.mu,
        }),
        explicit_sliding: config.explicit_sliding_friction,
    })
}

#[cfg(test)]
mod coulomb_model;
#[cfg(test)]
mod drift_tests;
#[cfg(test)]
mod joint_speed_tests;
#[cfg(test)]
mod pole_tests;
#[cfg(test)]
mod self_collision_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod validation_tests;
