//! A series-elastic servo: motor → spring (+ damper) → output link.
//!
//! Pure model, time step as an argument. The module's own controller is a cascade
//! on the output side: position (P) → velocity (PI) → spring torque (P), and the
//! torque loop is closed through the motor's speed: the motor moves the spring's
//! input end so the deflection makes the wanted torque. The motor is modelled as a
//! speed source (its own current loop is much faster than anything here), limited
//! to [`ServoParams::max_motor_speed_rad_s`].
//!
//! # Sign convention
//! Spring torque `τ_s = k · (θ_motor − θ_output)` acts on the output in the joint's
//! positive direction when positive. An external torque that pushes the joint
//! negative while the motor holds position therefore appears as a *positive* spring
//! torque (the spring is wound up against the push). The reported torque is the spring
//! torque; the deflection is `θ_motor − θ_output`.
//!
//! # Limits
//! - Motor speed `|θ̇_motor| ≤ 3.46 rad/s` while driving.
//! - Spring torque `|τ_s| ≤ 7 N·m`: the controller never asks for more, and an
//!   external load that would deflect the spring further back-drives the motor
//!   (the deflection is clamped), as a real actuator at stall would slip.
//! - Limp: the motor is unpowered and back-drives freely, so the deflection (and the
//!   spring torque) relaxes to zero within a few ms; the output then moves only under
//!   external torque and viscous damping.
//!
//! Integration is semi-implicit Euler on substeps of at most
//! [`ServoParams::max_substep_s`] (0.1 ms), so a 1 ms plant step is stable for springs
//! and obstacle contacts far stiffer than the defaults.

use crate::module::{
    MODULE_LENGTH_M, MODULE_MASS_KG, MODULE_MAX_SPEED_RAD_S, MODULE_MAX_TORQUE_NM,
};
use crate::protocol::{Command, ControlStrategy};

/// How a position command becomes the velocity loop's reference.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum PositionLoop {
    /// `v_ref = clamp(Kp·e, ±v_max)`, the integrator at `velocity_integral_nm_per_rad`.
    /// The clamp caps what the position error alone can ask at `Kv·v_max` (0.7 N·m),
    /// so a loaded joint leans on the fast integrator, and that makes any load above
    /// 0.005 kg·m² oscillate (Routh): a lifted body thrashes (docs/emulator.md, "The
    /// servo loop"). The earlier default; kept to reproduce the results
    /// measured with it.
    SpeedClamped,
    /// The position loop chases a target that approaches the set-point at no more than
    /// the motor's speed (a motion profile), `v_ref = Kp·(target − θ)` unclamped, so a
    /// stalled joint gets full torque from its error; the integrator runs at the slow
    /// `position_integral_nm_per_rad`. Stable for every load a joint can lift.
    #[default]
    Profiled,
}

/// Physical and controller parameters of one servo. Defaults are SEA-Snake-like
/// (SPEC §1: 205 g, 6.4 cm, 7 N·m, 3.46 rad/s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct ServoParams {
    /// Spring stiffness, N·m/rad.
    pub spring_stiffness_nm_per_rad: f64,
    /// Damper in parallel with the spring, N·m·s/rad (not part of the reported torque).
    pub spring_damping_nm_s_per_rad: f64,
    /// Output-side inertia, kg·m² (default: one module as a rod about its end, m·L²/3).
    pub output_inertia_kg_m2: f64,
    /// Viscous damping of the output, N·m·s/rad.
    pub output_damping_nm_s_per_rad: f64,
    /// Motor speed limit while driving, rad/s.
    pub max_motor_speed_rad_s: f64,
    /// Spring torque limit, N·m.
    pub max_torque_nm: f64,
    /// Position loop gain: velocity reference per rad of error, 1/s.
    pub position_gain_per_s: f64,
    /// Velocity loop proportional gain, N·m·s/rad.
    pub velocity_gain_nm_s_per_rad: f64,
    /// Velocity loop integral gain, N·m/rad (under a velocity-only command, and under a
    /// position command in the [`PositionLoop::SpeedClamped`] loop).
    pub velocity_integral_nm_per_rad: f64,
    /// How a position command drives the velocity loop (see [`PositionLoop`]).
    pub position_loop: PositionLoop,
    /// Velocity loop integral gain while a position is commanded in the
    /// [`PositionLoop::Profiled`] loop, N·m/rad. Through the position gain it
    /// integrates the position error at `Ki·Kp`, and the cascade is stable only while
    /// `Kv·(Kv·Kp + Ki) > J·Ki·Kp` (Routh; `J` the load's inertia): 0.2 keeps up to
    /// 0.2 kg·m² stable, past the 0.12 of the most a joint can lift (7 modules held out
    /// at 7 N·m).
    pub position_integral_nm_per_rad: f64,
    /// Torque loop bandwidth, 1/s (spring torque follows its reference with this rate).
    pub torque_bandwidth_per_s: f64,
    /// Rate at which a limp motor lets the spring unwind, 1/s.
    pub limp_relax_per_s: f64,
    /// Longest internal integration substep, s.
    pub max_substep_s: f64,
}

impl Default for ServoParams {
    fn default() -> Self {
        Self {
            spring_stiffness_nm_per_rad: 100.0,
            spring_damping_nm_s_per_rad: 0.01,
            output_inertia_kg_m2: MODULE_MASS_KG * MODULE_LENGTH_M * MODULE_LENGTH_M / 3.0,
            output_damping_nm_s_per_rad: 0.02,
            max_motor_speed_rad_s: MODULE_MAX_SPEED_RAD_S,
            max_torque_nm: MODULE_MAX_TORQUE_NM,
            position_gain_per_s: 150.0,
            velocity_gain_nm_s_per_rad: 0.2,
            velocity_integral_nm_per_rad: 10.0,
            position_loop: PositionLoop::Profiled,
            position_integral_nm_per_rad: 0.2,
            torque_bandwidth_per_s: 2000.0,
            limp_relax_per_s: 500.0,
            max_substep_s: 1e-4,
        }
    }
}

/// Why a parameter set was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("servo parameter {name} = {value} is out of range (finite, positive)")]
pub struct ServoParamError {
    pub name: &'static str,
    pub value: f64,
}

impl ServoParams {
    /// Every parameter must be finite and positive (damping may be zero).
    pub fn validate(&self) -> Result<(), ServoParamError> {
        let positive = [
            (
                "spring_stiffness_nm_per_rad",
                self.spring_stiffness_nm_per_rad,
            ),
            ("output_inertia_kg_m2", self.output_inertia_kg_m2),
            ("max_motor_speed_rad_s", self.max_motor_speed_rad_s),
            ("max_torque_nm", self.max_torque_nm),
            ("position_gain_per_s", self.position_gain_per_s),
            (
                "velocity_gain_nm_s_per_rad",
                self.velocity_gain_nm_s_per_rad,
            ),
            ("torque_bandwidth_per_s", self.torque_bandwidth_per_s),
            ("limp_relax_per_s", self.limp_relax_per_s),
            ("max_substep_s", self.max_substep_s),
        ];
        let non_negative = [
            (
                "spring_damping_nm_s_per_rad",
                self.spring_damping_nm_s_per_rad,
            ),
            (
                "output_damping_nm_s_per_rad",
                self.output_damping_nm_s_per_rad,
            ),
            (
                "velocity_integral_nm_per_rad",
                self.velocity_integral_nm_per_rad,
            ),
            (
                "position_integral_nm_per_rad",
                self.position_integral_nm_per_rad,
            ),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(ServoParamError { name, value });
            }
        }
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ServoParamError { name, value });
            }
        }
        // The torque loop is integrated explicitly on substeps.
        if self.torque_bandwidth_per_s * self.max_substep_s > 0.5 {
            return Err(ServoParamError {
                name: "torque_bandwidth_per_s * max_substep_s (must be <= 0.5)",
                value: self.torque_bandwidth_per_s * self.max_substep_s,
            });
        }
        Ok(())
    }
}

/// State of one servo. Angles in rad, joint zero = straight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Servo {
    params: ServoParams,
    motor_rad: f64,
    output_rad: f64,
    output_rad_s: f64,
    motor_rad_s: f64,
    /// Velocity-loop integrator, N·m.
    integral_nm: f64,
    /// The [`PositionLoop::Profiled`] loop's target: the set-point approached at no
    /// more than the motor's speed.
    target_rad: f64,
}

/// A set-point is commanded when it is finite (NaN, and defensively ±inf, are not).
fn commanded(x: f32) -> Option<f64> {
    x.is_finite().then_some(x as f64)
}

impl Servo {
    /// A servo at rest with motor and output at `angle_rad` (zero deflection).
    pub fn new(params: ServoParams, angle_rad: f64) -> Self {
        Self {
            params,
            motor_rad: angle_rad,
            output_rad: angle_rad,
            output_rad_s: 0.0,
            motor_rad_s: 0.0,
            integral_nm: 0.0,
            target_rad: angle_rad,
        }
    }

    pub fn params(&self) -> &ServoParams {
        &self.params
    }
    /// Output (joint) angle, rad.
    pub fn position_rad(&self) -> f64 {
        self.output_rad
    }
    /// Output (joint) velocity, rad/s.
    pub fn velocity_rad_s(&self) -> f64 {
        self.output_rad_s
    }
    /// Motor-side angle, rad.
    pub fn motor_rad(&self) -> f64 {
        self.motor_rad
    }
    /// Motor-side velocity over the last substep, rad/s.
    pub fn motor_rad_s(&self) -> f64 {
        self.motor_rad_s
    }
    /// Spring deflection `θ_motor − θ_output`, rad.
    pub fn deflection_rad(&self) -> f64 {
        self.motor_rad - self.output_rad
    }
    /// Spring torque `k · deflection`, N·m (see the module docs for the sign).
    pub fn torque_nm(&self) -> f64 {
        self.params.spring_stiffness_nm_per_rad * self.deflection_rad()
    }

    /// Advance by `dt_s` applying `cmd` (`strategy` Off or an all-NaN command = limp).
    /// `external_nm(position_rad, velocity_rad_s)` is the torque the world puts on the
    /// output; it is evaluated every substep so stiff contacts stay stable.
    pub fn step<F>(&mut self, dt_s: f64, cmd: &Command, strategy: ControlStrategy, external_nm: F)
    where
        F: Fn(f64, f64) -> f64,
    {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return;
        }
        let n = (dt_s / self.params.max_substep_s).ceil().max(1.0);
        let h = dt_s / n;
        let limp = strategy == ControlStrategy::Off || cmd.is_limp();
        if limp {
            self.integral_nm = 0.0;
            self.target_rad = self.output_rad;
        }
        for _ in 0..n as u64 {
            let ext = external_nm(self.output_rad, self.output_rad_s);
            self.substep(h, cmd, limp, ext);
        }
    }

    fn substep(&mut self, h: f64, cmd: &Command, limp: bool, external_nm: f64) {
        let p = self.params;
        let tau_s = self.torque_nm();
        let motor_rad_s = self.motor_speed(h, cmd, limp);
        // Semi-implicit Euler: velocities from current forces, positions from new velocities.
        let damper_nm = p.spring_damping_nm_s_per_rad * (motor_rad_s - self.output_rad_s);
        let accel = (tau_s + damper_nm + external_nm
            - p.output_damping_nm_s_per_rad * self.output_rad_s)
            / p.output_inertia_kg_m2;
        self.output_rad_s += accel * h;
        self.output_rad += self.output_rad_s * h;
        self.advance_motor(h, motor_rad_s);
    }

    /// Motor-side step with the output supplied from outside (a rigid-body simulation
    /// owns the output): the output is set to `output_rad` / `output_rad_s`, the
    /// cascade and the motor advance by `h` (call with `h <= max_substep_s`), and the
    /// torque the actuator puts on the output during the step is returned: spring
    /// (from the deflection at the start of the step) plus damper, N·m, positive in
    /// the joint's positive direction. Apply it equal and opposite to the two links.
    pub fn step_motor(
        &mut self,
        h: f64,
        cmd: &Command,
        strategy: ControlStrategy,
        output_rad: f64,
        output_rad_s: f64,
    ) -> f64 {
        self.output_rad = output_rad;
        self.output_rad_s = output_rad_s;
        if !(h.is_finite() && h > 0.0) {
            return self.torque_nm();
        }
        let limp = strategy == ControlStrategy::Off || cmd.is_limp();
        if limp {
            self.integral_nm = 0.0;
            self.target_rad = self.output_rad;
        }
        let tau_s = self.torque_nm();
        let motor_rad_s = self.motor_speed(h, cmd, limp);
        let damper_nm = self.params.spring_damping_nm_s_per_rad * (motor_rad_s - self.output_rad_s);
        self.advance_motor(h, motor_rad_s);
        tau_s + damper_nm
    }

    /// Motor speed for the next `h`: keep up with the output, plus what closes the
    /// torque loop (or, limp, what lets the spring unwind).
    fn motor_speed(&mut self, h: f64, cmd: &Command, limp: bool) -> f64 {
        let p = self.params;
        let k = p.spring_stiffness_nm_per_rad;
        let tau_s = self.torque_nm();
        if limp {
            self.output_rad_s - p.limp_relax_per_s * tau_s / k
        } else {
            let tau_ref = self.torque_reference(h, cmd);
            let w = self.output_rad_s + p.torque_bandwidth_per_s * (tau_ref - tau_s) / k;
            w.clamp(-p.max_motor_speed_rad_s, p.max_motor_speed_rad_s)
        }
    }

    fn advance_motor(&mut self, h: f64, motor_rad_s: f64) {
        let p = self.params;
        self.motor_rad += motor_rad_s * h;
        self.motor_rad_s = motor_rad_s;
        // The motor cannot hold more than its torque limit: beyond it, it is back-driven.
        let max_defl = p.max_torque_nm / p.spring_stiffness_nm_per_rad;
        let defl = self.motor_rad - self.output_rad;
        if defl.abs() > max_defl {
            self.motor_rad = self.output_rad + defl.clamp(-max_defl, max_defl);
        }
    }

    /// Cascade: position (P) → velocity (PI) → torque reference, clamped to the limit.
    fn torque_reference(&mut self, h: f64, cmd: &Command) -> f64 {
        let p = self.params;
        let pos = commanded(cmd.position_rad);
        let vel = commanded(cmd.velocity_rad_s);
        let tau_ff = commanded(cmd.torque_nm).unwrap_or(0.0);
        let (v_ref, ki) = match (pos, vel) {
            (Some(x), v) if p.position_loop == PositionLoop::Profiled => {
                let step = p.max_motor_speed_rad_s * h;
                self.target_rad += (x - self.target_rad).clamp(-step, step);
                // Not clamped: a stalled joint's error must reach full torque; the
                // profile limits the motion instead.
                let v_ref =
                    p.position_gain_per_s * (self.target_rad - self.output_rad) + v.unwrap_or(0.0);
                (v_ref, p.position_integral_nm_per_rad)
            }
            (Some(x), v) => {
                self.target_rad = x;
                let v_ref = p.position_gain_per_s * (x - self.output_rad) + v.unwrap_or(0.0);
                (
                    v_ref.clamp(-p.max_motor_speed_rad_s, p.max_motor_speed_rad_s),
                    p.velocity_integral_nm_per_rad,
                )
            }
            (None, Some(v)) => {
                // Velocity only: `J·s² + Kv·s + Ki`, stable for any load.
                self.target_rad = self.output_rad;
                let v_ref = v.clamp(-p.max_motor_speed_rad_s, p.max_motor_speed_rad_s);
                (v_ref, p.velocity_integral_nm_per_rad)
            }
            (None, None) => {
                // Torque only: no motion loop.
                self.integral_nm = 0.0;
                self.target_rad = self.output_rad;
                return tau_ff.clamp(-p.max_torque_nm, p.max_torque_nm);
            }
        };
        let err = v_ref - self.output_rad_s;
        let unclamped = p.velocity_gain_nm_s_per_rad * err + self.integral_nm + tau_ff;
        // Anti-windup: integrate only while the output is not saturated (or it unwinds).
        if unclamped.abs() < p.max_torque_nm || unclamped.signum() != err.signum() {
            self.integral_nm += ki * err * h;
            self.integral_nm = self.integral_nm.clamp(-p.max_torque_nm, p.max_torque_nm);
        }
        (p.velocity_gain_nm_s_per_rad * err + self.integral_nm + tau_ff)
            .clamp(-p.max_torque_nm, p.max_torque_nm)
    }
}

#[cfg(test)]
#[path = "servo_tests.rs"]
mod tests;
