//! Encoding and decoding of protocol v1 datagrams. Byte layouts: `docs/protocol.md`.
//!
//! `datagram = header (16 B) | payload | crc32 (4 B)`, little endian. The encoding is
//! canonical: every datagram `decode` accepts re-encodes to the same bytes (reserved
//! bytes and name padding must be zero), so a corrupted datagram can never pass as a
//! different valid one without also matching the checksum.
use super::{
    AcquireReply, Announce, Command, ControlStrategy, Feedback, Header, LookupFilter, MAGIC, Mac,
    Message, MsgType, NAME_CAPACITY, Name, Settings, VERSION,
};

/// Largest datagram this protocol produces or accepts, bytes.
pub const MAX_DATAGRAM: usize = 1400;

const HEADER_LEN: usize = 16;
const CRC_LEN: usize = 4;
const MAX_PAYLOAD: usize = MAX_DATAGRAM - HEADER_LEN - CRC_LEN;

// Payload sizes of the fixed-size messages, bytes.
const ANNOUNCE_LEN: usize = 82;
const ACQUIRE_REPLY_LEN: usize = 8;
const SETTINGS_LEN: usize = 12;
const COMMAND_LEN: usize = 12;
const FEEDBACK_LEN: usize = 60;
/// Lookup payload before its entries: kind u8, reserved u8, count u16.
const LOOKUP_HEAD_LEN: usize = 4;
const MAC_LEN: usize = 6;

// Lookup filter kinds on the wire.
const FILTER_ALL: u8 = 0;
const FILTER_FAMILY: u8 = 1;
const FILTER_NAMES: u8 = 2;
const FILTER_MACS: u8 = 3;

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

/// Why a datagram was rejected. Receivers count these per kind and drop the datagram.
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
    #[error("checksum mismatch")]
    BadChecksum,
    #[error("malformed payload: {0}")]
    Malformed(&'static str),
}

/// Encode `msg` with the given session and sequence number into `buf`; returns the
/// datagram length. Never allocates.
pub fn encode(session: u32, seq: u32, msg: &Message, buf: &mut [u8]) -> Result<usize, EncodeError> {
    let payload_len = payload_len(msg)?;
    if payload_len > MAX_PAYLOAD {
        return Err(EncodeError::TooLarge);
    }
    let total = HEADER_LEN + payload_len + CRC_LEN;
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
    w.u32(session);
    w.u32(seq);
    w.u16(payload_len as u16); // <= MAX_PAYLOAD, checked above
    w.u16(0);
    write_payload(msg, &mut w);
    debug_assert_eq!(w.pos, HEADER_LEN + payload_len);
    let crc = crc32fast::hash(&w.buf[..HEADER_LEN + payload_len]);
    w.u32(crc);
    Ok(total)
}

/// Decode and validate one datagram. Allocates only for lookups that list names or MACs.
///
/// Checks in order: length of header and trailer, magic, version, declared payload
/// length against the datagram, checksum, reserved header field, message type, payload.
pub fn decode(buf: &[u8]) -> Result<(Header, Message), DecodeError> {
    if buf.len() < HEADER_LEN + CRC_LEN {
        return Err(DecodeError::Truncated);
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
    let seq = r.u32()?;
    let payload_len = r.u16()? as usize;
    let reserved = r.u16()?;
    if payload_len > MAX_PAYLOAD {
        return Err(DecodeError::BadLength);
    }
    let total = HEADER_LEN + payload_len + CRC_LEN;
    if buf.len() < total {
        return Err(DecodeError::Truncated);
    }
    if buf.len() > total {
        return Err(DecodeError::BadLength);
    }
    let body = &buf[..HEADER_LEN + payload_len];
    let crc = u32::from_le_bytes(buf[total - CRC_LEN..].try_into().expect("4-byte trailer"));
    if crc32fast::hash(body) != crc {
        return Err(DecodeError::BadChecksum);
    }
    if reserved != 0 {
        return Err(DecodeError::Malformed("reserved header field not zero"));
    }
    let msg_type = msg_type_from(type_byte).ok_or(DecodeError::UnknownType(type_byte))?;
    let payload = &body[HEADER_LEN..];
    let msg = decode_payload(msg_type, payload)?;
    Ok((
        Header {
            msg_type,
            session,
            seq,
        },
        msg,
    ))
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
        Message::Acquire | Message::Release => 0,
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
            w.u16(0);
            w.u32(a.firmware);
            w.u32(a.owner_session);
            w.u8(a.family.as_bytes().len() as u8);
            w.u8(a.name.as_bytes().len() as u8);
            w.padded_name(&a.family);
            w.padded_name(&a.name);
        }
        Message::Acquire | Message::Release => {}
        Message::AcquireReply(r) => {
            w.u8(r.granted as u8);
            w.bytes(&[0; 3]);
            w.u32(r.owner_session);
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
            w.u32(f.last_command_seq);
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
    let fixed_len = match msg_type {
        MsgType::Lookup => None,
        MsgType::Announce => Some(ANNOUNCE_LEN),
        MsgType::Acquire | MsgType::Release => Some(0),
        MsgType::AcquireReply => Some(ACQUIRE_REPLY_LEN),
        MsgType::Settings | MsgType::SettingsAck => Some(SETTINGS_LEN),
        MsgType::Command => Some(COMMAND_LEN),
        MsgType::Feedback => Some(FEEDBACK_LEN),
    };
    if fixed_len.is_some_and(|n| n != p.len()) {
        return Err(DecodeError::BadLength);
    }
    let mut r = Reader { buf: p, pos: 0 };
    let msg = match msg_type {
        MsgType::Lookup => Message::Lookup(decode_lookup(&mut r)?),
        MsgType::Announce => {
            let mac: Mac = r.array()?;
            r.zero(2)?;
            let firmware = r.u32()?;
            let owner_session = r.u32()?;
            let family_len = r.u8()?;
            let name_len = r.u8()?;
            let family = r.padded_name(family_len)?;
            let name = r.padded_name(name_len)?;
            Message::Announce(Announce {
                mac,
                family,
                name,
                firmware,
                owner_session,
            })
        }
        MsgType::Acquire => Message::Acquire,
        MsgType::Release => Message::Release,
        MsgType::AcquireReply => {
            let granted = match r.u8()? {
                0 => false,
                1 => true,
                _ => return Err(DecodeError::Malformed("granted flag not 0 or 1")),
            };
            r.zero(3)?;
            let owner_session = r.u32()?;
            Message::AcquireReply(AcquireReply {
                granted,
                owner_session,
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
            let last_command_seq = r.u32()?;
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

/// Writes into a buffer whose size `encode` has already checked.
struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        self.buf[self.pos..self.pos + b.len()].copy_from_slice(b);
        self.pos += b.len();
    }
    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    /// Bit-exact, so NaN payloads survive.
    fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    /// Length byte, then the bytes.
    fn short_name(&mut self, n: &Name) {
        self.u8(n.as_bytes().len() as u8);
        self.bytes(n.as_bytes());
    }
    /// `NAME_CAPACITY` bytes, zero padded (the length travels separately).
    fn padded_name(&mut self, n: &Name) {
        let b = n.as_bytes();
        self.bytes(b);
        self.bytes(&[0; NAME_CAPACITY][b.len()..]);
    }
}

/// Reads a payload; running out of bytes is a malformed payload.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], DecodeError> {
        if n > self.remaining() {
            return Err(DecodeError::Malformed("payload ends inside a field"));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        Ok(self.take(N)?.try_into().expect("take returns N bytes"))
    }
    fn u8(&mut self) -> Result<u8, DecodeError> {
        Ok(self.take(1)?[0])
    }
    fn u16(&mut self) -> Result<u16, DecodeError> {
        self.array().map(u16::from_le_bytes)
    }
    fn u32(&mut self) -> Result<u32, DecodeError> {
        self.array().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Result<u64, DecodeError> {
        self.array().map(u64::from_le_bytes)
    }
    fn f32(&mut self) -> Result<f32, DecodeError> {
        self.u32().map(f32::from_bits)
    }
    fn f32s<const N: usize>(&mut self) -> Result<[f32; N], DecodeError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f32()?;
        }
        Ok(out)
    }
    fn zero(&mut self, n: usize) -> Result<(), DecodeError> {
        if self.take(n)?.iter().any(|&b| b != 0) {
            return Err(DecodeError::Malformed("reserved bytes not zero"));
        }
        Ok(())
    }
    fn name(bytes: &[u8]) -> Result<Name, DecodeError> {
        let s = std::str::from_utf8(bytes).map_err(|_| DecodeError::Malformed("name not UTF-8"))?;
        Name::new(s).map_err(|_| DecodeError::Malformed("name too long"))
    }
    fn short_name(&mut self) -> Result<Name, DecodeError> {
        let len = self.u8()? as usize;
        if len > NAME_CAPACITY {
            return Err(DecodeError::Malformed("name too long"));
        }
        Self::name(self.take(len)?)
    }
    fn padded_name(&mut self, len: u8) -> Result<Name, DecodeError> {
        let field = self.take(NAME_CAPACITY)?;
        let len = len as usize;
        if len > NAME_CAPACITY {
            return Err(DecodeError::Malformed("name too long"));
        }
        if field[len..].iter().any(|&b| b != 0) {
            return Err(DecodeError::Malformed("name padding not zero"));
        }
        Self::name(&field[..len])
    }
}

/// The full suite (round trips, every error, corruption) is `tests/protocol_codec.rs`.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_fields_sit_at_their_offsets() {
        let mut buf = [0u8; MAX_DATAGRAM];
        let fb = Message::Feedback(Feedback::default());
        let n = encode(0x0102_0304, 0x0a0b_0c0d, &fb, &mut buf).unwrap();
        assert_eq!(n, HEADER_LEN + FEEDBACK_LEN + CRC_LEN);
        assert_eq!(&buf[..4], b"SN\x01\x09");
        assert_eq!(&buf[4..8], &[4, 3, 2, 1]);
        assert_eq!(&buf[8..12], &[0x0d, 0x0c, 0x0b, 0x0a]);
        assert_eq!(&buf[12..16], &[FEEDBACK_LEN as u8, 0, 0, 0]);
        let crc = crc32fast::hash(&buf[..n - CRC_LEN]);
        assert_eq!(&buf[n - CRC_LEN..n], &crc.to_le_bytes());
        let (h, back) = decode(&buf[..n]).unwrap();
        assert_eq!((h.session, h.seq, back), (0x0102_0304, 0x0a0b_0c0d, fb));
    }

    #[test]
    fn checksum_covers_every_byte() {
        let mut buf = [0u8; MAX_DATAGRAM];
        let n = encode(1, 2, &Message::Command(Command::position(0.3)), &mut buf).unwrap();
        for i in 16..n {
            let mut d = buf;
            d[i] ^= 0x80;
            assert_eq!(decode(&d[..n]), Err(DecodeError::BadChecksum), "byte {i}");
        }
    }
}
