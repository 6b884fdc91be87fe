//! What one module takes and reports, whatever carries it: protocol v2 over UDP
//! (`protocol`, `bus::udp`), the in-process emulator (`emu::sim_bus`), the loop and
//! the recorder alike; and the module's body, the figures everything that models,
//! draws or drives the SEA Snake uses (the emulator, the recorder's scene and URDF, the
//! gaits, the lab).

/// Length of one SEA Snake module, joint to joint, m (SPEC §1: 6.4 cm, the thesis's
/// Table 2.1).
pub const MODULE_LENGTH_M: f64 = 0.064;
/// Diameter of one module, m (SPEC §1: 5.1 cm, the thesis's Table 2.1).
pub const MODULE_DIAMETER_M: f64 = 0.051;
/// Radius of one module, m: half [`MODULE_DIAMETER_M`] (2.55 cm).
pub const MODULE_RADIUS_M: f64 = 0.5 * MODULE_DIAMETER_M;
/// Mass of one module, kg (SPEC §1: 205 g, the thesis's Table 2.1).
pub const MODULE_MASS_KG: f64 = 0.205;
/// A module's maximum output speed, rad/s (SPEC §1: 33 rpm, the thesis's Table 2.1).
pub const MODULE_MAX_SPEED_RAD_S: f64 = 3.46;
/// A module's maximum output torque, N·m (SPEC §1: 7 N·m, the thesis's Table 2.1).
pub const MODULE_MAX_TORQUE_NM: f64 = 7.0;

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
