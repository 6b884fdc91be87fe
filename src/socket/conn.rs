//! One client connection: a reader that handles requests in order, and a writer
//! task that owns the socket's write half.
//!
//! Everything the connection sends goes through one bounded queue to its writer.
//! Answers wait for room (that only slows this client, which is not reading);
//! telemetry messages never wait: when the queue is full they are dropped and
//! counted, so a slow subscriber costs nobody else anything.
use std::sync::Arc;

use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt, BufWriter};
use tokio::sync::{mpsc, watch};

use super::api::{self, OperatorError, code};
use super::clients::Client;
use super::lines::{Line, LineReader};
use super::methods;
use super::session::Session;
use super::shared::Shared;

/// Lines queued for one client's writer.
const OUT_QUEUE: usize = 32;

/// Methods a connection over the client limit may call (one, then it closes).
const STOP_METHODS: [&str; 3] = ["estop", "limp", "hold"];
/// How long a connection over the limit has to send its stop request.
const OVER_LIMIT_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Why a served connection stopped waiting for its next line.
enum Wake {
    Line(std::io::Result<Line>),
    /// Its slot went to a newcomer while it was idle.
    Evicted,
    /// No request and no stream for the idle timeout.
    Idle,
    /// The server shuts down.
    Closing,
}

/// Serve one client until it closes, is evicted or idles out, or the server shuts
/// down (after answering the request in hand).
pub(crate) async fn serve<S>(
    stream: S,
    shared: Arc<Shared>,
    client: Arc<Client>,
    transport: super::server::Transport,
    closing: watch::Receiver<bool>,
) where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let (read_half, write_half) = tokio::io::split(stream);
    let (out, out_rx) = mpsc::channel::<String>(OUT_QUEUE);
    let writer = tokio::spawn(write_lines(write_half, out_rx));
    let mut reader = LineReader::new(read_half, shared.max_line_bytes);
    let who = match transport {
        super::server::Transport::Unix => format!("unix client {}", client.id()),
        super::server::Transport::Tcp => format!("tcp client {}", client.id()),
    };
    let mut session = Session::new(out, closing, who);
    session.set_authorized(transport == super::server::Transport::Unix);
    loop {
        let idle = shared.idle_timeout.filter(|_| !session.subscribed());
        let wake = tokio::select! {
            line = reader.next() => Wake::Line(line),
            () = client.evicted.notified() => Wake::Evicted,
            () = sleep_or_never(idle) => Wake::Idle,
            () = session.closing() => Wake::Closing,
        };
        let line = match wake {
            Wake::Line(line) => line,
            Wake::Closing => break,
            Wake::Evicted | Wake::Idle => {
                let why = if matches!(wake, Wake::Evicted) {
                    "closing: this connection was idle while the client limit was reached"
                } else {
                    "closing: idle for too long (no request and no telemetry stream)"
                };
                let line = api::error_line(
                    &api::null_id(),
                    &OperatorError::new(code::TOO_MANY_CLIENTS, why),
                );
                let _ = session.send(line).await;
                break;
            }
        };
        client.touch();
        let answer = match line {
            Ok(Line::Complete) if reader.line().iter().all(u8::is_ascii_whitespace) => continue,
            Ok(Line::Complete) => handle_line(&shared, &mut session, reader.line()).await,
            Ok(Line::TooLong) => api::error_line(
                &api::null_id(),
                &OperatorError::new(
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
                if let Some(mut stream) = session.take_stream() {
                    tokio::select! {
                        _ = &mut stream => {}
                        () = session.closing() => stream.abort(),
                    }
                }
                break;
            }
            Err(_) => break,
        };
        if session.send(answer).await.is_err() {
            break; // The writer stopped: the peer is gone.
        }
        if session.failed_auths >= methods::MAX_FAILED_AUTHS {
            break; // Told so in the answer.
        }
        session.start_pending(&shared.op).await;
        client.set_subscribed(session.subscribed());
        client.touch();
    }
    session.unsubscribe().await;
    // A driver that goes away no longer drives.
    shared.op.release_drive(session.who());
    drop(session); // Closes the queue: the writer flushes what is left and ends.
    let _ = writer.await;
}

async fn sleep_or_never(d: Option<std::time::Duration>) {
    match d {
        Some(d) => tokio::time::sleep(d).await,
        None => std::future::pending().await,
    }
}

/// A connection beyond the client limit: told so at once, then served for one stop
/// request (`estop`, `limp`, `hold`) if it sends one within two seconds, then closed.
/// An e-stop always gets through, however many connections hold the slots.
pub(crate) async fn serve_over_limit<S>(
    stream: S,
    shared: Arc<Shared>,
    max: usize,
    closing: watch::Receiver<bool>,
) where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let (read_half, mut write_half) = tokio::io::split(stream);
    let notice = api::error_line(
        &api::null_id(),
        &OperatorError::new(
            code::TOO_MANY_CLIENTS,
            format!(
                "too many clients (at most {max}): this connection serves one of {} and closes",
                STOP_METHODS.join(", ")
            ),
        ),
    );
    let mut reader = LineReader::new(read_half, shared.max_line_bytes);
    let serve = async {
        write_half.write_all(notice.as_bytes()).await?;
        let line = match reader.next().await? {
            Line::Complete => reader.line().to_vec(),
            _ => return Ok(()),
        };
        let answer = match api::parse_request(&line) {
            Err(bad) => api::error_line(&bad.id, &bad.error),
            Ok(req) if STOP_METHODS.contains(&req.method.as_str()) => {
                let (out, _unused) = mpsc::channel::<String>(1);
                let mut session = Session::new(out, closing, "unix client over the limit".into());
                session.set_authorized(true); // Unix only: see `server::admit`.
                match methods::dispatch(&shared, &mut session, &req.method, req.params).await {
                    Ok(result) => api::result_line(&req.id, &result),
                    Err(e) => api::error_line(&req.id, &e),
                }
            }
            Ok(req) => api::error_line(
                &req.id,
                &OperatorError::new(
                    code::TOO_MANY_CLIENTS,
                    format!(
                        "too many clients (at most {max}): only {} are served over the limit",
                        STOP_METHODS.join(", ")
                    ),
                ),
            ),
        };
        write_half.write_all(answer.as_bytes()).await?;
        write_half.shutdown().await
    };
    let _ = tokio::time::timeout(OVER_LIMIT_WAIT, serve).await;
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
