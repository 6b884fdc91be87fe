//! What the UDP bus counts: the common counters and, as its own detail, why it
//! dropped datagrams (protocol v2's decode errors, sessions, strangers).

use super::super::{BusCounters, CounterSet};
use crate::protocol::{DecodeError, VERSION_1};

/// The UDP bus's counters; monotonically increasing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UdpCounters {
    pub feedback_received: u64,
    pub feedback_lost: u64,
    /// Authenticated feedback not newer than the newest held (replayed or reordered).
    pub feedback_replayed: u64,
    pub commands_sent: u64,
    pub send_errors: u64,
    /// Datagrams dropped, by reason.
    pub bad_truncated: u64,
    pub bad_magic: u64,
    pub bad_version: u64,
    /// Datagrams of protocol v1 (an old module or emulator): refused.
    pub v1_refused: u64,
    pub bad_type: u64,
    pub bad_length: u64,
    /// Frames whose tag did not verify: corrupted, forged, or of another session.
    pub bad_tag: u64,
    pub bad_malformed: u64,
    pub wrong_session: u64,
    /// Well-formed datagrams from an address that is not in the group, or of a type
    /// the loop does not expect.
    pub unexpected: u64,
}

/// The detail's names, in the order of [`UdpCounters::dropped`].
const DETAIL: &[&str] = &[
    "bad_truncated",
    "bad_magic",
    "bad_version",
    "v1_refused",
    "bad_type",
    "bad_length",
    "bad_tag",
    "bad_malformed",
    "wrong_session",
    "unexpected",
];

impl UdpCounters {
    /// Dropped datagrams by reason, in the order of `DETAIL`.
    fn dropped(&self) -> [u64; 10] {
        [
            self.bad_truncated,
            self.bad_magic,
            self.bad_version,
            self.v1_refused,
            self.bad_type,
            self.bad_length,
            self.bad_tag,
            self.bad_malformed,
            self.wrong_session,
            self.unexpected,
        ]
    }

    /// As every bus reports them.
    pub fn to_bus(&self) -> BusCounters {
        let dropped = self.dropped();
        let mut detail = CounterSet::new(DETAIL);
        for (i, &n) in dropped.iter().enumerate() {
            detail.set(i, n);
        }
        BusCounters {
            feedback_received: self.feedback_received,
            feedback_lost: self.feedback_lost,
            feedback_replayed: self.feedback_replayed,
            commands_sent: self.commands_sent,
            send_errors: self.send_errors,
            dropped: dropped.iter().sum(),
            detail,
        }
    }

    /// Count a rejected datagram under its reason.
    pub fn count_decode_error(&mut self, e: DecodeError) {
        let counter = match e {
            DecodeError::Truncated => &mut self.bad_truncated,
            DecodeError::BadMagic => &mut self.bad_magic,
            DecodeError::WrongVersion(VERSION_1) => &mut self.v1_refused,
            DecodeError::WrongVersion(_) => &mut self.bad_version,
            DecodeError::UnknownType(_) => &mut self.bad_type,
            DecodeError::BadLength => &mut self.bad_length,
            DecodeError::BadTag => &mut self.bad_tag,
            DecodeError::Malformed(_) => &mut self.bad_malformed,
        };
        *counter += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_decode_error_has_a_counter_and_the_detail_names_each() {
        let mut c = UdpCounters::default();
        for e in [
            DecodeError::Truncated,
            DecodeError::BadMagic,
            DecodeError::WrongVersion(3),
            DecodeError::WrongVersion(1),
            DecodeError::UnknownType(0),
            DecodeError::BadLength,
            DecodeError::BadTag,
            DecodeError::Malformed("x"),
        ] {
            c.count_decode_error(e);
        }
        c.unexpected += 2;
        let bus = c.to_bus();
        assert_eq!(bus.dropped, 10);
        for name in &DETAIL[..8] {
            assert_eq!(bus.detail.get(name), Some(1), "{name}");
        }
        assert_eq!(bus.detail.get("wrong_session"), Some(0));
        assert_eq!(bus.detail.get("unexpected"), Some(2));
    }
}
