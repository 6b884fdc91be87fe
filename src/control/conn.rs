//! One client connection: a reader that handles requests in order, and a writer
//! task that owns the socket's write half.
//!
//! Everything the connection sends goes through one bounded queue to its writer.
//! Answers wait for room (that only slows this client, which is not reading);
//! telemetry messages never wait: when the queue is full they are dropped and
//! counted, so a slow subscriber costs nobody else anything.
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use serde_json::Value;
use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt, BufWriter};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::MissedTickBehavior;

use super::api::{self, RpcError, code};
use super::lines::{Line, LineReader};
use super::methods;
use super::server::Shared;
use super::views;
use crate::rt::telemetry::TelemetryReader;

/// Lines queued for one client's writer.
const OUT_QUEUE: usize = 32;

/// Per-connection state the methods can change.
pub(crate) struct Session {
    out: mpsc::Sender<String>,
    stream: Option<JoinHandle<()>>,
    /// Set by `telemetry.subscribe`; started after its answer is queued.
    pending_rate_hz: Option<f64>,
    /// Telemetry messages dropped because this client read too slowly.
    dropped: Arc<AtomicU64>,
}

impl Session {
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

    async fn start_pending(&mut self, telemetry: &TelemetryReader) {
        if let Some(rate_hz) = self.pending_rate_hz.take() {
            self.unsubscribe().await;
            self.dropped.store(0, Ordering::Relaxed);
            self.stream = Some(tokio::spawn(stream_telemetry(
                telemetry.clone(),
                Duration::from_secs_f64(1.0 / rate_hz),
                self.out.clone(),
                self.dropped.clone(),
            )));
        }
    }
}

/// Serve one client until it closes (or the runtime shuts down).
pub(crate) async fn serve<S>(stream: S, shared: Arc<Shared>)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let (read_half, write_half) = tokio::io::split(stream);
    let (out, out_rx) = mpsc::channel::<String>(OUT_QUEUE);
    let writer = tokio::spawn(write_lines(write_half, out_rx));
    let mut reader = LineReader::new(read_half, shared.max_line_bytes);
    let mut session = Session {
        out,
        stream: None,
        pending_rate_hz: None,
        dropped: Arc::default(),
    };
    loop {
        let answer = match reader.next().await {
            Ok(Line::Complete) if reader.line().iter().all(u8::is_ascii_whitespace) => continue,
            Ok(Line::Complete) => handle_line(&shared, &mut session, reader.line()).await,
            Ok(Line::TooLong) => api::error_line(
                &Value::Null,
                &RpcError::new(
                    code::LINE_TOO_LONG,
                    format!(
                        "line longer than {} bytes: discarded up to its newline",
                        shared.max_line_bytes
                    ),
                ),
            ),
            Ok(Line::Eof) => {
                // Half-closed (`echo '...subscribe...' | socat`): a subscriber keeps
                // its stream until the peer closes completely and the writer fails.
                if let Some(stream) = session.stream.take() {
                    let _ = stream.await;
                }
                break;
            }
            Err(_) => break,
        };
        if session.out.send(answer).await.is_err() {
            break; // The writer stopped: the peer is gone.
        }
        session.start_pending(&shared.telemetry).await;
    }
    session.unsubscribe().await;
    drop(session); // Closes the queue: the writer flushes what is left and ends.
    let _ = writer.await;
}

async fn handle_line(shared: &Arc<Shared>, session: &mut Session, line: &[u8]) -> String {
    match api::parse_request(line) {
        Err(bad) => api::error_line(&bad.id, &bad.error),
        Ok(req) => match methods::dispatch(shared, session, &req.method, req.params).await {
            Ok(result) => api::result_line(&req.id, &result),
            Err(e) => api::error_line(&req.id, &e),
        },
    }
}

async fn write_lines<W: AsyncWrite + Unpin>(w: W, mut rx: mpsc::Receiver<String>) {
    let mut w = BufWriter::new(w);
    while let Some(line) = rx.recv().await {
        if w.write_all(line.as_bytes()).await.is_err() {
            return;
        }
        // Batch what is already queued into one write.
        if rx.is_empty() && w.flush().await.is_err() {
            return;
        }
    }
    let _ = w.flush().await;
    let _ = w.shutdown().await;
}

async fn stream_telemetry(
    telemetry: TelemetryReader,
    period: Duration,
    out: mpsc::Sender<String>,
    dropped: Arc<AtomicU64>,
) {
    let mut ticks = tokio::time::interval(period);
    ticks.set_missed_tick_behavior(MissedTickBehavior::Skip);
    loop {
        ticks.tick().await;
        let line = api::stream_line("telemetry", &views::telemetry(&telemetry.latest()));
        match out.try_send(line) {
            Ok(()) => {}
            Err(mpsc::error::TrySendError::Full(_)) => {
                dropped.fetch_add(1, Ordering::Relaxed);
            }
            Err(mpsc::error::TrySendError::Closed(_)) => return,
        }
    }
}
