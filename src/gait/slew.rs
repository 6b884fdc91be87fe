//! The per-joint slew limit (the one definition): no set-point moves faster than the
//! joint can turn. The selector limits its blends with it, and the loop's set-point
//! guard limits whatever the controllers send.

/// Limits each joint's set-point against the previous output.
#[derive(Debug, Clone)]
pub struct SlewLimiter {
    max_rad_s: f64,
    last: Vec<f64>,
    have_last: bool,
}

impl SlewLimiter {
    /// For `joints` joints turning at most `max_rad_s` (positive, finite).
    pub fn new(joints: usize, max_rad_s: f64) -> Self {
        debug_assert!(max_rad_s.is_finite() && max_rad_s > 0.0);
        Self {
            max_rad_s,
            last: vec![0.0; joints],
            have_last: false,
        }
    }

    pub fn max_rad_s(&self) -> f64 {
        self.max_rad_s
    }

    /// The previous output is `pos` (e.g. a pose the joints were resynced to).
    pub fn reset_to(&mut self, pos: &[f64]) {
        self.last.copy_from_slice(pos);
        self.have_last = true;
    }

    /// No previous output: the next one passes as it is.
    pub fn forget(&mut self) {
        self.have_last = false;
    }

    /// Limits `pos` against the previous output `dt_s` ago and makes it the new
    /// previous output. `vel` is the velocity feed-forward: with `derive` it becomes
    /// each joint's difference quotient, otherwise clamped joints get theirs and every
    /// entry is clamped to the joint speed. Returns whether any joint was clamped.
    /// Allocates nothing.
    pub fn apply(&mut self, dt_s: f64, pos: &mut [f64], vel: &mut [f64], derive: bool) -> bool {
        let vmax = self.max_rad_s;
        let mut clamped = false;
        if self.have_last {
            let step = vmax * dt_s.max(0.0);
            for ((p, v), &last) in pos.iter_mut().zip(vel.iter_mut()).zip(&self.last) {
                let d = *p - last;
                let limited = d.clamp(-step, step);
                if d.abs() > step {
                    *p = last + limited;
                    clamped = true;
                }
                if derive || d.abs() > step {
                    *v = if dt_s > 0.0 { limited / dt_s } else { 0.0 };
                }
            }
        } else if derive {
            vel.fill(0.0);
        }
        for v in vel.iter_mut() {
            *v = v.clamp(-vmax, vmax);
        }
        self.last.copy_from_slice(pos);
        self.have_last = true;
        clamped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_limited_and_velocities_follow() {
        let mut s = SlewLimiter::new(2, 2.0);
        let (mut p, mut v) = ([1.0, -1.0], [9.0, 0.0]);
        assert!(
            !s.apply(0.01, &mut p, &mut v, false),
            "nothing to limit against"
        );
        assert_eq!(
            (p, v),
            ([1.0, -1.0], [2.0, 0.0]),
            "velocity clamped to the speed"
        );
        let (mut p, mut v) = ([2.0, -1.01], [0.0, 0.0]);
        assert!(s.apply(0.01, &mut p, &mut v, true));
        assert!(
            (p[0] - 1.02).abs() < 1e-12 && (v[0] - 2.0).abs() < 1e-9,
            "{p:?} {v:?}"
        );
        assert!(
            (p[1] + 1.01).abs() < 1e-12 && (v[1] + 1.0).abs() < 1e-9,
            "{p:?} {v:?}"
        );
        s.reset_to(&[0.0, 0.0]);
        let (mut p, mut v) = ([0.5, 0.0], [0.0, 0.0]);
        s.apply(0.0, &mut p, &mut v, true);
        assert_eq!((p, v), ([0.0, 0.0], [0.0, 0.0]), "no time, no motion");
    }
}
