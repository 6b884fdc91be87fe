//! Receive-side bookkeeping of the bus: per-module newest feedback, sequence gaps,
//! counting of rejected datagrams. Pure logic, no I/O.
use crate::bus::BusCounters;
use crate::protocol::{DecodeError, Feedback};

/// A feedback seq this far behind the newest is taken as a module restart (accepted)
/// rather than as a late duplicate (dropped).
const RESTART_BACKWARD_JUMP: u32 = 1024;

/// Newest feedback of one module.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Slot {
    pub newest: Feedback,
    /// Header seq of `newest`; `None` before the first feedback.
    pub last_seq: Option<u32>,
    /// Arrived since it was last handed to the loop.
    pub pending: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SeqVerdict {
    /// Newer than what we have; `lost` datagrams were skipped.
    Accept { lost: u32 },
    /// A duplicate or an older datagram that arrived late.
    Stale,
}

/// Judge feedback seq `seq` against the newest seen (`last`), modulo 2³².
pub(super) fn judge_seq(last: Option<u32>, seq: u32) -> SeqVerdict {
    let Some(last) = last else {
        return SeqVerdict::Accept { lost: 0 };
    };
    let forward = seq.wrapping_sub(last);
    if forward == 0 {
        SeqVerdict::Stale
    } else if forward < 1 << 31 {
        SeqVerdict::Accept { lost: forward - 1 }
    } else if last.wrapping_sub(seq) <= RESTART_BACKWARD_JUMP {
        SeqVerdict::Stale
    } else {
        SeqVerdict::Accept { lost: 0 }
    }
}

impl Slot {
    /// Take `fb` if it is newer than what the slot holds; returns whether it did.
    pub(super) fn offer(&mut self, seq: u32, fb: Feedback, counters: &mut BusCounters) -> bool {
        match judge_seq(self.last_seq, seq) {
            SeqVerdict::Stale => false,
            SeqVerdict::Accept { lost } => {
                counters.feedback_lost += u64::from(lost);
                counters.feedback_received += 1;
                self.newest = fb;
                self.last_seq = Some(seq);
                self.pending = true;
                true
            }
        }
    }
}

/// Count a rejected datagram under its reason.
pub(super) fn count_decode_error(c: &mut BusCounters, e: DecodeError) {
    let counter = match e {
        DecodeError::Truncated => &mut c.bad_truncated,
        DecodeError::BadMagic => &mut c.bad_magic,
        DecodeError::WrongVersion(_) => &mut c.bad_version,
        DecodeError::UnknownType(_) => &mut c.bad_type,
        DecodeError::BadLength => &mut c.bad_length,
        DecodeError::BadChecksum => &mut c.bad_checksum,
        DecodeError::Malformed(_) => &mut c.bad_malformed,
    };
    *counter += 1;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seq_gaps_duplicates_wrap_and_restart() {
        use SeqVerdict::*;
        assert_eq!(judge_seq(None, 77), Accept { lost: 0 });
        assert_eq!(judge_seq(Some(5), 6), Accept { lost: 0 });
        assert_eq!(judge_seq(Some(5), 9), Accept { lost: 3 });
        assert_eq!(judge_seq(Some(5), 5), Stale);
        assert_eq!(judge_seq(Some(5), 3), Stale);
        assert_eq!(judge_seq(Some(u32::MAX), 0), Accept { lost: 0 });
        assert_eq!(judge_seq(Some(u32::MAX - 1), 1), Accept { lost: 2 });
        assert_eq!(judge_seq(Some(1), u32::MAX), Stale);
        assert_eq!(judge_seq(Some(100_000), 0), Accept { lost: 0 });
    }

    #[test]
    fn slot_keeps_newest_and_counts() {
        let mut c = BusCounters::default();
        let mut s = Slot::default();
        let fb = |t| Feedback {
            module_time_us: t,
            ..Feedback::default()
        };
        assert!(s.offer(10, fb(1), &mut c));
        assert!(s.offer(13, fb(4), &mut c));
        assert!(!s.offer(12, fb(3), &mut c));
        assert!(!s.offer(13, fb(4), &mut c));
        assert_eq!(s.newest.module_time_us, 4);
        assert_eq!((c.feedback_received, c.feedback_lost), (2, 2));
    }

    #[test]
    fn every_decode_error_has_a_counter() {
        let mut c = BusCounters::default();
        for e in [
            DecodeError::Truncated,
            DecodeError::BadMagic,
            DecodeError::WrongVersion(2),
            DecodeError::UnknownType(0),
            DecodeError::BadLength,
            DecodeError::BadChecksum,
            DecodeError::Malformed("x"),
        ] {
            count_decode_error(&mut c, e);
        }
        let all = [
            c.bad_truncated,
            c.bad_magic,
            c.bad_version,
            c.bad_type,
            c.bad_length,
            c.bad_checksum,
            c.bad_malformed,
        ];
        assert_eq!(all, [1; 7]);
    }
}
