//! Stepping: the motor sides on their own short substeps, the rigid bodies on
//! `substeps` rapier steps per plant step, the actuator torques coupling them.

use super::PhysicsPlant;
use super::build::TAG_LINK_BASE;
use super::kinematics::twist_angle;
use crate::emu::{ContactSummary, GroundTruth, LinkPose, Plant};
use crate::protocol::{Command, ControlStrategy, Feedback};

impl PhysicsPlant {
    /// Exact joint angles and rates from the links' poses and velocities.
    pub(super) fn measure_joints(&mut self) {
        let bodies = &self.world.bodies;
        for i in 0..self.config.modules {
            let p = &bodies[self.chain.links[i]];
            let c = &bodies[self.chain.links[i + 1]];
            let axis = self.chain.axes[i];
            self.joint_rad[i] = twist_angle(p.rotation(), c.rotation(), axis);
            let axis_w = *p.rotation() * axis;
            self.joint_rad_s[i] = f64::from((c.angvel() - p.angvel()).dot(axis_w));
        }
    }

    /// One rigid-body substep of `h` seconds with `commands` held.
    fn substep(&mut self, h: f64, commands: &[Command]) {
        self.measure_joints();
        let max_h = self.config.servo.max_substep_s;
        let m = (h / max_h).ceil().max(1.0) as usize;
        let hm = h / m as f64;
        for &link in &self.chain.links {
            self.world.bodies[link].reset_torques(false);
            self.world.bodies[link].reset_forces(false);
        }
        self.apply_skin_friction(h);
        for i in 0..self.config.modules {
            let cmd = commands.get(i).copied().unwrap_or(Command::LIMP);
            let (x, w) = (self.joint_rad[i], self.joint_rad_s[i]);
            // The output moves on during the motor's substeps: extrapolate it.
            let mut sum_nm = 0.0;
            for j in 0..m {
                let t = j as f64 * hm;
                sum_nm +=
                    self.servos[i].step_motor(hm, &cmd, ControlStrategy::Cascaded, x + w * t, w);
            }
            let tau = (sum_nm / m as f64) as f32;
            let (pl, cl) = (self.chain.links[i], self.chain.links[i + 1]);
            let axis_w = *self.world.bodies[pl].rotation() * self.chain.axes[i];
            self.world.bodies[pl].add_torque(-tau * axis_w, false);
            self.world.bodies[cl].add_torque(tau * axis_w, false);
        }
        self.world.integration_parameters.dt = h as f32;
        match &self.hooks {
            Some(hooks) => self.world.step_with_events(hooks, &()),
            None => self.world.step_with_events(&(), &()),
        }
        if self.config.self_collision {
            self.self_contacts
                .update(&self.world, &self.chain.colliders);
        }
    }

    /// Spring torque of module `i` from the motor angle and the exact joint angle, N·m.
    pub fn spring_torque_nm(&self, i: usize) -> f64 {
        let s = &self.servos[i];
        s.params().spring_stiffness_nm_per_rad * (s.motor_rad() - self.joint_rad[i])
    }

    /// Exact joint angle of module `i`, rad.
    pub fn joint_rad(&self, i: usize) -> f64 {
        self.joint_rad[i]
    }
}

impl Plant for PhysicsPlant {
    fn module_count(&self) -> usize {
        self.config.modules
    }

    fn step(&mut self, dt_s: f64, commands: &[Command]) {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return;
        }
        self.remember_velocities();
        let n = self.config.substeps;
        let h = dt_s / n as f64;
        for _ in 0..n {
            self.substep(h, commands);
        }
        self.measure_joints();
        self.time_ns += (dt_s * 1e9).round() as u64;
        self.update_feedback(dt_s);
    }

    fn time_s(&self) -> f64 {
        self.time_ns as f64 * 1e-9
    }

    fn feedback(&self, i: usize) -> Feedback {
        self.feedback[i]
    }

    fn ground_truth(&self, i: usize) -> GroundTruth {
        GroundTruth {
            position_rad: self.joint_rad[i],
            torque_nm: self.spring_torque_nm(i),
        }
    }

    /// Links: modules + head.
    fn link_count(&self) -> usize {
        self.chain.links.len()
    }

    /// Link `k`: 0 = head, `i + 1` = module `i`'s output side.
    fn link_pose(&self, k: usize) -> LinkPose {
        let b = &self.world.bodies[self.chain.links[k]];
        let t = b.translation();
        let q = b.rotation();
        LinkPose {
            position_m: [t.x, t.y, t.z].map(f64::from),
            quat_wxyz: [q.w, q.x, q.y, q.z].map(f64::from),
        }
    }

    /// Link–world collider pairs touching and their summed normal force (last
    /// substep's impulses); link–link pairs are left to [`Plant::self_contacts`].
    fn contacts(&self) -> ContactSummary {
        let mut s = ContactSummary::default();
        let dt = f64::from(self.world.integration_parameters.dt);
        let is_link = |h| {
            self.world
                .colliders
                .get(h)
                .is_some_and(|c| c.user_data >= TAG_LINK_BASE)
        };
        for pair in self.world.narrow_phase.contact_pairs() {
            if pair.has_any_active_contact()
                && !(is_link(pair.collider1) && is_link(pair.collider2))
            {
                s.pairs += 1;
                s.normal_force_n += f64::from(pair.total_impulse_magnitude()) / dt;
            }
        }
        s
    }

    fn self_contacts(&self) -> u64 {
        self.self_contacts.onsets()
    }

    fn self_contact_pairs_now(&self) -> usize {
        self.self_contacts.pairs_now()
    }
}
