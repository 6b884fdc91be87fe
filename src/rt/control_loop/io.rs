//! The loop's bookkeeping around the gait: how healthy the feedback is (and the measured
//! pose the controllers see), the cycle statistics, the telemetry snapshot and the
//! recording. Part of [`super::ControlLoop`]; nothing here allocates or blocks.

use super::ControlLoop;
use crate::controller_interface::Imu;
use crate::rt::observer::CycleView;
use crate::rt::pacer::Cycle;
use crate::rt::setpoint_guard::NonFiniteSetpoint;
use crate::safety::failsafe::Health;

impl ControlLoop {
    /// Feedback health and the measured pose; also lockstep's notion of module time.
    pub(super) fn assess(&mut self, c: &Cycle) -> Health {
        let mut oldest_ns = 0u64;
        let mut never = false;
        let mut non_finite = false;
        let mut late = 0u64;
        let mut min_module_time: Option<u64> = None;
        for (i, m) in self.group.modules.iter().enumerate() {
            match m.received_ns {
                Some(_) => oldest_ns = oldest_ns.max(feedback_age_ns(m, c.clock_ns)),
                None => never = true,
            }
            if !m.fresh {
                late += 1;
            }
            let f = &m.feedback;
            let finite = f.position_rad.is_finite()
                && f.velocity_rad_s.is_finite()
                && f.torque_nm.is_finite()
                && f.accel_m_s2
                    .iter()
                    .chain(&f.gyro_rad_s)
                    .all(|v| v.is_finite());
            if m.received_ns.is_some() && !finite {
                non_finite = true;
            }
            self.measured[i] = f.position_rad as f64;
            self.measured_velocity[i] = f.velocity_rad_s as f64;
            self.torques[i] = f.torque_nm as f64;
            self.imu[i] = Imu {
                accel_m_s2: f.accel_m_s2.map(f64::from),
                gyro_rad_s: f.gyro_rad_s.map(f64::from),
            };
            min_module_time =
                Some(min_module_time.map_or(f.module_time_us, |t| t.min(f.module_time_us)));
        }
        if !never {
            self.last_module_time_us = min_module_time;
        }
        self.stats.late_feedback += late;
        self.stats
            .feedback_age
            .record(if never { c.clock_ns } else { oldest_ns });
        Health {
            oldest_feedback_age_s: if never {
                f64::INFINITY
            } else {
                oldest_ns as f64 * 1e-9
            },
            non_finite,
        }
    }

    /// Hands the cycle to the recorder, if there is one.
    pub(super) fn record_cycle(&mut self, c: &Cycle, fault: Option<NonFiniteSetpoint>) {
        let Some(o) = self.observer.as_mut() else {
            return;
        };
        if let Some(f) = fault {
            let controller_id = self.slots.id(self.p.selector.active());
            o.setpoint_fault(c.t_ns, f.joint, controller_id);
        }
        o.cycle(&CycleView {
            cycle: c.index,
            t_ns: c.t_ns,
            mode: self.p.failsafe.mode(),
            reason: self.p.failsafe.reason(),
            gait: self.p.selector.active(),
            group: &self.group,
            commands: &self.commands,
            slots: &self.slots,
            bus: self.p.bus.as_ref(),
            stats: &self.stats,
            body: &self.body,
            progress: self.progress.report(),
            navigator: self.navigator,
        });
    }

    pub(super) fn record(&mut self, c: &Cycle, compute_ns: u64) {
        let period_ns = self.p.pacer.period_ns();
        let s = &mut self.stats;
        s.cycles += 1;
        s.record_start(c.index, c.clock_ns, c.lateness_ns, period_ns);
        s.compute.record(compute_ns);
        if c.skipped > 0 {
            s.overruns += 1;
            s.skipped_periods += c.skipped;
        }
    }

    pub(super) fn publish(&mut self, c: &Cycle) {
        let (group, commands, stats) = (&self.group, &self.commands, &self.stats);
        let (selector, failsafe, bus) = (&self.p.selector, &self.p.failsafe, &self.p.bus);
        let (slots, guard) = (&self.slots, self.guard.counters());
        let record_dropped = self.observer.as_ref().map_or(0, |o| o.dropped());
        let (applied, refused, body) = (self.applied, self.refused, self.body);
        let (progress, navigator) = (self.progress.report(), self.navigator);
        let (motion, gait_rate) = (self.clock.motion(), self.clock.rate());
        self.p.telemetry.write(|snap| {
            snap.cycle = c.index;
            snap.t_s = c.t_ns as f64 * 1e-9;
            snap.mode = failsafe.mode();
            snap.reason = failsafe.reason();
            snap.gait = selector.active();
            snap.blend_progress = selector.blend_progress();
            snap.blend_time_s = selector.blend_time_s();
            snap.params = *selector.table();
            for (j, (m, cmd)) in snap
                .joints
                .iter_mut()
                .zip(group.modules.iter().zip(commands))
            {
                j.setpoint_rad = cmd.position_rad as f64;
                j.position_rad = m.feedback.position_rad as f64;
                j.velocity_rad_s = m.feedback.velocity_rad_s as f64;
                j.torque_nm = m.feedback.torque_nm as f64;
                j.feedback_age_s = match m.received_ns {
                    Some(_) => feedback_age_ns(m, c.clock_ns) as f64 * 1e-9,
                    None => f64::INFINITY,
                };
            }
            snap.stats = *stats;
            snap.bus = bus.counters();
            snap.requests_applied = applied;
            snap.requests_refused = refused;
            slots.publish(selector.active(), &mut snap.controller);
            snap.guard = guard;
            snap.record_dropped = record_dropped;
            snap.body = body;
            snap.progress = progress;
            snap.navigator = navigator;
            snap.motion = motion;
            snap.gait_rate = gait_rate;
        });
    }
}

/// How old a module's newest feedback is at `now_ns` (loop clock): since it arrived,
/// plus how late it already was by the module's own clock, and at least (over UDP) the
/// round trip of the command it reports. Feedback delayed on the way looks fresh by its
/// arrival alone; a delay present from the start looks like clock offset to the
/// module's clock, and the round trip catches it.
fn feedback_age_ns(m: &crate::bus::ModuleState, now_ns: u64) -> u64 {
    let since_arrival = m.received_ns.map_or(u64::MAX, |r| now_ns.saturating_sub(r));
    since_arrival
        .saturating_add(m.clock_age_ns.unwrap_or(0))
        .max(m.command_age_ns.unwrap_or(0))
}
