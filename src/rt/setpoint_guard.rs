//! The last check before the bus, whatever produced the set-points (the selector or
//! a controller): every set-point finite, within the joints' range, and no faster than
//! the joints turn. A non-finite set-point is not sent: the loop reports it to the
//! failsafe, which holds (see `docs/failsafe.md`); a joint out of range is clamped and
//! counted.

use crate::gait::JOINT_LIMIT_RAD;
use crate::gait::slew::SlewLimiter;

/// A set-point the guard refused to send.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NonFiniteSetpoint {
    pub joint: usize,
}

/// Counters of what the guard changed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct GuardCounters {
    /// Cycles in which some set-point was slew-limited.
    pub slew_limited_cycles: u64,
    /// Cycles in which some set-point was clamped into the joint range.
    pub range_clamped_cycles: u64,
    /// Cycles refused for a non-finite set-point.
    pub non_finite: u64,
}

/// See the module docs.
#[derive(Debug, Clone)]
pub struct SetpointGuard {
    slew: SlewLimiter,
    last_t_s: Option<f64>,
    counters: GuardCounters,
}

impl SetpointGuard {
    pub fn new(joints: usize, max_joint_speed_rad_s: f64) -> Self {
        Self {
            slew: SlewLimiter::new(joints, max_joint_speed_rad_s),
            last_t_s: None,
            counters: GuardCounters::default(),
        }
    }

    pub fn counters(&self) -> GuardCounters {
        self.counters
    }

    /// The joints were last commanded to `pos` at `t_s` (a resync or a hold).
    pub fn reset_to(&mut self, pos: &[f64], t_s: f64) {
        self.slew.reset_to(pos);
        self.last_t_s = Some(t_s);
    }

    /// Nothing was commanded (limp): the next set-points are taken as they are.
    pub fn forget(&mut self) {
        self.slew.forget();
        self.last_t_s = None;
    }

    /// Checks the set-points of the cycle at `t_s` in place. `derive_velocity`: the
    /// velocity feed-forward is recomputed from the limited motion (a controller gives
    /// none), else only clamped. Allocates nothing.
    pub fn check(
        &mut self,
        t_s: f64,
        pos: &mut [f64],
        vel: &mut [f64],
        derive_velocity: bool,
    ) -> Result<(), NonFiniteSetpoint> {
        if let Some(joint) = pos.iter().position(|p| !p.is_finite()) {
            self.counters.non_finite += 1;
            return Err(NonFiniteSetpoint { joint });
        }
        let mut clamped = false;
        for p in pos.iter_mut() {
            let c = p.clamp(-JOINT_LIMIT_RAD, JOINT_LIMIT_RAD);
            clamped |= c != *p;
            *p = c;
        }
        if !derive_velocity {
            for v in vel.iter_mut().filter(|v| !v.is_finite()) {
                *v = 0.0;
            }
        }
        let dt = self.last_t_s.map_or(0.0, |last| (t_s - last).max(0.0));
        if self.slew.apply(dt, pos, vel, derive_velocity) {
            self.counters.slew_limited_cycles += 1;
        }
        self.counters.range_clamped_cycles += u64::from(clamped);
        self.last_t_s = Some(t_s);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_non_finite_clamps_range_and_limits_speed() {
        let mut g = SetpointGuard::new(3, 2.0);
        g.reset_to(&[0.0, 0.0, 0.0], 0.0);
        let (mut p, mut v) = ([0.0, f64::NAN, 0.0], [0.0; 3]);
        assert_eq!(
            g.check(0.001, &mut p, &mut v, true),
            Err(NonFiniteSetpoint { joint: 1 })
        );
        let (mut p, mut v) = ([0.0, f64::INFINITY, 0.0], [0.0; 3]);
        assert!(g.check(0.001, &mut p, &mut v, true).is_err());
        assert_eq!(g.counters().non_finite, 2);
        // A refused cycle moved nothing: the next is limited against the old pose.
        let (mut p, mut v) = ([0.001, 5.0, -0.5], [0.0; 3]);
        g.check(0.001, &mut p, &mut v, true).unwrap();
        assert!(
            (p[1] - 0.002).abs() < 1e-12 && (v[1] - 2.0).abs() < 1e-9,
            "{p:?} {v:?}"
        );
        assert!((p[0] - 0.001).abs() < 1e-12 && (v[0] - 1.0).abs() < 1e-9);
        let c = g.counters();
        assert_eq!((c.range_clamped_cycles, c.slew_limited_cycles), (1, 1));
    }
}
