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
    /// Where operator actions from ROS 2 are recorded (`/operator`).
    pub(super) actions: Arc<OnceLock<Actions>>,
    pub(super) _node: NodeThread,
}

impl crate::record::CycleSink for Sink {
    fn cycle(&mut self, rec: &CycleRecord, unix_ns: u64) {
        if rec.t_ns < self.next_ns {
            return;
        }
        // The next one due a period on, without drifting back after a gap.
        self.next_ns = (self.next_ns + self.period_ns).max(rec.t_ns + self.period_ns / 2);
        let frame = Box::new(Frame { rec: *rec, unix_ns });
        if self.tx.try_send(frame).is_err() {
            self.counters.dropped.fetch_add(1, Relaxed);
        }
    }

    fn attach(&mut self, ctx: &Arc<foxglove::Context>) {
        let _ = self.actions.set(Actions::new(ctx));
    }
}
