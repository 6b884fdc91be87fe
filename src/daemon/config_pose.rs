//! `[pose]`: how the external position source's fixes (`pose.external`, ROS 2's pose
//! topic) are fused into the pose estimate (`estimation::world_position`).
use std::path::Path;

use serde::Deserialize;

use super::config::{Config, ConfigFileError};
use crate::estimation::world_position::{FusionConfig, Tracked};
use crate::num::Num;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PoseConfig {
    /// What the source tracks: "chassis" (a rigid set along the backbone) or "head" (a
    /// marker on the head link).
    pub tracked: Tracked,
    /// The head marker in the head link's frame (x toward the nose, y left), m.
    pub marker_offset_m: [f64; 2],
    /// A fix's standard deviation when the source gives none, m.
    pub default_sd_m: f64,
    /// Fixes farther than this (or five standard deviations) from where the body
    /// should be are rejected, m.
    pub gate_m: f64,
    /// Without an accepted fix for this long the position is stale (not valid), s.
    pub max_age_s: f64,
}

impl Default for PoseConfig {
    fn default() -> Self {
        let f = FusionConfig::default();
        Self {
            tracked: f.tracked,
            marker_offset_m: f.marker_offset_m,
            default_sd_m: f.default_sd_m,
            gate_m: f.gate_m,
            max_age_s: f.max_age_s,
        }
    }
}

impl PoseConfig {
    pub fn fusion(&self) -> FusionConfig {
        FusionConfig {
            tracked: self.tracked,
            marker_offset_m: self.marker_offset_m,
            default_sd_m: self.default_sd_m,
            gate_m: self.gate_m,
            max_age_s: self.max_age_s,
            ..FusionConfig::default()
        }
    }
}

impl Config {
    /// `[pose]`: finite, positive where it must be.
    pub(super) fn pose_checks(&self, path: &Path) -> Result<(), ConfigFileError> {
        let p = &self.pose;
        let bad = |key: &'static str, v: f64, why: &str| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value: Num(v).to_string(),
            why: why.to_owned(),
        };
        for (key, v, max) in [
            ("pose.default_sd_m", p.default_sd_m, 1.0),
            ("pose.gate_m", p.gate_m, 10.0),
            ("pose.max_age_s", p.max_age_s, 10.0),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return Err(bad(key, v, &format!("must be in (0, {max}]")));
            }
        }
        for v in p.marker_offset_m {
            if !(v.is_finite() && v.abs() <= 2.0) {
                return Err(bad("pose.marker_offset_m", v, "must be within 2 m"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_keys_are_read_and_checked() {
        let c = Config::parse(
            "[pose]\ntracked = \"head\"\nmarker_offset_m = [0.03, 0.0]\nmax_age_s = 0.3\n",
            Path::new("x"),
        )
        .unwrap();
        let f = c.pose.fusion();
        assert_eq!(f.tracked, Tracked::Head);
        assert_eq!(f.marker_offset_m, [0.03, 0.0]);
        assert_eq!(f.max_age_s, 0.3);
        let refused = |t: &str| Config::parse(t, Path::new("x")).unwrap_err().to_string();
        assert!(refused("[pose]\ngate_m = 0.0\n").contains("pose.gate_m"));
        assert!(refused("[pose]\ntracked = \"tail\"\n").contains("tail"));
        assert!(refused("[pose]\nmarker_offset_m = [5.0, 0.0]\n").contains("pose.marker_offset_m"));
    }
}
