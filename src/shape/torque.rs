//! External joint torques from the SEAs' reports, filtered for shape forces.
//!
//! Sign convention (proven in `tests`): `τ_ext` is the torque the environment exerts
//! on the joint, positive in the joint's positive direction. The module reports the
//! spring torque the motor applies to the output (docs/protocol.md); quasi-statically
//! the environment holds the output against it, so `τ_ext = −τ_reported`. A push that
//! bends a joint further than its set-point is then positive along the bend, and under
//! compliance it increases the amplitude.

/// Low-pass (first order) then dead-band, per joint. Preallocated; allocates nothing
/// per step.
#[derive(Debug, Clone)]
pub struct TorqueFilter {
    filtered: Vec<f64>,
    cutoff_hz: f64,
    deadband_nm: f64,
}

impl TorqueFilter {
    pub fn new(joints: usize, cutoff_hz: f64, deadband_nm: f64) -> Self {
        Self {
            filtered: vec![0.0; joints],
            cutoff_hz,
            deadband_nm,
        }
    }

    /// Filters `reported_nm` over `dt_s` and writes `τ_ext` (sign-flipped, low-passed,
    /// dead-banded: |τ| below the band is 0, above it shrinks by the band) to `out`.
    pub fn update(&mut self, dt_s: f64, reported_nm: &[f64], out: &mut [f64]) {
        let alpha = if dt_s > 0.0 {
            let rc = 1.0 / (std::f64::consts::TAU * self.cutoff_hz);
            dt_s / (rc + dt_s)
        } else {
            0.0
        };
        for ((f, &r), o) in self
            .filtered
            .iter_mut()
            .zip(reported_nm)
            .zip(out.iter_mut())
        {
            let ext = if r.is_finite() { -r } else { *f };
            *f += alpha * (ext - *f);
            *o = f.signum() * (f.abs() - self.deadband_nm).max(0.0);
        }
    }

    /// New settings, keeping the filtered torques.
    pub fn set(&mut self, cutoff_hz: f64, deadband_nm: f64) {
        self.cutoff_hz = cutoff_hz;
        self.deadband_nm = deadband_nm;
    }

    pub fn reset(&mut self) {
        self.filtered.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::Plant;
    use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
    use crate::emu::world::{Peg, WorldSpec};
    use crate::module::Command;

    #[test]
    fn small_torques_are_ignored_and_steady_ones_pass_reversed() {
        let mut f = TorqueFilter::new(2, 10.0, 0.5);
        let mut out = [0.0; 2];
        for _ in 0..1000 {
            f.update(1e-3, &[0.3, -3.0], &mut out);
        }
        assert_eq!(out[0], 0.0);
        assert!((out[1] - 2.5).abs() < 1e-6, "{out:?}");
    }

    /// The convention against the physics: pegs block joint 4 short of its set-point
    /// (the geometry of the physics plant's peg test); the environment's torque on the
    /// joint must then oppose the commanded bend.
    #[test]
    fn the_environment_torque_opposes_a_blocked_joint() {
        let l = crate::module::MODULE_LENGTH_M;
        let gap = 0.5 * crate::module::MODULE_DIAMETER_M + 0.026;
        let peg = |x: f64, y: f64| Peg {
            x_m: x,
            y_m: y,
            diameter_m: 0.05,
            height_m: 0.1,
        };
        for sign in [1.0, -1.0] {
            let spec = WorldSpec {
                pegs: vec![
                    peg(-5.0 * l, sign * gap),
                    peg(-l, -sign * gap),
                    peg(-9.0 * l, -sign * gap),
                ],
                ..WorldSpec::default()
            };
            let config = PhysicsConfig {
                modules: 9,
                noise: crate::emu::plant::NoiseConfig::NONE,
                ..PhysicsConfig::default()
            };
            let mut plant = PhysicsPlant::new(&spec, config).unwrap();
            let mut filter = TorqueFilter::new(9, 10.0, 0.2);
            let (mut ext, mut reported) = ([0.0; 9], [0.0; 9]);
            let mut cmds = [Command::position(0.0); 9];
            cmds[4] = Command::position(sign * 0.8);
            for _ in 0..800 {
                plant.step(1e-3, &cmds);
                for (i, r) in reported.iter_mut().enumerate() {
                    *r = f64::from(plant.feedback(i).torque_nm);
                }
                filter.update(1e-3, &reported, &mut ext);
            }
            let joint = plant.joint_rad(4);
            assert!(joint.abs() < 0.4, "not blocked: {joint}");
            assert!(ext[4] * sign < 0.0 && ext[4].abs() > 1.0, "{sign}: {ext:?}");
        }
    }
}
