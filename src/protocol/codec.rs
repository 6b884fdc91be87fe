//! Encoding and decoding of protocol v1 datagrams. TO BE IMPLEMENTED (helper: protocol).
use super::{Header, Message};

/// Largest datagram this protocol produces or accepts, bytes.
pub const MAX_DATAGRAM: usize = 1400;

#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    #[error("buffer too small for the message")]
    BufferTooSmall,
    #[error("message too large for one datagram")]
    TooLarge,
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
    let _ = (session, seq, msg, buf);
    todo!("protocol helper")
}

/// Decode and validate one datagram. Allocates only for lookups that list names or MACs.
pub fn decode(buf: &[u8]) -> Result<(Header, Message), DecodeError> {
    let _ = buf;
    todo!("protocol helper")
}
