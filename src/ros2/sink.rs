//! The recorder writer's end of the node: it offers each recorded cycle, keeps one in
//! every `1 / rate` and hands it over a bounded channel without waiting (a full
//! channel drops it, counted). Neither the loop nor the writer ever waits on DDS.

use std::sync::atomic::Ordering::Relaxed;
use std::sync::{Arc, OnceLock};

use super::node::{BridgeCounters, NodeThread};
use crate::record::cycle::CycleRecord;
use crate::station::actions::Actions;

/// One recorded cycle and its wall-clock stamp, ns since the Unix epoch.
pub struct Frame {
    pub rec: CycleRecord,
    pub unix_ns: u64,
}

/// Dropping it (the recorder finishing) closes the channel, then ends and joins the
/// node's thread.
pub struct Sink {
    // Dropped before `node`: the closed channel is what ends the node's thread.
    pub(super) tx: crossbeam_channel::Sender<Box<Frame>>,
    pub(super) period_ns: u64,
    pub(super) next_ns: u64,
    pub(super) counters: Arc<BridgeCounters>,
    pub(super) stamps: Stamper,
    /// Where operator actions from ROS 2 are recorded (`/operator`).
    pub(super) actions: Arc<OnceLock<Actions>>,
    pub(super) _node: NodeThread,
}

/// The frames' stamps. The writer's run behind the wall clock by how long the loop took
/// to start after the recorder opened (its clock's anchor; 20 ms with locked memory):
/// the least lag seen so far is added, so ROS 2 gets stamps of when a cycle was read.
#[derive(Debug, Default)]
pub struct Stamper {
    lag_ns: Option<u64>,
    last_ns: u64,
}

impl Stamper {
    /// The stamp of a cycle the writer stamped `writer_ns`, offered at `now_ns`.
    pub fn stamp(&mut self, writer_ns: u64, now_ns: u64) -> u64 {
        let lag = now_ns.saturating_sub(writer_ns);
        let lag = *self.lag_ns.insert(self.lag_ns.map_or(lag, |l| l.min(lag)));
        // Never back in time while the least lag settles.
        self.last_ns = (writer_ns + lag).max(self.last_ns + 1);
        self.last_ns
    }
}

impl crate::record::CycleSink for Sink {
    fn cycle(&mut self, rec: &CycleRecord, unix_ns: u64) {
        if rec.t_ns < self.next_ns {
            return;
        }
        // The next one due a period on, without drifting back after a gap.
        self.next_ns = (self.next_ns + self.period_ns).max(rec.t_ns + self.period_ns / 2);
        let frame = Box::new(Frame {
            rec: *rec,
            unix_ns: self.stamps.stamp(unix_ns, super::node::unix_ns()),
        });
        if self.tx.try_send(frame).is_err() {
            self.counters.dropped.fetch_add(1, Relaxed);
        }
    }

    fn attach(&mut self, ctx: &Arc<foxglove::Context>) {
        let _ = self.actions.set(Actions::new(ctx));
    }
}

#[cfg(test)]
mod tests {
    use super::Stamper;

    #[test]
    fn stamps_take_the_least_lag_and_never_go_back() {
        let mut s = Stamper::default();
        // The writer's clock 20 ms behind; the first cycle offered 1 ms late.
        assert_eq!(s.stamp(1_000_000_000, 1_021_000_000), 1_021_000_000);
        // A later one offered at once: the lag is 20 ms from now on, never back in time.
        assert_eq!(s.stamp(1_001_000_000, 1_021_000_000), 1_021_000_001);
        assert_eq!(s.stamp(1_010_000_000, 1_035_000_000), 1_030_000_000);
    }
}
