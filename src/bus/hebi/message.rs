//! Reading one module's feedback and writing one module's command through libhebi's
//! message references: a field is present when its bit is set; the bus reads an absent
//! field as NaN (never as a number) and writes set-points as present fields.

use std::f64::consts::TAU;

use super::ffi::{HighResAngle, MessageRef, Metadata, field};
use crate::module::{Command, Feedback};

/// One module's feedback as the bus keeps it (`Feedback` plus what HEBI adds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The module's position arrived in this group feedback (a module that did not
    /// answer in time is in the group feedback with its fields absent).
    pub present: bool,
    /// NaN where a field is absent; `module_time_us` from the module's transmit time
    /// (else the library's receive time, else 0).
    pub feedback: Feedback,
    /// The module's own orientation estimate (w, x, y, z), NaN where it has none.
    pub orientation: [f32; 4],
    /// When the library received it, µs on the library's clock, if reported: a value
    /// that does not change between group feedbacks is old data repeated.
    pub receive_time_us: Option<u64>,
}

impl Default for Sample {
    fn default() -> Self {
        Self {
            present: false,
            feedback: absent_feedback(),
            orientation: [f32::NAN; 4],
            receive_time_us: None,
        }
    }
}

/// Feedback with every measured field NaN.
pub fn absent_feedback() -> Feedback {
    Feedback {
        position_rad: f32::NAN,
        velocity_rad_s: f32::NAN,
        torque_nm: f32::NAN,
        deflection_rad: f32::NAN,
        accel_m_s2: [f32::NAN; 3],
        gyro_rad_s: [f32::NAN; 3],
        temperature_c: f32::NAN,
        voltage_v: f32::NAN,
        ..Feedback::default()
    }
}

fn bit(bits: *const i32, index: u32) -> bool {
    // SAFETY (callers): `bits` holds `message_bitfield_count` bits and index < that.
    let word = unsafe { *bits.add((index / 32) as usize) };
    (word >> (index % 32)) & 1 == 1
}

fn set_bit(bits: *mut i32, index: u32) {
    // SAFETY (callers): as `bit`, and the message is ours to write.
    unsafe { *bits.add((index / 32) as usize) |= 1 << (index % 32) };
}

/// An angle from whole revolutions and an offset, rad.
pub fn angle(a: HighResAngle) -> f64 {
    a.revolutions as f64 * TAU + a.offset as f64
}

/// Splits `rad` into revolutions and an offset in [-π, π) (libhebi's own split).
pub fn high_res(rad: f32) -> HighResAngle {
    if !rad.is_finite() {
        return HighResAngle {
            revolutions: 0,
            offset: rad,
        };
    }
    let r = rad as f64;
    let revolutions = (r / TAU).round();
    HighResAngle {
        revolutions: revolutions as i64,
        offset: (r - revolutions * TAU) as f32,
    }
}

/// Reads one module's feedback.
///
/// # Safety
/// `r` is a reference the library filled for a live feedback message laid out by `m`.
pub unsafe fn read_feedback(r: &MessageRef, m: &Metadata) -> Sample {
    let bits = r.message_bitfield as *const i32;
    let float = |i: u32| {
        if bit(bits, m.float_field_bitfield_offset + i) {
            // SAFETY: i < float_field_count (checked at load).
            unsafe { *r.float_fields.add(i as usize) }
        } else {
            f32::NAN
        }
    };
    let vector = |i: u32| {
        if bit(bits, m.vector3f_field_bitfield_offset + i) {
            // SAFETY: i < vector3f_field_count.
            let v = unsafe { *r.vector3f_fields.add(i as usize) };
            [v.x, v.y, v.z]
        } else {
            [f32::NAN; 3]
        }
    };
    let uint = |i: u32| {
        // SAFETY: i < uint64_field_count.
        bit(bits, m.uint64_field_bitfield_offset + i)
            .then(|| unsafe { *r.uint64_fields.add(i as usize) })
    };
    let present = bit(
        bits,
        m.high_res_angle_field_bitfield_offset + field::FBK_POSITION,
    );
    let position_rad = if present {
        // SAFETY: FBK_POSITION < high_res_angle_field_count.
        angle(unsafe { *r.high_res_angle_fields.add(field::FBK_POSITION as usize) }) as f32
    } else {
        f32::NAN
    };
    let orientation = if bit(
        bits,
        m.quaternionf_field_bitfield_offset + field::FBK_ORIENTATION,
    ) {
        // SAFETY: FBK_ORIENTATION < quaternionf_field_count.
        let q = unsafe { *r.quaternionf_fields.add(field::FBK_ORIENTATION as usize) };
        [q.w, q.x, q.y, q.z]
    } else {
        [f32::NAN; 4]
    };
    let receive_time_us = uint(field::FBK_RECEIVE_TIME);
    let module_time_us = uint(field::FBK_HARDWARE_TRANSMIT_TIME)
        .or(receive_time_us)
        .unwrap_or(0);
    Sample {
        present,
        feedback: Feedback {
            module_time_us,
            last_command_seq: 0,
            position_rad,
            velocity_rad_s: float(field::FBK_VELOCITY),
            // HEBI's effort is the torque the actuator applies at its output, which is
            // the protocol's sign (docs/protocol.md): no change.
            torque_nm: float(field::FBK_EFFORT),
            deflection_rad: float(field::FBK_DEFLECTION),
            accel_m_s2: vector(field::FBK_ACCELEROMETER),
            gyro_rad_s: vector(field::FBK_GYRO),
            temperature_c: float(field::FBK_BOARD_TEMPERATURE),
            voltage_v: float(field::FBK_VOLTAGE),
        },
        orientation,
        receive_time_us,
    }
}

/// Writes one module's set-points into its command message: each of position,
/// velocity and effort as given, NaN included (HEBI reads a NaN target as "this loop
/// does not drive"; a limp command sets all three NaN, an explicit stop).
///
/// An imitation group echoes only what was commanded, and has no position of its own:
/// for it (`imitation` = the module's last commanded position) a NaN position goes out
/// as that last position (the module stays where it was, as a limp module at rest
/// does) and a NaN velocity or effort as 0, so that its echo is a number.
///
/// # Safety
/// `r` is a reference the library filled for a live command message laid out by `m`,
/// not in use by another thread.
pub unsafe fn write_command(r: &MessageRef, m: &Metadata, c: &Command, imitation: Option<f32>) {
    let fill = |v: f32| {
        if imitation.is_some() && v.is_nan() {
            0.0
        } else {
            v
        }
    };
    let position = match imitation {
        Some(last) if c.position_rad.is_nan() => last,
        _ => c.position_rad,
    };
    let bits = r.message_bitfield;
    // SAFETY: the indices are below the counts checked at load.
    unsafe {
        *r.high_res_angle_fields.add(field::CMD_POSITION as usize) = high_res(position);
        *r.float_fields.add(field::CMD_VELOCITY as usize) = fill(c.velocity_rad_s);
        *r.float_fields.add(field::CMD_EFFORT as usize) = fill(c.torque_nm);
    }
    set_bit(
        bits,
        m.high_res_angle_field_bitfield_offset + field::CMD_POSITION,
    );
    set_bit(bits, m.float_field_bitfield_offset + field::CMD_VELOCITY);
    set_bit(bits, m.float_field_bitfield_offset + field::CMD_EFFORT);
}

/// Writes a command float field (a gain) as present.
///
/// # Safety
/// As [`write_command`], and `index` < the command's float field count.
pub unsafe fn write_float(r: &MessageRef, m: &Metadata, index: u32, value: f32) {
    // SAFETY: caller's contract.
    unsafe { *r.float_fields.add(index as usize) = value };
    set_bit(r.message_bitfield, m.float_field_bitfield_offset + index);
}

/// Writes a command enum field (the control strategy) as present.
///
/// # Safety
/// As [`write_command`], and `index` < the command's enum field count.
pub unsafe fn write_enum(r: &MessageRef, m: &Metadata, index: u32, value: i32) {
    // SAFETY: caller's contract.
    unsafe { *r.enum_fields.add(index as usize) = value };
    set_bit(r.message_bitfield, m.enum_field_bitfield_offset + index);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn high_res_angles_round_trip() {
        for rad in [0.0f32, 1.0, -1.0, 3.2, -3.2, 7.0, -20.5] {
            let h = high_res(rad);
            assert!((angle(h) as f32 - rad).abs() < 1e-5, "{rad}");
            assert!(h.offset.abs() <= std::f32::consts::PI + 1e-6);
        }
        assert!(high_res(f32::NAN).offset.is_nan());
        assert!(angle(high_res(f32::NAN)).is_nan());
    }
}
