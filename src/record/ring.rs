//! The ring between the control loop and the writer thread: a bounded, preallocated,
//! lock-free MPMC queue (`crossbeam_queue::ArrayQueue`). The loop side makes no system
//! call and takes no lock: the writer polls rather than being woken, because waking a
//! parked thread is a syscall (and `crossbeam_channel`'s waker takes a mutex).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crossbeam_queue::ArrayQueue;

use super::cycle::RecordItem;

/// How long [`RecordTx::push_wait`] sleeps while the ring is full.
const WAIT: std::time::Duration = std::time::Duration::from_micros(200);

/// The shared ring and its counters.
pub(crate) struct Ring {
    queue: ArrayQueue<RecordItem>,
    /// Items refused because the ring was full.
    dropped: AtomicU64,
    /// Set once the recorder has finished: later pushes are refused (and not counted).
    closed: AtomicBool,
}

impl Ring {
    /// A ring of `capacity` items (≥ 1), all slots allocated now.
    pub(crate) fn new(capacity: usize) -> Arc<Self> {
        Arc::new(Self {
            queue: ArrayQueue::new(capacity),
            dropped: AtomicU64::new(0),
            closed: AtomicBool::new(false),
        })
    }

    pub(crate) fn pop(&self) -> Option<RecordItem> {
        self.queue.pop()
    }

    pub(crate) fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    pub(crate) fn close(&self) {
        self.closed.store(true, Ordering::Release);
    }

    pub(crate) fn capacity(&self) -> usize {
        self.queue.capacity()
    }
}

/// Closes the ring when dropped: the writer thread holds one, so a writer that ends
/// for any reason (a panic included) lets waiting pushers go.
pub(crate) struct CloseOnDrop(pub Arc<Ring>);

impl Drop for CloseOnDrop {
    fn drop(&mut self) {
        self.0.close();
    }
}

/// The loop's end of the ring: `Send`, cheap to clone, never blocks, never allocates.
///
/// Dropping the last handle after the [`super::Recorder`] is gone frees the ring: do
/// that off the real-time path (at shutdown) or keep the handle until then.
#[derive(Clone)]
pub struct RecordTx {
    ring: Arc<Ring>,
}

impl RecordTx {
    pub(crate) fn new(ring: Arc<Ring>) -> Self {
        Self { ring }
    }

    /// Copies `item` into the ring. `false` when the ring is full (the item is dropped
    /// and counted in [`RecordTx::dropped`]) or the recorder has finished.
    #[inline]
    pub fn push(&self, item: &RecordItem) -> bool {
        if self.ring.closed.load(Ordering::Acquire) {
            return false;
        }
        match self.ring.queue.push(*item) {
            Ok(()) => true,
            Err(_) => {
                self.ring.dropped.fetch_add(1, Ordering::Relaxed);
                false
            }
        }
    }

    /// For offline runs (the lab's lockstep loop) that would rather wait than lose an
    /// item: retries until the ring takes `item` (nothing is counted as dropped);
    /// `false` only once the recorder has finished or its thread has died. It sleeps,
    /// so never call it from the real-time loop.
    pub fn push_wait(&self, item: &RecordItem) -> bool {
        let mut item = *item;
        loop {
            if self.ring.closed.load(Ordering::Acquire) {
                return false;
            }
            match self.ring.queue.push(item) {
                Ok(()) => return true,
                Err(back) => {
                    item = back;
                    std::thread::sleep(WAIT);
                }
            }
        }
    }

    /// Items dropped so far because the ring was full.
    pub fn dropped(&self) -> u64 {
        self.ring.dropped()
    }

    /// Items waiting in the ring now.
    pub fn len(&self) -> usize {
        self.ring.queue.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ring.queue.is_empty()
    }

    /// The ring's capacity, items.
    pub fn capacity(&self) -> usize {
        self.ring.capacity()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::cycle::RecordEvent;
    use crate::safety::failsafe::{Mode, Reason};

    fn event(t_ns: u64) -> RecordItem {
        RecordItem::Event {
            t_ns,
            event: RecordEvent::Mode {
                mode: Mode::Hold,
                reason: Reason::Operator,
            },
        }
    }

    #[test]
    fn a_full_ring_drops_and_counts() {
        let ring = Ring::new(4);
        let tx = RecordTx::new(ring.clone());
        let accepted = (0..10).filter(|&t| tx.push(&event(t))).count();
        assert_eq!(accepted, 4);
        assert_eq!(tx.dropped(), 6);
        assert_eq!(tx.len(), 4);
        // FIFO: the first four went in.
        let times: Vec<u64> = std::iter::from_fn(|| ring.pop())
            .map(|i| match i {
                RecordItem::Event { t_ns, .. } => t_ns,
                _ => u64::MAX,
            })
            .collect();
        assert_eq!(times, [0, 1, 2, 3]);
    }

    #[test]
    fn a_closed_ring_refuses_without_counting() {
        let ring = Ring::new(4);
        let tx = RecordTx::new(ring.clone());
        ring.close();
        assert!(!tx.push(&event(0)));
        assert_eq!(tx.dropped(), 0);
        assert!(tx.is_empty());
    }
}
