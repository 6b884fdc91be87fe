//! Module network protocol v1 (see `docs/protocol.md`).
//!
//! A compact little-endian binary format. Every datagram is
//! `header (16 bytes) | payload | crc32 (4 bytes)`. Every module is its own UDP
//! endpoint. Decoding validates everything; a bad datagram is reported as a
//! [`DecodeError`] which callers count and drop.
//!
//! The real-time path only encodes [`Command`]s and decodes [`Feedback`]: both are
//! `Copy` and neither allocates.

mod codec;
mod name;

pub use codec::{DecodeError, EncodeError, MAX_DATAGRAM, decode, encode};
pub use name::{NAME_CAPACITY, Name};

/// First two bytes of every datagram: ASCII "SN".
pub const MAGIC: [u8; 2] = *b"SN";
/// The protocol version this build speaks.
pub const VERSION: u8 = 1;
/// Session id that means "no session" (a free module, or a lookup).
pub const NO_SESSION: u32 = 0;

/// A module's hardware address.
pub type Mac = [u8; 6];

/// Fixed header of every datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    pub msg_type: MsgType,
    /// Session that owns the module ([`NO_SESSION`] for lookups).
    pub session: u32,
    /// Sender's sequence number, per sender and message stream.
    pub seq: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum MsgType {
    Lookup = 1,
    Announce = 2,
    Acquire = 3,
    AcquireReply = 4,
    Release = 5,
    Settings = 6,
    SettingsAck = 7,
    Command = 8,
    Feedback = 9,
}

/// Which modules a lookup asks to answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LookupFilter {
    /// Every module answers.
    All,
    /// Modules whose family equals this.
    Family(Name),
    /// Modules whose name is in the list.
    Names(Vec<Name>),
    /// Modules whose MAC is in the list.
    Macs(Vec<Mac>),
}

/// A module's answer to a lookup: who it is and whether it is free.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Announce {
    pub mac: Mac,
    pub family: Name,
    pub name: Name,
    pub firmware: u32,
    /// Session currently driving it ([`NO_SESSION`] when free).
    pub owner_session: u32,
}

/// Ask to drive a module with the header's session id. Granted when the module is
/// free, already owned by this session, or its owner has been silent longer than
/// its release timeout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AcquireReply {
    pub granted: bool,
    /// The session that owns the module after this request.
    pub owner_session: u32,
}

/// How the module's own servo runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ControlStrategy {
    /// Motor off: the joint is limp whatever is commanded.
    Off = 0,
    /// Cascaded position → velocity → torque control (the default).
    Cascaded = 1,
}

/// Per-module settings, sent by the session owner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// How often the module streams feedback to its owner, Hz (1..=2000).
    pub feedback_rate_hz: f32,
    /// A command older than this stops driving and the module goes limp, s (> 0).
    pub command_lifetime_s: f32,
    pub strategy: ControlStrategy,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            feedback_rate_hz: 1000.0,
            command_lifetime_s: 0.05,
            strategy: ControlStrategy::Cascaded,
        }
    }
}

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
    pub last_command_seq: u32,
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

/// Any message of the protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    Lookup(LookupFilter),
    Announce(Announce),
    Acquire,
    AcquireReply(AcquireReply),
    Release,
    Settings(Settings),
    SettingsAck(Settings),
    Command(Command),
    Feedback(Feedback),
}

impl Message {
    pub fn msg_type(&self) -> MsgType {
        match self {
            Message::Lookup(_) => MsgType::Lookup,
            Message::Announce(_) => MsgType::Announce,
            Message::Acquire => MsgType::Acquire,
            Message::AcquireReply(_) => MsgType::AcquireReply,
            Message::Release => MsgType::Release,
            Message::Settings(_) => MsgType::Settings,
            Message::SettingsAck(_) => MsgType::SettingsAck,
            Message::Command(_) => MsgType::Command,
            Message::Feedback(_) => MsgType::Feedback,
        }
    }
}
