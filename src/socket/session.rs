//! Per-connection state the methods can change: the telemetry stream.
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::MissedTickBehavior;

use super::api;
use super::views;
use crate::controller_interface::catalog::Catalog;
use crate::operator::Operator;
use crate::rt::telemetry::Snapshot;

/// Per-connection state the methods can change.
pub(crate) struct Session {
    out: mpsc::Sender<String>,
    stream: Option<JoinHandle<()>>,
    /// Set by `telemetry.subscribe`; started after its answer is queued.
    pending_rate_hz: Option<f64>,
    /// Telemetry messages dropped because this client read too slowly.
    dropped: Arc<AtomicU64>,
    /// May call methods (Unix clients always; TCP clients after `auth`).
    authorized: bool,
    /// True once the server shuts down. Held while the connection lives: the server
    /// waits for every holder to go before it drops the connections.
    closing: watch::Receiver<bool>,
    /// Who this is, as the drive lease and the logs name it ("unix client 3").
    who: String,
    /// Wrong tokens sent so far (`auth`).
    pub(crate) failed_auths: u32,
}

impl Session {
    pub(crate) fn new(
        out: mpsc::Sender<String>,
        closing: watch::Receiver<bool>,
        who: String,
    ) -> Self {
        Self {
            who,
            failed_auths: 0,
            out,
            stream: None,
            pending_rate_hz: None,
            dropped: Arc::default(),
            authorized: false,
            closing,
        }
    }

    /// Resolves once the server has begun to shut down.
    pub(crate) async fn closing(&self) {
        let mut rx = self.closing.clone();
        // An error: the server is gone, which is closing too.
        let _ = rx.wait_for(|closing| *closing).await;
    }

    pub(crate) fn who(&self) -> &str {
        &self.who
    }

    pub(crate) fn authorized(&self) -> bool {
        self.authorized
    }

    pub(crate) fn set_authorized(&mut self, on: bool) {
        self.authorized = on;
    }

    /// Queue a line for the writer (waits for room); `Err` once the writer is gone.
    pub(crate) async fn send(&self, line: String) -> Result<(), ()> {
        self.out.send(line).await.map_err(|_| ())
    }

    /// Whether a telemetry stream runs (or starts after this answer).
    pub(crate) fn subscribed(&self) -> bool {
        self.stream.is_some() || self.pending_rate_hz.is_some()
    }

    /// The running stream, if any (the connection waits for it on a half-close).
    pub(crate) fn take_stream(&mut self) -> Option<JoinHandle<()>> {
        self.stream.take()
    }

    pub(crate) fn subscribe_after_answer(&mut self, rate_hz: f64) {
        self.pending_rate_hz = Some(rate_hz);
    }

    /// Stop the stream (if any); returns the messages dropped so far.
    pub(crate) async fn unsubscribe(&mut self) -> u64 {
        if let Some(task) = self.stream.take() {
            task.abort();
            // Wait until it has really stopped: nothing of it may follow our answer.
            let _ = task.await;
        }
        self.dropped.load(Ordering::Relaxed)
    }

    pub(crate) async fn start_pending(&mut self, op: &Operator) {
        if let Some(rate_hz) = self.pending_rate_hz.take() {
            self.unsubscribe().await;
            self.dropped.store(0, Ordering::Relaxed);
            let period = Duration::from_secs_f64(1.0 / rate_hz);
            self.stream = Some(tokio::spawn(stream_telemetry(
                op.subscribe(period),
                op.catalog().clone(),
                period,
                self.out.clone(),
                self.dropped.clone(),
            )));
        }
    }
}

/// The newest snapshot of the subscription, at the client's rate.
async fn stream_telemetry(
    snapshots: tokio::sync::watch::Receiver<Arc<Snapshot>>,
    catalog: Catalog,
    period: Duration,
    out: mpsc::Sender<String>,
    dropped: Arc<AtomicU64>,
) {
    let mut ticks = tokio::time::interval(period);
    ticks.set_missed_tick_behavior(MissedTickBehavior::Skip);
    loop {
        ticks.tick().await;
        let latest = snapshots.borrow().clone();
        let line = api::stream_line("telemetry", &views::telemetry(&latest, &catalog));
        match out.try_send(line) {
            Ok(()) => {}
            Err(mpsc::error::TrySendError::Full(_)) => {
                dropped.fetch_add(1, Ordering::Relaxed);
            }
            Err(mpsc::error::TrySendError::Closed(_)) => return,
        }
    }
}
