//! snaked as a ROS 2 node (`ros2-client` on RustDDS: no ROS installation), on a thread
//! of its own (`snaked-ros2`), never the loop's:
//!
//! - [`sink`]: the recorder's writer hands it each recorded cycle, decimated, without
//!   waiting.
//! - [`publish`]: a cycle as ROS 2 messages (joints, IMUs, odometry, transforms).
//! - [`status`]: the loop's snapshot as `/diagnostics` and `~/state`.
//! - [`node`]: the node, its topics, and the thread that publishes them.
//! - `operate`: with `[ros2] operate`, `/cmd_vel`, the services and the parameters,
//!   each a thin edge over the operator API, like the socket and Foxglove.
//! - `parameters`: the ROS 2 parameter services over `operator::parameters`.
//! - [`msg`]: ROS 2's messages as serde structs (CDR through RustDDS).

pub mod msg;
#[cfg(test)]
mod msg_tests;
pub mod node;
mod operate;
mod parameters;
pub mod publish;
pub mod sink;
pub mod status;

use std::sync::{Arc, OnceLock};

pub use node::{BridgeCounters, Ros2Error, start};

use crate::operator::Operator;
use crate::station::TeleopConfig;

/// What `[ros2]` asks of the node.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Options {
    pub domain_id: u16,
    /// The node's namespace ("/" or e.g. "/snake"); topics are under it.
    pub namespace: String,
    pub node_name: String,
    /// `/joint_states` rate, Hz (up to the loop's).
    pub joint_states_rate_hz: f64,
    /// Each module's IMU, Hz (at most the joint states').
    pub imu_rate_hz: f64,
    /// `/odom` and `/tf`, Hz (at most the joint states').
    pub odometry_rate_hz: f64,
    /// Whether ROS 2 may drive and tune the robot (`/cmd_vel`, services, parameters).
    pub operate: bool,
    /// How `/cmd_vel` drives (the station's mapping and dead-man).
    pub teleop: TeleopConfig,
    /// The external pose's topic (`geometry_msgs/PoseStamped`); `None`: not read.
    pub pose_topic: Option<String>,
}

/// The running node as the daemon holds it: its counters, and where the operator API
/// is bound once the control socket runs (until then, requests wait).
#[derive(Clone)]
pub struct Ros2Handle {
    pub counters: Arc<BridgeCounters>,
    pub(crate) operator: Arc<OnceLock<Operator>>,
}

impl Ros2Handle {
    /// Binds the operator API; later binds are ignored.
    pub fn bind(&self, operator: Operator) {
        let _ = self.operator.set(operator);
    }
}

/// A topic or service name: `path` (relative, "a/b/c", or absolute, "/a/b/c") under
/// the namespace `ns` ("/" or "/x/y"). ROS 2's `Name` takes the last token apart.
pub fn name(ns: &str, path: &str) -> Result<ros2_client::Name, String> {
    let full = if path.starts_with('/') {
        path.to_owned()
    } else {
        format!("{}/{path}", ns.trim_end_matches('/'))
    };
    let (dir, base) = full.rsplit_once('/').unwrap_or(("", &full));
    let dir = if dir.is_empty() { "/" } else { dir };
    ros2_client::Name::new(dir, base).map_err(|e| format!("{full:?}: {e:?}"))
}

/// The machine's interfaces that are up and have an address, loopback aside: where
/// DDS discovery reaches besides localhost.
pub fn interfaces_beyond_loopback() -> Vec<String> {
    let mut out = Vec::new();
    let mut addrs: *mut libc::ifaddrs = std::ptr::null_mut();
    // SAFETY: getifaddrs fills a list that freeifaddrs frees; each entry is read only
    // while the list lives, and its name is a NUL-terminated string.
    unsafe {
        if libc::getifaddrs(&mut addrs) != 0 {
            return out;
        }
        let mut a = addrs;
        while !a.is_null() {
            let i = &*a;
            let flags = i.ifa_flags;
            let up = flags & libc::IFF_UP as u32 != 0;
            let loopback = flags & libc::IFF_LOOPBACK as u32 != 0;
            let inet = !i.ifa_addr.is_null()
                && matches!(
                    i32::from((*i.ifa_addr).sa_family),
                    libc::AF_INET | libc::AF_INET6
                );
            if up && !loopback && inet {
                let name = std::ffi::CStr::from_ptr(i.ifa_name)
                    .to_string_lossy()
                    .into_owned();
                if !out.contains(&name) {
                    out.push(name);
                }
            }
            a = i.ifa_next;
        }
        libc::freeifaddrs(addrs);
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn names_under_a_namespace_or_absolute() {
        let full = |ns, p| super::name(ns, p).map(|n| n.to_string());
        assert_eq!(full("/", "joint_states").unwrap(), "/joint_states");
        assert_eq!(
            full("/snake", "imu/m_01/data_raw").unwrap(),
            "/snake/imu/m_01/data_raw"
        );
        assert_eq!(
            full("/snake", "/vrpn/body/pose").unwrap(),
            "/vrpn/body/pose"
        );
        assert_eq!(
            full("/snaked", "gait/rolling").unwrap(),
            "/snaked/gait/rolling"
        );
        assert!(full("/", "bad topic").is_err());
        assert!(full("/", "a//b").is_err());
    }
}
