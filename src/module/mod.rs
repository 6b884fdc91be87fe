//! What one module takes and reports, whatever carries it: protocol v2 over UDP
//! (`protocol`, `bus::udp`), the in-process emulator (`emu::sim_bus`), the loop and
//! the recorder alike.

/// Set-points for one module. NaN means "not commanded". All three NaN = limp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    pub position_rad: f32,
    pub velocity_rad_s: f32,
    pub torque_nm: f32,
}

impl Command {
    pub const LIMP: Command = Command {
        position_rad: f32::NAN,
        velocity_rad_s: f32::NAN,
        torque_nm: f32::NAN,
    };

    pub fn position(position_rad: f64) -> Self {
        Command {
            position_rad: position_rad as f32,
            ..Self::LIMP
        }
    }

    pub fn is_limp(&self) -> bool {
        self.position_rad.is_nan() && self.velocity_rad_s.is_nan() && self.torque_nm.is_nan()
    }
}

/// One module's feedback sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Feedback {
    /// Module clock, µs since the module started (the emulator's simulated clock).
    pub module_time_us: u64,
    /// Sequence number of the last command the module applied (0 if none).
    pub last_command_seq: u64,
    pub position_rad: f32,
    pub velocity_rad_s: f32,
    /// Spring torque: stiffness × deflection. Positive when the output is pushed
    /// in the joint's negative direction relative to the motor (see docs/protocol.md).
    pub torque_nm: f32,
    pub deflection_rad: f32,
    pub accel_m_s2: [f32; 3],
    pub gyro_rad_s: [f32; 3],
    pub temperature_c: f32,
    pub voltage_v: f32,
}
