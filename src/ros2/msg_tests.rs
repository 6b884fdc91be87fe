//! The messages' CDR bytes as DDS lays them out (XCDR1, little-endian: each primitive
//! aligned to its size from the payload's start; strings and sequences with a u32
//! length; fixed arrays without).

use super::msg::*;

fn cdr<T: serde::Serialize>(v: &T) -> Vec<u8> {
    cdr_encoding::to_vec::<T, byteorder::LittleEndian>(v).unwrap()
}

#[test]
fn a_joint_state_encodes_as_ros_lays_it_out() {
    let m = JointState {
        header: Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "ab".into(),
        },
        name: vec!["j1".into()],
        position: vec![0.5],
        velocity: vec![],
        effort: vec![-1.0],
    };
    let b = cdr(&m);
    // sec, nanosec, "ab\0" (length 3), pad to 4; one name "j1\0", pad to 4; each
    // float64 aligned to 8 from the start of the payload.
    let mut want = vec![1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0];
    want.extend([1, 0, 0, 0, 3, 0, 0, 0, b'j', b'1', 0, 0]);
    want.extend([1, 0, 0, 0]); // position: 1 element, the double at offset 32
    want.extend(0.5f64.to_le_bytes());
    want.extend([0, 0, 0, 0]); // velocity: empty
    want.extend([1, 0, 0, 0]); // effort: 1 element, the double at offset 48
    want.extend((-1.0f64).to_le_bytes());
    assert_eq!(b, want);
}

#[test]
fn fixed_arrays_have_no_length_and_round_trip() {
    let imu = Imu {
        header: Header::default(),
        orientation: Quaternion::default(),
        orientation_covariance: Fixed::unknown(),
        angular_velocity: Vector3::default(),
        angular_velocity_covariance: Fixed([0.0; 9]),
        linear_acceleration: Vector3 {
            x: 0.0,
            y: 0.0,
            z: 9.81,
        },
        linear_acceleration_covariance: Fixed([0.0; 9]),
    };
    let b = cdr(&imu);
    // header 4+4+4("" is length 1 + NUL)+pad; then 4 + 9 + 3 + 9 + 3 + 9 doubles.
    assert_eq!(b.len(), 16 + 8 * (4 + 9 + 3 + 9 + 3 + 9));
    let (back, _) = cdr_encoding::from_bytes::<Imu, byteorder::LittleEndian>(&b).unwrap();
    assert_eq!(back, imu);
}
