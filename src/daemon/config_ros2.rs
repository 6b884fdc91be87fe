//! `[ros2]`: snaked as a ROS 2 node (docs/ros2.md), off by default.
use std::path::Path;

use serde::Deserialize;

use super::config::{Config, ConfigFileError};
use crate::num::Num;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2Config {
    pub enabled: bool,
    /// The DDS domain (ROS_DOMAIN_ID), 0..=232.
    pub domain_id: u16,
    /// The node's namespace; its topics are under it ("/" = none).
    pub namespace: String,
    pub node_name: String,
    /// `/joint_states` rate, Hz (1 up to the loop's rate).
    pub joint_states_rate_hz: f64,
    /// Each module's IMU (`imu/<module>/data_raw`), Hz (at most the joint states').
    pub imu_rate_hz: f64,
    /// `odom` and `/tf`, Hz (at most the joint states').
    pub odometry_rate_hz: f64,
    /// Whether ROS 2 may drive and tune the robot: `/cmd_vel` (with `[foxglove]`'s
    /// teleop mapping and dead-man), services, parameters.
    pub operate: bool,
    /// The external pose's topic (`geometry_msgs/PoseStamped`); "" reads none.
    pub pose_topic: String,
}

impl Default for Ros2Config {
    fn default() -> Self {
        Self {
            enabled: false,
            domain_id: 0,
            namespace: "/".into(),
            node_name: "snaked".into(),
            joint_states_rate_hz: 100.0,
            imu_rate_hz: 100.0,
            odometry_rate_hz: 50.0,
            operate: false,
            pose_topic: "external_pose".into(),
        }
    }
}

impl Ros2Config {
    /// The node's options, `/cmd_vel` driving as `teleop` says.
    pub fn options(&self, teleop: crate::station::TeleopConfig) -> crate::ros2::Ros2Options {
        crate::ros2::Ros2Options {
            domain_id: self.domain_id,
            namespace: self.namespace.clone(),
            node_name: self.node_name.clone(),
            joint_states_rate_hz: self.joint_states_rate_hz,
            imu_rate_hz: self.imu_rate_hz,
            odometry_rate_hz: self.odometry_rate_hz,
            operate: self.operate,
            teleop,
            pose_topic: (!self.pose_topic.is_empty()).then(|| self.pose_topic.clone()),
        }
    }
}

impl Config {
    /// `[ros2]`: names ROS 2 accepts, a domain DDS can map to ports, a rate the loop has.
    pub(super) fn ros2_checks(&self, path: &Path) -> Result<(), ConfigFileError> {
        let bad = |key: &'static str, value: String, why: String| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value,
            why,
        };
        let r = &self.ros2;
        if r.domain_id > 232 {
            return Err(bad(
                "ros2.domain_id",
                r.domain_id.to_string(),
                "must be in [0, 232] (DDS maps larger ids outside the port range)".into(),
            ));
        }
        for (key, rate) in [
            ("ros2.joint_states_rate_hz", r.joint_states_rate_hz),
            ("ros2.imu_rate_hz", r.imu_rate_hz),
            ("ros2.odometry_rate_hz", r.odometry_rate_hz),
        ] {
            if !(rate.is_finite() && rate >= 1.0 && rate <= self.loop_.rate_hz) {
                return Err(bad(
                    key,
                    Num(rate).to_string(),
                    format!("must be in [1, {}] (loop.rate_hz)", Num(self.loop_.rate_hz)),
                ));
            }
        }
        if !r.pose_topic.is_empty()
            && let Err(e) = crate::ros2::name(&r.namespace, &r.pose_topic)
        {
            return Err(bad(
                "ros2.pose_topic",
                format!("{:?}", r.pose_topic),
                format!("not a ROS 2 topic name: {e}"),
            ));
        }
        if r.operate {
            self.foxglove
                .teleop()
                .check()
                .map_err(|e| bad("ros2.operate", "true".into(), format!("foxglove: {e}")))?;
        }
        if let Err(e) = ros2_client::NodeName::new(&r.namespace, &r.node_name) {
            return Err(bad(
                "ros2.node_name",
                format!("{:?} in namespace {:?}", r.node_name, r.namespace),
                format!("not a ROS 2 node name: {e:?}"),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros2_keys_are_checked_with_their_names() {
        let refused = |t: &str| {
            Config::parse(t, Path::new("x.toml"))
                .unwrap_err()
                .to_string()
        };
        let e = refused("[ros2]\ndomain_id = 300\n");
        assert!(e.contains("ros2.domain_id") && e.contains("232"), "{e}");
        let e = refused("[ros2]\njoint_states_rate_hz = 2000.0\n");
        assert!(
            e.contains("ros2.joint_states_rate_hz") && e.contains("1000"),
            "{e}"
        );
        let e = refused("[ros2]\nimu_rate_hz = 0.5\n");
        assert!(e.contains("ros2.imu_rate_hz"), "{e}");
        let e = refused("[ros2]\npose_topic = \"bad topic\"\n");
        assert!(e.contains("ros2.pose_topic"), "{e}");
        let e = refused("[ros2]\nnode_name = \"has space\"\n");
        assert!(e.contains("ros2.node_name"), "{e}");
        let e = refused("[ros2]\nnamespace = \"no_slash\"\n");
        assert!(
            e.contains("ros2.node_name") && e.contains("no_slash"),
            "{e}"
        );
        assert!(
            Config::parse(
                "[ros2]\nenabled = true\nnamespace = \"/snake\"\n",
                Path::new("x")
            )
            .is_ok()
        );
    }
}
