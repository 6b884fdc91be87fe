//! ROS 2 message types the node publishes and takes, as serde structs in the field
//! order of their `.msg` definitions (what DDS's CDR encoding follows): `ros2-client`
//! serialises them. Names and units as ROS has them (REP-103: metres, radians, s).

use serde::{Deserialize, Serialize};

/// builtin_interfaces/Time
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    pub fn from_unix_ns(ns: u64) -> Self {
        Self {
            sec: (ns / 1_000_000_000) as i32,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// ns since the Unix epoch (0 before it).
    pub fn unix_ns(&self) -> u64 {
        u64::try_from(self.sec).map_or(0, |s| s * 1_000_000_000 + u64::from(self.nanosec))
    }
}

/// std_msgs/Header
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// sensor_msgs/JointState
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    pub header: Header,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// geometry_msgs/Vector3 (also Point's layout)
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// geometry_msgs/Quaternion
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// geometry_msgs/Pose
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

/// geometry_msgs/Twist
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}

/// A fixed `float64[N]` (CDR: no length prefix; serde's derive stops at 32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed<const N: usize>(pub [f64; N]);

impl<const N: usize> Fixed<N> {
    /// ROS's "unknown": the first element −1 (REP-145, sensor_msgs/Imu).
    pub fn unknown() -> Self {
        let mut a = [0.0; N];
        a[0] = -1.0;
        Self(a)
    }
}

impl<const N: usize> Serialize for Fixed<N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(N)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

impl<'de, const N: usize> Deserialize<'de> for Fixed<N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> serde::de::Visitor<'de> for V<N> {
            type Value = Fixed<N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "{N} float64")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Fixed<N>, A::Error> {
                let mut out = [0.0; N];
                for (i, o) in out.iter_mut().enumerate() {
                    *o = a
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Fixed(out))
            }
        }
        d.deserialize_tuple(N, V::<N>)
    }
}

/// geometry_msgs/PoseWithCovariance
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    pub pose: Pose,
    pub covariance: Fixed<36>,
}

/// geometry_msgs/TwistWithCovariance
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    pub twist: Twist,
    pub covariance: Fixed<36>,
}

/// nav_msgs/Odometry
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: String,
    pub pose: PoseWithCovariance,
    pub twist: TwistWithCovariance,
}

/// sensor_msgs/Imu (REP-145)
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Imu {
    pub header: Header,
    pub orientation: Quaternion,
    pub orientation_covariance: Fixed<9>,
    pub angular_velocity: Vector3,
    pub angular_velocity_covariance: Fixed<9>,
    pub linear_acceleration: Vector3,
    pub linear_acceleration_covariance: Fixed<9>,
}

/// geometry_msgs/Transform
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    pub translation: Vector3,
    pub rotation: Quaternion,
}

/// geometry_msgs/TransformStamped
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

/// tf2_msgs/TFMessage
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}

/// geometry_msgs/PoseStamped
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    pub header: Header,
    pub pose: Pose,
}

/// diagnostic_msgs/KeyValue
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}

/// diagnostic_msgs/DiagnosticStatus; `level`: 0 OK, 1 WARN, 2 ERROR, 3 STALE.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    pub level: u8,
    pub name: String,
    pub message: String,
    pub hardware_id: String,
    pub values: Vec<KeyValue>,
}

/// diagnostic_msgs/DiagnosticArray
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    pub header: Header,
    pub status: Vec<DiagnosticStatus>,
}

/// std_msgs/String
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StringMsg {
    pub data: String,
}

/// std_srvs/Trigger's request: an empty message, which ROS 2's IDL gives one byte.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Empty {
    pub structure_needs_at_least_one_member: u8,
}

/// std_srvs/SetBool's request.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SetBoolRequest {
    pub data: bool,
}

/// std_srvs/Trigger's and SetBool's response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ServiceAnswer {
    pub success: bool,
    pub message: String,
}

impl ros2_client::Message for JointState {}
impl ros2_client::Message for Imu {}
impl ros2_client::Message for Odometry {}
impl ros2_client::Message for TfMessage {}
impl ros2_client::Message for PoseStamped {}
impl ros2_client::Message for Twist {}
impl ros2_client::Message for DiagnosticArray {}
impl ros2_client::Message for StringMsg {}
impl ros2_client::Message for Empty {}
impl ros2_client::Message for SetBoolRequest {}
impl ros2_client::Message for ServiceAnswer {}
