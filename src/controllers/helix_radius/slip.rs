//! Safety on the pole (issue 12, point 4): grip lost while climbing.
//!
//! - **Detected** from the torques, the grip (mean |τ_ext| over the joints) under
//!   `lost_nm` for `grace_s` — the pole no longer pushes back on the coil, so it holds
//!   nothing and slides — and from the IMUs, the modules' mean specific force under
//!   `falling_g` of gravity (the body accelerating down: falling).
//! - **Answered** by stopping the roll (the phase holds) and squeezing harder (the
//!   virtual squeeze × `squeeze_gain`) until the grip is back above `lost_nm` and the
//!   IMUs read gravity again for `recover_s`; then the coil rolls on. Each episode is
//!   counted and reported (`slipping`, `slips`).
//!
//! Nothing here allocates.

use serde::{Deserialize, Serialize};

use crate::controller_interface::Imu;
use crate::controller_interface::config::{ConfigError, check_range};

const G: f64 = 9.81;

/// When grip counts as lost and what the controller does then.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SlipConfig {
    pub enabled: bool,
    /// Grip below this is lost, N·m.
    pub lost_nm: f64,
    /// Mean specific force below this fraction of g is a fall.
    pub falling_g: f64,
    /// How long the grip must stay lost before the guard acts, s.
    pub grace_s: f64,
    /// How long grip and gravity must be back before the roll resumes, s.
    pub recover_s: f64,
    /// The squeeze τ_D is multiplied by this while slipping.
    pub squeeze_gain: f64,
}

impl Default for SlipConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            lost_nm: 0.4,
            falling_g: 0.6,
            grace_s: 0.3,
            recover_s: 1.0,
            squeeze_gain: 2.0,
        }
    }
}

impl SlipConfig {
    pub fn check(&self) -> Result<(), ConfigError> {
        let k = |e: ConfigError| e.under("slip");
        check_range(
            "lost_nm",
            self.lost_nm,
            0.0,
            crate::module::MODULE_MAX_TORQUE_NM,
        )
        .map_err(k)?;
        check_range("falling_g", self.falling_g, 0.0, 1.0).map_err(k)?;
        check_range("grace_s", self.grace_s, 0.0, 10.0).map_err(k)?;
        check_range("recover_s", self.recover_s, 0.0, 30.0).map_err(k)?;
        check_range("squeeze_gain", self.squeeze_gain, 1.0, 5.0).map_err(k)
    }
}

/// The guard's state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SlipGuard {
    slipping: bool,
    lost_for_s: f64,
    back_for_s: f64,
    count: u32,
}

/// The modules' mean specific force as a fraction of g (1 at rest, 0 in free fall).
pub fn specific_force_g(imu: &[Imu]) -> f64 {
    if imu.is_empty() {
        return 1.0;
    }
    let sum: f64 = imu
        .iter()
        .map(|m| {
            let [x, y, z] = m.accel_m_s2;
            (x * x + y * y + z * z).sqrt()
        })
        .sum();
    sum / imu.len() as f64 / G
}

impl SlipGuard {
    /// Whether the body is slipping (the roll holds, the squeeze is raised).
    pub fn slipping(&self) -> bool {
        self.slipping
    }

    /// Slip episodes since the takeover.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Advances by `dt_s` with the grip (N·m) and the IMUs; returns whether slipping.
    pub fn update(&mut self, c: &SlipConfig, dt_s: f64, grip_nm: f64, imu: &[Imu]) -> bool {
        if !c.enabled {
            self.slipping = false;
            return false;
        }
        let falling = specific_force_g(imu) < c.falling_g;
        let lost = grip_nm < c.lost_nm;
        if lost || falling {
            self.lost_for_s += dt_s;
            self.back_for_s = 0.0;
        } else {
            self.lost_for_s = 0.0;
            self.back_for_s += dt_s;
        }
        if !self.slipping && (falling || self.lost_for_s >= c.grace_s) {
            self.slipping = true;
            self.count += 1;
        } else if self.slipping && self.back_for_s >= c.recover_s {
            self.slipping = false;
        }
        self.slipping
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resting(g: f64) -> [Imu; 4] {
        [Imu {
            accel_m_s2: [0.0, 0.0, g * G],
            gyro_rad_s: [0.0; 3],
        }; 4]
    }

    #[test]
    fn lost_grip_after_the_grace_and_back_after_the_recovery() {
        let c = SlipConfig::default();
        let mut g = SlipGuard::default();
        let dt = 0.01;
        let run = |g: &mut SlipGuard, s: f64, grip: f64, imu: &[Imu]| {
            let mut any = false;
            for _ in 0..(s / dt).round() as usize {
                any |= g.update(&c, dt, grip, imu);
            }
            any
        };
        assert!(!run(&mut g, 2.0, 1.5, &resting(1.0)), "held");
        assert!(
            !run(&mut g, 0.2, 0.1, &resting(1.0)),
            "a short dip is no slip"
        );
        assert!(run(&mut g, 0.5, 0.1, &resting(1.0)));
        assert!(g.slipping() && g.count() == 1);
        assert!(run(&mut g, 0.5, 1.5, &resting(1.0)), "not yet recovered");
        run(&mut g, 0.6, 1.5, &resting(1.0));
        assert!(!g.slipping(), "recovered after 1 s of grip");
        // A fall shows in the IMUs at once, whatever the torques say.
        assert!(g.update(&c, dt, 1.5, &resting(0.2)));
        assert_eq!(g.count(), 2);
        // Off: never.
        let off = SlipConfig {
            enabled: false,
            ..c
        };
        let mut h = SlipGuard::default();
        assert!(!h.update(&off, dt, 0.0, &resting(0.0)));
    }

    #[test]
    fn the_configuration_is_checked() {
        assert!(SlipConfig::default().check().is_ok());
        let bad = SlipConfig {
            squeeze_gain: 0.5,
            ..SlipConfig::default()
        };
        assert!(
            bad.check()
                .unwrap_err()
                .to_string()
                .contains("squeeze_gain")
        );
    }
}
