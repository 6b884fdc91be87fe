//! Receive-side bookkeeping of the bus: per-module newest feedback, sequence gaps,
//! counting of rejected datagrams. Pure logic, no I/O.
use super::clock::ModuleClock;
use super::counters::UdpCounters;
use crate::module::Feedback;

/// Newest feedback of one module.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Slot {
    pub newest: Feedback,
    /// Header seq of `newest`; 0 before the first feedback (modules start at 1).
    pub last_seq: u64,
    /// Arrived since it was last handed to the loop.
    pub pending: bool,
    /// When `newest` arrived, ns on the loop's clock (`None`: before the loop's clock
    /// was known, during connect).
    pub rx_ns: Option<u64>,
    /// How late `newest` was on arrival by the module's clock (`None`: not measured).
    pub clock_age_ns: Option<u64>,
    pub clock: ModuleClock,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SeqVerdict {
    /// Newer than what we have; `lost` datagrams were skipped.
    Accept { lost: u64 },
    /// A duplicate, a replay or an older datagram that arrived late.
    Stale,
}

/// Judge the seq of an authenticated feedback against the newest seen (`last`, 0 for
/// none). Seqs never wrap (u64) and only the module can tag its feedback, so "newer"
/// is plain `>`: a replay is never newer, and nothing forged gets this far to push the
/// newest ahead (`docs/protocol.md` §5). A restarted module has lost its session key;
/// it must be acquired again.
pub(super) fn judge_seq(last: u64, seq: u64) -> SeqVerdict {
    if seq > last {
        SeqVerdict::Accept {
            lost: seq - last - 1,
        }
    } else {
        SeqVerdict::Stale
    }
}

impl Slot {
    /// Take `fb` if it is newer than what the slot holds; returns whether it did.
    /// `rx_ns` is its arrival on the loop's clock; `on_clock` says that clock runs in
    /// real time, so the module's clock can be compared with it.
    pub(super) fn offer(
        &mut self,
        seq: u64,
        fb: Feedback,
        rx_ns: Option<u64>,
        on_clock: bool,
        counters: &mut UdpCounters,
    ) -> bool {
        match judge_seq(self.last_seq, seq) {
            SeqVerdict::Stale => {
                counters.feedback_replayed += 1;
                false
            }
            SeqVerdict::Accept { lost } => {
                // The first feedback of a session says nothing about loss before it.
                if self.last_seq > 0 {
                    counters.feedback_lost += lost;
                }
                counters.feedback_received += 1;
                self.newest = fb;
                self.last_seq = seq;
                self.rx_ns = rx_ns;
                self.clock_age_ns = match rx_ns {
                    Some(rx) if on_clock => Some(self.clock.observe(rx, fb.module_time_us)),
                    _ => None,
                };
                self.pending = true;
                true
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seq_gaps_duplicates_and_replays() {
        use SeqVerdict::*;
        assert_eq!(judge_seq(0, 77), Accept { lost: 76 });
        assert_eq!(judge_seq(5, 6), Accept { lost: 0 });
        assert_eq!(judge_seq(5, 9), Accept { lost: 3 });
        assert_eq!(judge_seq(5, 5), Stale);
        assert_eq!(judge_seq(5, 3), Stale);
        // No wrap, no "restart": far behind is a replay.
        assert_eq!(judge_seq(100_000, 0), Stale);
        assert_eq!(judge_seq(u64::from(u32::MAX), 1 << 32), Accept { lost: 0 });
    }

    #[test]
    fn slot_keeps_newest_and_counts() {
        let mut c = UdpCounters::default();
        let mut s = Slot::default();
        let fb = |t| Feedback {
            module_time_us: t,
            ..Feedback::default()
        };
        assert!(s.offer(10, fb(1), None, false, &mut c));
        assert!(s.offer(13, fb(4), Some(7), false, &mut c));
        assert!(!s.offer(12, fb(3), Some(8), false, &mut c));
        assert!(!s.offer(13, fb(4), Some(9), false, &mut c));
        assert_eq!(s.rx_ns, Some(7));
        assert_eq!(s.newest.module_time_us, 4);
        assert_eq!(
            (c.feedback_received, c.feedback_lost, c.feedback_replayed),
            (2, 2, 2)
        );
    }
}
