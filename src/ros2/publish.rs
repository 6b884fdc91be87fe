//! What the node publishes from a recorded cycle, in ROS 2's own messages (pure, no
//! DDS): the joints (`sensor_msgs/JointState`), each module's IMU (`sensor_msgs/Imu`,
//! REP-145's `data_raw`: no orientation), and the virtual chassis as odometry
//! (`nav_msgs/Odometry`) and transforms (`odom → base_link → body`, REP-105).
//!
//! Frames (REP-103): metres, radians, x forward, z up. `odom` is the estimate's world
//! (yaw 0 where the estimator started; it drifts); `base_link` is the virtual chassis
//! (x toward the head); `body` is the URDF's root, the head link, and `module_k` its
//! links (`robot_state_publisher` places them from `/joint_states`). Covariances that
//! are not known are −1 on the diagonal.

use nalgebra::{Quaternion as NQuat, UnitQuaternion, Vector3 as NVec};

use super::msg::{
    Fixed, Header, Imu, JointState, Odometry, Pose, PoseWithCovariance, Quaternion, Time,
    Transform, TransformStamped, Twist, TwistWithCovariance, Vector3,
};
use crate::controller_interface::BodyEstimate;
use crate::record::cycle::CycleRecord;

pub const ODOM_FRAME: &str = "odom";
pub const BASE_FRAME: &str = "base_link";
/// The URDF's root link (`record::urdf`).
pub const HEAD_FRAME: &str = "body";

/// A covariance whose every variance is unknown (−1 on the diagonal).
pub fn unknown_covariance<const N: usize>() -> Fixed<N> {
    let side = (N as f64).sqrt() as usize;
    let mut a = [0.0; N];
    for i in 0..side {
        a[i * side + i] = -1.0;
    }
    Fixed(a)
}

fn header(stamp: Time, frame: &str) -> Header {
    Header {
        stamp,
        frame_id: frame.to_owned(),
    }
}

/// The URDF link module `k` (from 0) drives, whose frame its IMU is reported in.
pub fn module_frame(k: usize) -> String {
    format!("module_{}", k + 1)
}

/// A name usable in a ROS topic (letters, digits, `_`; not starting with a digit).
pub fn topic_token(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, 'm');
    }
    s
}

/// The joints of `rec` into `msg` (names kept), buffers reused.
pub fn joint_state(rec: &CycleRecord, stamp: Time, msg: &mut JointState) {
    let n = rec.joints().len().min(msg.name.len());
    msg.header.stamp = stamp;
    msg.position.clear();
    msg.velocity.clear();
    msg.effort.clear();
    for j in &rec.joints()[..n] {
        msg.position.push(j.position_rad as f64);
        msg.velocity.push(j.velocity_rad_s as f64);
        msg.effort.push(j.torque_nm as f64);
    }
}

/// Module `k`'s IMU in `rec`: rates and accelerations, no orientation (REP-145).
pub fn imu(rec: &CycleRecord, k: usize, stamp: Time, frame: &str) -> Imu {
    let j = &rec.joints()[k];
    let v = |a: [f32; 3]| Vector3 {
        x: a[0] as f64,
        y: a[1] as f64,
        z: a[2] as f64,
    };
    Imu {
        header: header(stamp, frame),
        orientation: Quaternion::default(),
        // sensor_msgs: −1 first says "no orientation".
        orientation_covariance: Fixed::unknown(),
        angular_velocity: v(j.gyro_rad_s),
        angular_velocity_covariance: unknown_covariance(),
        linear_acceleration: v(j.accel_m_s2),
        linear_acceleration_covariance: unknown_covariance(),
    }
}

fn quat(q: UnitQuaternion<f64>) -> Quaternion {
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

fn unit(wxyz: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(NQuat::new(wxyz[0], wxyz[1], wxyz[2], wxyz[3]))
}

/// The chassis in `odom`: on the ground plane where contact odometry puts it, turned
/// as the estimate says.
fn chassis_pose(b: &BodyEstimate) -> (NVec<f64>, UnitQuaternion<f64>) {
    (
        NVec::new(b.odometry_m[0], b.odometry_m[1], 0.0),
        unit(b.orientation_wxyz),
    )
}

/// The head link in the chassis frame.
fn head_in_chassis(b: &BodyEstimate) -> (NVec<f64>, UnitQuaternion<f64>) {
    let chassis = unit(b.orientation_wxyz);
    let head = unit(b.head_wxyz);
    let origin = NVec::from(b.position_m);
    let inv = chassis.inverse();
    (inv * -origin, inv * head)
}

/// The chassis' velocity in its own frame from two estimates `dt_s` apart (`None`
/// before there are two).
pub fn chassis_twist(before: &BodyEstimate, now: &BodyEstimate, dt_s: f64) -> Option<Twist> {
    if !(before.valid && now.valid && dt_s > 0.0) {
        return None;
    }
    let (p0, q0) = chassis_pose(before);
    let (p1, q1) = chassis_pose(now);
    let v = q1.inverse() * ((p1 - p0) / dt_s);
    let w = (q0.inverse() * q1).scaled_axis() / dt_s;
    Some(Twist {
        linear: Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        },
        angular: Vector3 {
            x: w.x,
            y: w.y,
            z: w.z,
        },
    })
}

/// The chassis as odometry (`None` while the estimate is not valid).
pub fn odometry(b: &BodyEstimate, twist: Option<Twist>, stamp: Time) -> Option<Odometry> {
    if !b.valid {
        return None;
    }
    let (p, q) = chassis_pose(b);
    Some(Odometry {
        header: header(stamp, ODOM_FRAME),
        child_frame_id: BASE_FRAME.into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Vector3 {
                    x: p.x,
                    y: p.y,
                    z: p.z,
                },
                orientation: quat(q),
            },
            covariance: unknown_covariance(),
        },
        twist: TwistWithCovariance {
            twist: twist.unwrap_or_default(),
            covariance: unknown_covariance(),
        },
    })
}

fn transform(
    stamp: Time,
    parent: &str,
    child: &str,
    (t, q): (NVec<f64>, UnitQuaternion<f64>),
) -> TransformStamped {
    TransformStamped {
        header: header(stamp, parent),
        child_frame_id: child.into(),
        transform: Transform {
            translation: Vector3 {
                x: t.x,
                y: t.y,
                z: t.z,
            },
            rotation: quat(q),
        },
    }
}

/// `odom → base_link` and `base_link → body` (none while the estimate is not valid).
pub fn transforms(b: &BodyEstimate, stamp: Time) -> Vec<TransformStamped> {
    if !b.valid {
        return Vec::new();
    }
    vec![
        transform(stamp, ODOM_FRAME, BASE_FRAME, chassis_pose(b)),
        transform(stamp, BASE_FRAME, HEAD_FRAME, head_in_chassis(b)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::cycle::JointSample;

    fn estimate(x: f64, y: f64, yaw: f64) -> BodyEstimate {
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        BodyEstimate {
            valid: true,
            // The chassis 0.3 m behind the head along the chassis' x, on world axes.
            position_m: (q * NVec::new(-0.3, 0.0, 0.0)).into(),
            orientation_wxyz: [q.w, q.i, q.j, q.k],
            heading_rad: yaw,
            odometry_m: [x, y],
            head_wxyz: [q.w, q.i, q.j, q.k],
            ..BodyEstimate::NONE
        }
    }

    #[test]
    fn joints_in_si_units_with_their_names() {
        let mut rec = CycleRecord::EMPTY;
        rec.modules = 2;
        rec.joints[0] = JointSample {
            position_rad: 0.5,
            velocity_rad_s: -1.0,
            torque_nm: 2.0,
            ..rec.joints[0]
        };
        let mut msg = JointState {
            name: vec!["a".into(), "b".into()],
            ..JointState::default()
        };
        joint_state(&rec, Time::from_unix_ns(1_500_000_000), &mut msg);
        assert_eq!(msg.position, [0.5, 0.0]);
        assert_eq!(msg.velocity, [-1.0, 0.0]);
        assert_eq!(msg.effort, [2.0, 0.0]);
        assert_eq!(
            (msg.header.stamp.sec, msg.header.stamp.nanosec),
            (1, 500_000_000)
        );
    }

    #[test]
    fn an_imu_has_rates_and_accelerations_and_says_it_has_no_orientation() {
        let mut rec = CycleRecord::EMPTY;
        rec.modules = 1;
        rec.joints[0].gyro_rad_s = [0.1, 0.2, 0.3];
        rec.joints[0].accel_m_s2 = [0.0, 0.0, 9.8];
        let m = imu(&rec, 0, Time::default(), &module_frame(0));
        assert_eq!(m.header.frame_id, "module_1");
        assert_eq!(m.orientation_covariance.0[0], -1.0);
        assert!((m.angular_velocity.z - 0.3).abs() < 1e-6);
        assert!((m.linear_acceleration.z - 9.8).abs() < 1e-6);
        assert_eq!(m.linear_acceleration_covariance.0[4], -1.0);
    }

    #[test]
    fn odometry_and_transforms_put_the_chassis_in_odom_and_the_head_ahead_of_it() {
        let yaw = std::f64::consts::FRAC_PI_2;
        let b = estimate(1.0, 2.0, yaw);
        let o = odometry(&b, None, Time::default()).unwrap();
        assert_eq!(
            (o.header.frame_id.as_str(), o.child_frame_id.as_str()),
            ("odom", "base_link")
        );
        assert_eq!((o.pose.pose.position.x, o.pose.pose.position.y), (1.0, 2.0));
        assert!((o.pose.pose.orientation.z - (yaw / 2.0).sin()).abs() < 1e-12);
        assert_eq!(o.pose.covariance.0[0], -1.0);
        assert_eq!(o.pose.covariance.0[1], 0.0);
        let tf = transforms(&b, Time::default());
        assert_eq!(tf[1].header.frame_id, "base_link");
        assert_eq!(tf[1].child_frame_id, "body");
        // The head 0.3 m ahead along the chassis' x, turned as the chassis is.
        let t = tf[1].transform.translation;
        assert!((t.x - 0.3).abs() < 1e-12 && t.y.abs() < 1e-12, "{t:?}");
        assert!((tf[1].transform.rotation.w - 1.0).abs() < 1e-12);
        assert!(transforms(&BodyEstimate::NONE, Time::default()).is_empty());
        assert!(odometry(&BodyEstimate::NONE, None, Time::default()).is_none());
    }

    #[test]
    fn the_twist_is_in_the_chassis_frame() {
        let yaw = std::f64::consts::FRAC_PI_2;
        // Facing +y, moving 0.1 m along +y in 1 s while turning 0.2 rad: forward at 0.1 m/s.
        let tw = chassis_twist(
            &estimate(0.0, 0.0, yaw),
            &estimate(0.0, 0.1, yaw + 0.2),
            1.0,
        )
        .unwrap();
        assert!((tw.linear.x - 0.1 * 0.2f64.cos()).abs() < 1e-9, "{tw:?}");
        assert!((tw.angular.z - 0.2).abs() < 1e-9);
        assert!(chassis_twist(&BodyEstimate::NONE, &estimate(0.0, 0.0, 0.0), 1.0).is_none());
    }

    #[test]
    fn module_names_become_topic_tokens() {
        assert_eq!(topic_token("module-01"), "module_01");
        assert_eq!(topic_token("3rd"), "m3rd");
        assert_eq!(topic_token(""), "m");
    }
}
