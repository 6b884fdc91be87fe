//! Where group feedback waits for the loop: the library's thread (or the fake's)
//! writes each whole group feedback into a triple buffer, in body order; the loop takes
//! the newest without waiting or locking. What the writer counts is atomic.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use super::message::Sample;

/// CLOCK_MONOTONIC, ns: the loop's pacer's clock (`rt::sys::monotonic_ns`, which the
/// bus cannot use without depending on `rt`).
pub fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid timespec; CLOCK_MONOTONIC always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// One whole group feedback, head first.
#[derive(Debug, Clone, Default)]
pub struct GroupSample {
    /// How many group feedbacks the writer has published, this one included.
    pub number: u64,
    /// When it arrived, CLOCK_MONOTONIC ns (the bus maps it to the loop's clock).
    pub arrival_ns: u64,
    pub modules: Vec<Sample>,
}

/// What the writer counts.
#[derive(Debug, Default)]
pub struct WriterCounters {
    pub group_feedbacks: AtomicU64,
    /// Group feedbacks replaced by a newer one before the loop took them.
    pub superseded: AtomicU64,
    /// Modules absent from a group feedback (did not answer in time).
    pub absent: AtomicU64,
}

/// The writing end, owned by whoever produces feedback.
pub struct FeedbackWriter {
    input: triple_buffer::Input<GroupSample>,
    /// Body position `i` is the group's module `order[i]`.
    order: Vec<usize>,
    counters: Arc<WriterCounters>,
    number: u64,
}

/// A mailbox for `order.len()` modules: its writer and its reader.
pub fn mailbox(order: Vec<usize>) -> (FeedbackWriter, triple_buffer::Output<GroupSample>) {
    let empty = GroupSample {
        number: 0,
        arrival_ns: 0,
        modules: vec![Sample::default(); order.len()],
    };
    let (input, output) = triple_buffer::triple_buffer(&empty);
    let writer = FeedbackWriter {
        input,
        order,
        counters: Arc::new(WriterCounters::default()),
        number: 0,
    };
    (writer, output)
}

impl FeedbackWriter {
    pub fn counters(&self) -> Arc<WriterCounters> {
        self.counters.clone()
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Body position `i` is the group's module `order()[i]`.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Publishes one group feedback; `read(g)` gives the group's module `g`. Does not
    /// allocate.
    pub fn publish(&mut self, arrival_ns: u64, mut read: impl FnMut(usize) -> Sample) {
        if !self.input.consumed() && self.number > 0 {
            self.counters.superseded.fetch_add(1, Relaxed);
        }
        self.number += 1;
        let buf = self.input.input_buffer_mut();
        buf.number = self.number;
        buf.arrival_ns = arrival_ns;
        let mut absent = 0;
        for (slot, &g) in buf.modules.iter_mut().zip(&self.order) {
            *slot = read(g);
            absent += u64::from(!slot.present);
        }
        self.input.publish();
        self.counters.group_feedbacks.fetch_add(1, Relaxed);
        self.counters.absent.fetch_add(absent, Relaxed);
    }
}
