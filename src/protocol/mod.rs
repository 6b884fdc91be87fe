//! Module network protocol v2 (see `docs/protocol.md`).
//!
//! A compact little-endian binary format. A datagram carries one or more frames, each
//! `header (20 bytes) | payload | tag (16 bytes)`; the tag is a keyed BLAKE3 hash under
//! the network key (discovery, Acquire) or the session key (everything a session
//! sends), so only the owner can drive a module and only the module can report to it.
//! Decoding validates everything; a bad frame is reported as a [`DecodeError`] which
//! callers count and drop.
//!
//! The real-time path only encodes [`Command`]s and decodes [`Feedback`]: both are
//! `Copy` and neither allocates.

mod codec;
mod key;
mod name;
mod wire;

/// What a module takes and reports, as this protocol carries it.
pub use crate::module::{Command, Feedback};
pub use codec::{
    DecodeError, EncodeError, FRAME_OVERHEAD, Frames, HEADER_LEN, MAX_DATAGRAM, MAX_PAYLOAD,
    decode, encode, open, peek,
};
pub use key::{KEY_LEN, Key, KeyError, NONCE_LEN, Nonce, TAG_LEN};
pub use name::{NAME_CAPACITY, Name};

/// First two bytes of every datagram: ASCII "SN".
pub const MAGIC: [u8; 2] = *b"SN";
/// The protocol version this build speaks.
pub const VERSION: u8 = 2;
/// The previous version: refused, and counted apart so an old peer is easy to spot.
pub const VERSION_1: u8 = 1;
/// Session id that means "no session" (a free module, or a lookup).
pub const NO_SESSION: u32 = 0;

/// A module's hardware address.
pub type Mac = [u8; 6];

/// Fixed header of every frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    pub msg_type: MsgType,
    /// Session that owns the module ([`NO_SESSION`] for lookups).
    pub session: u32,
    /// Sender's sequence number, per sender and message stream; never wraps.
    pub seq: u64,
    /// Which module of the endpoint the frame is for or from (0 for a module that is
    /// its own endpoint; a gateway serves units 0..n on one address).
    pub unit: u16,
}

/// What a sender chooses for a frame's header (the type comes from the message).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Route {
    pub session: u32,
    pub seq: u64,
    pub unit: u16,
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
    /// Whether some session drives it now (which one is never disclosed).
    pub owned: bool,
}

/// The answer to an Acquire. Granted when the module is free, already granted to this
/// session and nonce, or its owner has been silent longer than its release timeout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AcquireReply {
    pub granted: bool,
    /// The module's half of the session key (zero when refused).
    pub module_nonce: Nonce,
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

/// Any message of the protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    Lookup(LookupFilter),
    Announce(Announce),
    /// Ask to drive a module with the header's session; carries the host's nonce.
    Acquire(Nonce),
    AcquireReply(AcquireReply),
    Release,
    Settings(Settings),
    SettingsAck(Settings),
    Command(Command),
    Feedback(Feedback),
}

impl MsgType {
    /// Discovery and Acquire are tagged with the network key, everything else with
    /// the session key (`docs/protocol.md` §4).
    pub fn uses_network_key(self) -> bool {
        matches!(
            self,
            MsgType::Lookup | MsgType::Announce | MsgType::Acquire | MsgType::AcquireReply
        )
    }
}

impl Message {
    pub fn msg_type(&self) -> MsgType {
        match self {
            Message::Lookup(_) => MsgType::Lookup,
            Message::Announce(_) => MsgType::Announce,
            Message::Acquire(_) => MsgType::Acquire,
            Message::AcquireReply(_) => MsgType::AcquireReply,
            Message::Release => MsgType::Release,
            Message::Settings(_) => MsgType::Settings,
            Message::SettingsAck(_) => MsgType::SettingsAck,
            Message::Command(_) => MsgType::Command,
            Message::Feedback(_) => MsgType::Feedback,
        }
    }
}
