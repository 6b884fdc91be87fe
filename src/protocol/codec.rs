//! Encoding and decoding of protocol v2 frames. Byte layouts: `docs/protocol.md`.
//!
//! `frame = header (20 B) | payload | tag (16 B)`, little endian; a datagram holds one
//! or more frames back to back ([`Frames`]). The encoding is canonical: every frame
//! `open` accepts re-encodes to the same bytes (reserved bytes and name padding must be
//! zero), and the tag covers every byte before it.
use super::wire::{Reader, Writer};
use super::{
    AcquireReply, Announce, Command, ControlStrategy, Feedback, Header, Key, LookupFilter, MAGIC,
    Mac, Message, MsgType, NONCE_LEN, Route, Settings, TAG_LEN, VERSION,
};

/// Largest datagram this protocol produces or accepts, bytes.
pub const MAX_DATAGRAM: usize = 1400;

/// Bytes of a frame header.
pub const HEADER_LEN: usize = 20;
/// Bytes a frame adds to its payload.
pub const FRAME_OVERHEAD: usize = HEADER_LEN + TAG_LEN;
/// Largest payload of one frame.
pub const MAX_PAYLOAD: usize = MAX_DATAGRAM - FRAME_OVERHEAD;

// Payload sizes of the fixed-size messages, bytes.
const ANNOUNCE_LEN: usize = 78;
const ACQUIRE_LEN: usize = NONCE_LEN;
const ACQUIRE_REPLY_LEN: usize = 4 + NONCE_LEN;
const SETTINGS_LEN: usize = 12;
const COMMAND_LEN: usize = 12;
const FEEDBACK_LEN: usize = 64;
/// Lookup payload before its entries: kind u8, reserved u8, count u16.
const LOOKUP_HEAD_LEN: usize = 4;
const MAC_LEN: usize = 6;

// Lookup filter kinds on the wire.
const FILTER_ALL: u8 = 0;
const FILTER_FAMILY: u8 = 1;
const FILTER_NAMES: u8 = 2;
const FILTER_MACS: u8 = 3;

/// Announce flags.
const OWNED: u8 = 1;

#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    #[error("buffer too small for the message")]
    BufferTooSmall,
    #[error("message too large for one datagram")]
    TooLarge,
    /// The message holds a value the protocol forbids (e.g. an infinite set-point).
    #[error("message not encodable: {0}")]
    Invalid(&'static str),
}

/// Why a frame was rejected. Receivers count these per kind and drop the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    #[error("datagram truncated")]
    Truncated,
    #[error("bad magic")]
    BadMagic,
    #[error("unsupported protocol version {0}")]
    WrongVersion(u8),
    #[error("unknown message type {0}")]
    UnknownType(u8),
    #[error("payload length does not match the datagram")]
    BadLength,
    /// Corrupted, forged, or tagged under another key (another session, another network).
    #[error("authentication tag mismatch")]
    BadTag,
    #[error("malformed payload: {0}")]
    Malformed(&'static str),
}

/// Encode `msg` as one frame with the header fields of `route`, tagged under `key`,
/// at the start of `buf`; returns the frame's length. Never allocates.
pub fn encode(
    route: Route,
    msg: &Message,
    key: &Key,
    buf: &mut [u8],
) -> Result<usize, EncodeError> {
    let payload_len = payload_len(msg)?;
    if payload_len > MAX_PAYLOAD {
        return Err(EncodeError::TooLarge);
    }
    let body = HEADER_LEN + payload_len;
    let total = body + TAG_LEN;
    if buf.len() < total {
        return Err(EncodeError::BufferTooSmall);
    }
    let mut w = Writer {
        buf: &mut buf[..total],
        pos: 0,
    };
    w.bytes(&MAGIC);
    w.u8(VERSION);
    w.u8(msg.msg_type() as u8);
    w.u32(route.session);
    w.u64(route.seq);
    w.u16(route.unit);
    w.u16(payload_len as u16); // <= MAX_PAYLOAD, checked above
    write_payload(msg, &mut w);
    debug_assert_eq!(w.pos, body);
    let tag = key.tag(&w.buf[..body]);
    w.bytes(&tag);
    Ok(total)
}

/// Validate the header of the frame at the start of `buf` (magic, version, declared
/// length against what is there, message type, fixed payload sizes) and return it
/// with the frame's length. The tag is not checked: pick the key by the header, then
/// [`open`] the frame.
pub fn peek(buf: &[u8]) -> Result<(Header, usize), DecodeError> {
    if buf.len() < FRAME_OVERHEAD {
        return Err(
            if buf.len() >= 3 && buf[..2] == MAGIC && buf[2] != VERSION {
                DecodeError::WrongVersion(buf[2])
            } else if buf.len() >= 2 && buf[..2] != MAGIC {
                DecodeError::BadMagic
            } else {
                DecodeError::Truncated
            },
        );
    }
    if buf[0..2] != MAGIC {
        return Err(DecodeError::BadMagic);
    }
    if buf[2] != VERSION {
        return Err(DecodeError::WrongVersion(buf[2]));
    }
    let mut r = Reader {
        buf: &buf[3..HEADER_LEN],
        pos: 0,
    };
    let type_byte = r.u8()?;
    let session = r.u32()?;
    let seq = r.u64()?;
    let unit = r.u16()?;
    let payload_len = r.u16()? as usize;
    if payload_len > MAX_PAYLOAD {
        return Err(DecodeError::BadLength);
    }
    let total = FRAME_OVERHEAD + payload_len;
    if buf.len() < total {
        return Err(DecodeError::Truncated);
    }
    let msg_type = msg_type_from(type_byte).ok_or(DecodeError::UnknownType(type_byte))?;
    if fixed_len(msg_type).is_some_and(|n| n != payload_len) {
        return Err(DecodeError::BadLength);
    }
    let header = Header {
        msg_type,
        session,
        seq,
        unit,
    };
    Ok((header, total))
}

/// Check the tag of `frame` (exactly one frame, as [`peek`] measured it) under `key`,
/// then decode its payload. Allocates only for lookups that list names or MACs.
pub fn open(frame: &[u8], key: &Key) -> Result<Message, DecodeError> {
    let (header, total) = peek(frame)?;
    if frame.len() != total {
        return Err(DecodeError::BadLength);
    }
    let body = total - TAG_LEN;
    if !key.verify(&frame[..body], &frame[body..]) {
        return Err(DecodeError::BadTag);
    }
    decode_payload(header.msg_type, &frame[HEADER_LEN..body])
}

/// Decode a datagram of exactly one frame whose key depends only on the message type
/// (`key_for(header)`): discovery and tests. The loop uses [`Frames`] and [`open`].
pub fn decode(
    buf: &[u8],
    key_for: impl FnOnce(&Header) -> Key,
) -> Result<(Header, Message), DecodeError> {
    let (header, total) = peek(buf)?;
    if buf.len() != total {
        return Err(DecodeError::BadLength);
    }
    let key = key_for(&header);
    Ok((header, open(buf, &key)?))
}

/// The frames of a datagram, in order: each item is a frame's header and bytes, or
/// the error that ends the walk (nothing after a bad header can be framed).
pub struct Frames<'a> {
    rest: &'a [u8],
}

impl<'a> Frames<'a> {
    pub fn new(datagram: &'a [u8]) -> Self {
        Self { rest: datagram }
    }
}

impl<'a> Iterator for Frames<'a> {
    type Item = Result<(Header, &'a [u8]), DecodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() {
            return None;
        }
        match peek(self.rest) {
            Ok((header, total)) => {
                let (frame, rest) = self.rest.split_at(total);
                self.rest = rest;
                Some(Ok((header, frame)))
            }
            Err(e) => {
                self.rest = &[];
                Some(Err(e))
            }
        }
    }
}

fn fixed_len(msg_type: MsgType) -> Option<usize> {
    match msg_type {
        MsgType::Lookup => None,
        MsgType::Announce => Some(ANNOUNCE_LEN),
        MsgType::Acquire => Some(ACQUIRE_LEN),
        MsgType::Release => Some(0),
        MsgType::AcquireReply => Some(ACQUIRE_REPLY_LEN),
        MsgType::Settings | MsgType::SettingsAck => Some(SETTINGS_LEN),
        MsgType::Command => Some(COMMAND_LEN),
        MsgType::Feedback => Some(FEEDBACK_LEN),
    }
}

fn msg_type_from(b: u8) -> Option<MsgType> {
    Some(match b {
        1 => MsgType::Lookup,
        2 => MsgType::Announce,
        3 => MsgType::Acquire,
        4 => MsgType::AcquireReply,
        5 => MsgType::Release,
        6 => MsgType::Settings,
        7 => MsgType::SettingsAck,
        8 => MsgType::Command,
        9 => MsgType::Feedback,
        _ => return None,
    })
}

/// Payload length of `msg`, and a check that it holds only encodable values.
fn payload_len(msg: &Message) -> Result<usize, EncodeError> {
    Ok(match msg {
        Message::Lookup(filter) => {
            LOOKUP_HEAD_LEN
                + match filter {
                    LookupFilter::All => 0,
                    LookupFilter::Family(name) => 1 + name.as_bytes().len(),
                    LookupFilter::Names(names) => {
                        names.iter().map(|n| 1 + n.as_bytes().len()).sum()
                    }
                    LookupFilter::Macs(macs) => macs.len() * MAC_LEN,
                }
        }
        Message::Announce(_) => ANNOUNCE_LEN,
        Message::Acquire(_) => ACQUIRE_LEN,
        Message::Release => 0,
        Message::AcquireReply(_) => ACQUIRE_REPLY_LEN,
        Message::Settings(s) | Message::SettingsAck(s) => {
            if !(s.feedback_rate_hz.is_finite() && s.command_lifetime_s.is_finite()) {
                return Err(EncodeError::Invalid("settings not finite"));
            }
            SETTINGS_LEN
        }
        Message::Command(c) => {
            if [c.position_rad, c.velocity_rad_s, c.torque_nm]
                .iter()
                .any(|v| v.is_infinite())
            {
                return Err(EncodeError::Invalid("infinite set-point"));
            }
            COMMAND_LEN
        }
        Message::Feedback(_) => FEEDBACK_LEN,
    })
}

fn write_payload(msg: &Message, w: &mut Writer<'_>) {
    match msg {
        Message::Lookup(filter) => {
            let (kind, count) = match filter {
                LookupFilter::All => (FILTER_ALL, 0),
                LookupFilter::Family(_) => (FILTER_FAMILY, 1),
                LookupFilter::Names(names) => (FILTER_NAMES, names.len()),
                LookupFilter::Macs(macs) => (FILTER_MACS, macs.len()),
            };
            w.u8(kind);
            w.u8(0);
            w.u16(count as u16); // the payload limit keeps count far below u16::MAX
            match filter {
                LookupFilter::All => {}
                LookupFilter::Family(name) => w.short_name(name),
                LookupFilter::Names(names) => names.iter().for_each(|n| w.short_name(n)),
                LookupFilter::Macs(macs) => macs.iter().for_each(|m| w.bytes(m)),
            }
        }
        Message::Announce(a) => {
            w.bytes(&a.mac);
            w.u8(if a.owned { OWNED } else { 0 });
            w.u8(0);
            w.u32(a.firmware);
            w.u8(a.family.as_bytes().len() as u8);
            w.u8(a.name.as_bytes().len() as u8);
            w.padded_name(&a.family);
            w.padded_name(&a.name);
        }
        Message::Acquire(nonce) => w.bytes(nonce),
        Message::Release => {}
        Message::AcquireReply(r) => {
            w.u8(r.granted as u8);
            w.bytes(&[0; 3]);
            w.bytes(&r.module_nonce);
        }
        Message::Settings(s) | Message::SettingsAck(s) => {
            w.f32(s.feedback_rate_hz);
            w.f32(s.command_lifetime_s);
            w.u8(s.strategy as u8);
            w.bytes(&[0; 3]);
        }
        Message::Command(c) => {
            w.f32(c.position_rad);
            w.f32(c.velocity_rad_s);
            w.f32(c.torque_nm);
        }
        Message::Feedback(f) => {
            w.u64(f.module_time_us);
            w.u64(f.last_command_seq);
            for v in [
                f.position_rad,
                f.velocity_rad_s,
                f.torque_nm,
                f.deflection_rad,
            ] {
                w.f32(v);
            }
            f.accel_m_s2
                .iter()
                .chain(&f.gyro_rad_s)
                .for_each(|&v| w.f32(v));
            w.f32(f.temperature_c);
            w.f32(f.voltage_v);
        }
    }
}

fn decode_payload(msg_type: MsgType, p: &[u8]) -> Result<Message, DecodeError> {
    if fixed_len(msg_type).is_some_and(|n| n != p.len()) {
        return Err(DecodeError::BadLength);
    }
    let mut r = Reader { buf: p, pos: 0 };
    let msg = match msg_type {
        MsgType::Lookup => Message::Lookup(decode_lookup(&mut r)?),
        MsgType::Announce => {
            let mac: Mac = r.array()?;
            let owned = match r.u8()? {
                0 => false,
                OWNED => true,
                _ => return Err(DecodeError::Malformed("unknown announce flags")),
            };
            r.zero(1)?;
            let firmware = r.u32()?;
            let family_len = r.u8()?;
            let name_len = r.u8()?;
            let family = r.padded_name(family_len)?;
            let name = r.padded_name(name_len)?;
            Message::Announce(Announce {
                mac,
                family,
                name,
                firmware,
                owned,
            })
        }
        MsgType::Acquire => Message::Acquire(r.array()?),
        MsgType::Release => Message::Release,
        MsgType::AcquireReply => {
            let granted = match r.u8()? {
                0 => false,
                1 => true,
                _ => return Err(DecodeError::Malformed("granted flag not 0 or 1")),
            };
            r.zero(3)?;
            let module_nonce = r.array()?;
            Message::AcquireReply(AcquireReply {
                granted,
                module_nonce,
            })
        }
        MsgType::Settings | MsgType::SettingsAck => {
            let feedback_rate_hz = r.f32()?;
            let command_lifetime_s = r.f32()?;
            let strategy = match r.u8()? {
                0 => ControlStrategy::Off,
                1 => ControlStrategy::Cascaded,
                _ => return Err(DecodeError::Malformed("unknown control strategy")),
            };
            r.zero(3)?;
            if !(feedback_rate_hz.is_finite() && command_lifetime_s.is_finite()) {
                return Err(DecodeError::Malformed("settings not finite"));
            }
            let s = Settings {
                feedback_rate_hz,
                command_lifetime_s,
                strategy,
            };
            if msg_type == MsgType::Settings {
                Message::Settings(s)
            } else {
                Message::SettingsAck(s)
            }
        }
        MsgType::Command => {
            let c = Command {
                position_rad: r.f32()?,
                velocity_rad_s: r.f32()?,
                torque_nm: r.f32()?,
            };
            if [c.position_rad, c.velocity_rad_s, c.torque_nm]
                .iter()
                .any(|v| v.is_infinite())
            {
                return Err(DecodeError::Malformed("infinite set-point"));
            }
            Message::Command(c)
        }
        MsgType::Feedback => {
            let module_time_us = r.u64()?;
            let last_command_seq = r.u64()?;
            let [position_rad, velocity_rad_s, torque_nm, deflection_rad] = r.f32s()?;
            let accel_m_s2 = r.f32s()?;
            let gyro_rad_s = r.f32s()?;
            let [temperature_c, voltage_v] = r.f32s()?;
            Message::Feedback(Feedback {
                module_time_us,
                last_command_seq,
                position_rad,
                velocity_rad_s,
                torque_nm,
                deflection_rad,
                accel_m_s2,
                gyro_rad_s,
                temperature_c,
                voltage_v,
            })
        }
    };
    if r.pos != p.len() {
        return Err(DecodeError::Malformed("trailing bytes after the payload"));
    }
    Ok(msg)
}

fn decode_lookup(r: &mut Reader<'_>) -> Result<LookupFilter, DecodeError> {
    if r.remaining() < LOOKUP_HEAD_LEN {
        return Err(DecodeError::Malformed(
            "lookup shorter than its filter header",
        ));
    }
    let kind = r.u8()?;
    r.zero(1)?;
    let count = r.u16()? as usize;
    let filter = match kind {
        FILTER_ALL if count == 0 => LookupFilter::All,
        FILTER_FAMILY if count == 1 => LookupFilter::Family(r.short_name()?),
        FILTER_ALL | FILTER_FAMILY => {
            return Err(DecodeError::Malformed(
                "lookup count does not fit the filter kind",
            ));
        }
        FILTER_NAMES => {
            // Every entry takes at least its length byte: bound the allocation first.
            if count > r.remaining() {
                return Err(DecodeError::Malformed("list count exceeds the payload"));
            }
            let mut names = Vec::with_capacity(count);
            for _ in 0..count {
                names.push(r.short_name()?);
            }
            LookupFilter::Names(names)
        }
        FILTER_MACS => {
            if count * MAC_LEN > r.remaining() {
                return Err(DecodeError::Malformed("list count exceeds the payload"));
            }
            let mut macs = Vec::with_capacity(count);
            for _ in 0..count {
                macs.push(r.array()?);
            }
            LookupFilter::Macs(macs)
        }
        _ => return Err(DecodeError::Malformed("unknown lookup filter kind")),
    };
    Ok(filter)
}

/// The full suite (round trips, every error, corruption) is `tests/integration/protocol/codec.rs`.
#[cfg(test)]
#[path = "codec_tests.rs"]
mod tests;
