//! The channels between the control side and the loop, made in one place so the
//! daemon, the lab and the tests size them alike: requests in, answers out, and
//! controllers the loop retires (freed off the loop thread).

use crossbeam_channel::{Receiver, Sender, bounded};

use super::control_loop::ack_capacity;
use super::controller_slots::Installed;
use super::messages::{Ack, Envelope};

/// The loop's ends.
pub struct LoopEnds {
    pub requests: Receiver<Envelope>,
    pub acks: Sender<Ack>,
    pub retired: Sender<Installed>,
}

/// The control side's ends.
pub struct ControlEnds {
    pub requests: Sender<Envelope>,
    pub acks: Receiver<Ack>,
    pub retired: Receiver<Installed>,
}

/// The channel set for a queue of `requests` requests: the answers sized by
/// [`ack_capacity`] (the loop's `try_send` of an answer never finds it full), the
/// retired controllers by the queue plus two (each request retires at most one and the
/// control side drains before it sends one: it never fills).
pub fn loop_channels(requests: usize) -> (ControlEnds, LoopEnds) {
    let (req_tx, req_rx) = bounded(requests);
    let (ack_tx, ack_rx) = bounded(ack_capacity(requests));
    let (retired_tx, retired_rx) = bounded(requests + 2);
    (
        ControlEnds {
            requests: req_tx,
            acks: ack_rx,
            retired: retired_rx,
        },
        LoopEnds {
            requests: req_rx,
            acks: ack_tx,
            retired: retired_tx,
        },
    )
}
