//! Getting requests to the loop and its acks back to the connection that asked.
//!
//! A request gets a ticket and a oneshot registered in `pending` BEFORE it is
//! sent (so an ack can never arrive first), then goes out with `try_send`: a full
//! channel is an immediate "busy", never a wait. A plain thread blocks on the
//! loop's crossbeam ack channel and completes the oneshot with the same ticket.
//!
//! The loop answers with `try_send` and drops an answer that finds the ack channel
//! full, so the router keeps at most that channel's capacity of requests in flight
//! (sent, answer not yet taken off the channel); one more is "busy". The loop answers
//! each request once, so the channel can never hold more answers than are in flight,
//! and none is ever dropped, however late this thread runs.
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TrySendError};
use tokio::sync::oneshot;

use super::error::{OperatorError, code};
use crate::rt::controller_slots::Installed;
use crate::rt::messages::{Ack, Continuity, Envelope, LoopRequest, LoopResult, Refusal, Rejection};

type Pending = Arc<Mutex<HashMap<u64, oneshot::Sender<LoopResult>>>>;

/// How often the ack thread looks at its stop flag while no ack arrives.
const STOP_POLL: Duration = Duration::from_millis(50);

pub(crate) struct AckRouter {
    requests: Sender<Envelope>,
    pending: Pending,
    /// Requests sent whose answer has not left the ack channel yet.
    in_flight: Arc<InFlight>,
    next_ticket: AtomicU64,
    ack_timeout: Duration,
    stop: Arc<AtomicBool>,
    thread: Mutex<Option<JoinHandle<()>>>,
}

/// Removes its ticket from `pending` when dropped: on timeout, and when the
/// connection waiting for the ack goes away.
struct TicketGuard<'a> {
    pending: &'a Pending,
    ticket: u64,
}

impl Drop for TicketGuard<'_> {
    fn drop(&mut self) {
        lock(self.pending).remove(&self.ticket);
    }
}

fn lock(p: &Pending) -> std::sync::MutexGuard<'_, HashMap<u64, oneshot::Sender<LoopResult>>> {
    // A panic while holding this lock leaves the map consistent (single inserts/removes).
    p.lock().unwrap_or_else(|e| e.into_inner())
}

/// A count of requests in flight, bounded by the ack channel's capacity.
struct InFlight {
    count: AtomicUsize,
    max: usize,
}

impl InFlight {
    /// Takes a place; `false` when all are taken.
    fn enter(&self) -> bool {
        self.count
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < self.max).then_some(n + 1)
            })
            .is_ok()
    }

    fn leave(&self) {
        self.count.fetch_sub(1, Ordering::AcqRel);
    }
}

impl AckRouter {
    pub(crate) fn start(
        requests: Sender<Envelope>,
        acks: Receiver<Ack>,
        ack_timeout: Duration,
    ) -> std::io::Result<Self> {
        let pending: Pending = Arc::default();
        let stop = Arc::new(AtomicBool::new(false));
        let in_flight = Arc::new(InFlight {
            count: AtomicUsize::new(0),
            max: acks.capacity().unwrap_or(usize::MAX),
        });
        let thread = {
            let pending = pending.clone();
            let stop = stop.clone();
            let in_flight = in_flight.clone();
            std::thread::Builder::new()
                .name("snaked-ctl-acks".into())
                .spawn(move || route_acks(&acks, &pending, &in_flight, &stop))?
        };
        Ok(Self {
            requests,
            pending,
            in_flight,
            next_ticket: AtomicU64::new(1),
            ack_timeout,
            stop,
            thread: Mutex::new(Some(thread)),
        })
    }

    /// Send `request` to the loop and wait for its ack (at most `ack_timeout`); what
    /// became of the gait's controller, for a change of its parameters or controller.
    pub(crate) async fn call(
        &self,
        request: LoopRequest,
    ) -> Result<Option<Continuity>, OperatorError> {
        self.call_with(request, None).await
    }

    /// [`Self::call`] with a controller attached. When the queue is
    /// full the controller comes back here and is dropped with the envelope.
    pub(crate) async fn call_with(
        &self,
        request: LoopRequest,
        controller: Option<Installed>,
    ) -> Result<Option<Continuity>, OperatorError> {
        let ticket = self.next_ticket.fetch_add(1, Ordering::Relaxed);
        let (tx, rx) = oneshot::channel();
        lock(&self.pending).insert(ticket, tx);
        let _guard = TicketGuard {
            pending: &self.pending,
            ticket,
        };
        let envelope = Envelope {
            ticket,
            request,
            controller,
        };
        if !self.in_flight.enter() {
            return Err(busy());
        }
        match self.requests.try_send(envelope) {
            Ok(()) => {}
            Err(e) => {
                self.in_flight.leave();
                return Err(match e {
                    TrySendError::Full(_) => busy(),
                    TrySendError::Disconnected(_) => not_running(),
                });
            }
        }
        match tokio::time::timeout(self.ack_timeout, rx).await {
            Ok(Ok(Ok(continuity))) => Ok(continuity),
            Ok(Ok(Err(rejection))) => Err(OperatorError::new(
                code::REFUSED,
                format!("refused by the loop: {rejection}"),
            )),
            Ok(Err(_)) => Err(not_running()),
            Err(_) => Err(OperatorError::new(
                code::LOOP_TIMEOUT,
                format!(
                    "the loop did not answer within {} ms",
                    self.ack_timeout.as_millis()
                ),
            )),
        }
    }

    /// Stop the ack thread (waits for it; at most one `STOP_POLL`).
    pub(crate) fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
        let thread = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(t) = thread {
            let _ = t.join();
        }
    }
}

impl Drop for AckRouter {
    fn drop(&mut self) {
        self.stop();
    }
}

fn busy() -> OperatorError {
    OperatorError::new(
        code::BUSY,
        "busy: the loop's request queue is full; try again",
    )
}

fn not_running() -> OperatorError {
    OperatorError::new(
        code::REFUSED,
        format!(
            "refused: the loop is not running ({})",
            Rejection::Failsafe(Refusal::ShuttingDown)
        ),
    )
}

fn route_acks(acks: &Receiver<Ack>, pending: &Pending, in_flight: &InFlight, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        match acks.recv_timeout(STOP_POLL) {
            Ok(ack) => {
                in_flight.leave();
                // No entry: the requester timed out or left; the ack is dropped.
                if let Some(tx) = lock(pending).remove(&ack.ticket) {
                    let _ = tx.send(ack.result);
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => {
                // The loop is gone: fail every waiter now rather than at their timeouts.
                lock(pending).clear();
                // Keep clearing new waiters until stopped (their sends also fail).
                while !stop.load(Ordering::Relaxed) {
                    std::thread::sleep(STOP_POLL);
                    lock(pending).clear();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rt() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap()
    }

    #[test]
    fn acks_reach_their_requester_and_rejections_carry_their_message() {
        let (req_tx, req_rx) = crossbeam_channel::bounded::<Envelope>(4);
        let (ack_tx, ack_rx) = crossbeam_channel::bounded::<Ack>(4);
        let router = AckRouter::start(req_tx, ack_rx, Duration::from_secs(5)).unwrap();
        let fake = std::thread::spawn(move || {
            for (i, env) in req_rx.iter().take(2).enumerate() {
                let result = if i == 0 {
                    Ok(None)
                } else {
                    Err(Rejection::Failsafe(Refusal::EStopLatched))
                };
                ack_tx
                    .send(Ack {
                        ticket: env.ticket,
                        result,
                    })
                    .unwrap();
            }
        });
        let rt = rt();
        assert_eq!(rt.block_on(router.call(LoopRequest::Hold)), Ok(None));
        let e = rt.block_on(router.call(LoopRequest::Arm)).unwrap_err();
        assert_eq!(e.code, code::REFUSED);
        assert!(e.message.contains("e-stop"), "{}", e.message);
        fake.join().unwrap();
        assert!(lock(&router.pending).is_empty());
    }

    #[test]
    fn full_channel_is_busy_and_silence_times_out() {
        let (req_tx, _req_rx) = crossbeam_channel::bounded::<Envelope>(1);
        let (_ack_tx, ack_rx) = crossbeam_channel::bounded::<Ack>(1);
        let router = AckRouter::start(req_tx, ack_rx, Duration::from_millis(20)).unwrap();
        let rt = rt();
        let e = rt.block_on(router.call(LoopRequest::Hold)).unwrap_err();
        assert_eq!(e.code, code::LOOP_TIMEOUT);
        let e = rt.block_on(router.call(LoopRequest::Hold)).unwrap_err();
        assert_eq!(e.code, code::BUSY);
        assert!(
            lock(&router.pending).is_empty(),
            "timed-out tickets are forgotten"
        );
    }

    /// Issue 25: the loop answers with `try_send` and drops an answer that finds the
    /// ack channel full. The server never has more requests in flight (sent, answer not
    /// yet routed) than that channel holds, so however late the router is, no answer is
    /// dropped: a second wave while the first's answers wait is busy at once.
    #[test]
    fn no_answer_is_dropped_however_late_the_acks_are_routed() {
        const CAP: usize = 8;
        let (req_tx, req_rx) = crossbeam_channel::bounded::<Envelope>(CAP);
        // The loop's ack channel, and a gate standing in for a router that runs late.
        let (loop_tx, loop_rx) = crossbeam_channel::bounded::<Ack>(CAP);
        let (fwd_tx, fwd_rx) = crossbeam_channel::bounded::<Ack>(CAP);
        let router = AckRouter::start(req_tx, fwd_rx, Duration::from_secs(2)).unwrap();
        let taken = Arc::new(AtomicU64::new(0));
        let dropped = Arc::new(AtomicU64::new(0));
        let fake = {
            let (taken, dropped) = (taken.clone(), dropped.clone());
            std::thread::spawn(move || {
                for env in req_rx.iter() {
                    taken.fetch_add(1, Ordering::SeqCst);
                    let ack = Ack {
                        ticket: env.ticket,
                        result: Ok(None),
                    };
                    if loop_tx.try_send(ack).is_err() {
                        dropped.fetch_add(1, Ordering::SeqCst);
                    }
                }
            })
        };
        let open = Arc::new(AtomicBool::new(false));
        let gate = {
            let open = open.clone();
            std::thread::spawn(move || {
                while !open.load(Ordering::SeqCst) {
                    std::thread::sleep(Duration::from_millis(1));
                }
                for ack in loop_rx.iter() {
                    let _ = fwd_tx.send(ack);
                }
            })
        };
        let router = Arc::new(router);
        let done = Arc::new(AtomicU64::new(0));
        let results = rt().block_on(async {
            let mut calls = tokio::task::JoinSet::new();
            for wave in 1..=2u64 {
                for _ in 0..CAP {
                    let (r, done) = (router.clone(), done.clone());
                    calls.spawn(async move {
                        let result = r.call(LoopRequest::Hold).await;
                        done.fetch_add(1, Ordering::SeqCst);
                        result
                    });
                }
                // Until each call of this wave is with the loop or answered.
                let want = CAP as u64 * wave;
                let deadline = tokio::time::Instant::now() + Duration::from_secs(5);
                while taken.load(Ordering::SeqCst) + done.load(Ordering::SeqCst) < want
                    && tokio::time::Instant::now() < deadline
                {
                    tokio::time::sleep(Duration::from_millis(1)).await;
                }
            }
            open.store(true, Ordering::SeqCst);
            calls.join_all().await
        });
        let answered = results.iter().filter(|r| r.is_ok()).count();
        let busy = results
            .iter()
            .filter(|r| matches!(r, Err(e) if e.code == code::BUSY))
            .count();
        assert_eq!(dropped.load(Ordering::SeqCst), 0, "answers dropped");
        assert_eq!(answered as u64, taken.load(Ordering::SeqCst), "{results:?}");
        assert_eq!(answered + busy, 2 * CAP, "{results:?}");
        drop(router);
        fake.join().unwrap();
        gate.join().unwrap();
    }

    #[test]
    fn a_dead_loop_is_refused() {
        let (req_tx, req_rx) = crossbeam_channel::bounded::<Envelope>(1);
        let (ack_tx, ack_rx) = crossbeam_channel::bounded::<Ack>(1);
        drop((req_rx, ack_tx));
        let router = AckRouter::start(req_tx, ack_rx, Duration::from_secs(5)).unwrap();
        let e = rt().block_on(router.call(LoopRequest::Limp)).unwrap_err();
        assert_eq!(e.code, code::REFUSED);
        router.stop();
    }
}
