//! One client connection: a reader that handles requests in order, and a writer
//! task that owns the socket's write half.
//!
//! Everything the connection sends goes through one bounded queue to its writer.
//! Answers wait for room (that only slows this client, which is not reading);
//! telemetry messages never wait: when the queue is full they are dropped and
//! counted, so a slow subscriber costs nobody else anything.
use std::sync::Arc;

use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt, BufWriter};
use tokio::sync::mpsc;

use super::api::{self, RpcError, code};
use super::lines::{Line, LineReader};
use super::methods;
use super::session::Session;
use super::shared::Shared;

/// Lines queued for one client's writer.
const OUT_QUEUE: usize = 32;

/// Serve one client until it closes (or the runtime shuts down).
pub(crate) async fn serve<S>(stream: S, shared: Arc<Shared>)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let (read_half, write_half) = tokio::io::split(stream);
    let (out, out_rx) = mpsc::channel::<String>(OUT_QUEUE);
    let writer = tokio::spawn(write_lines(write_half, out_rx));
    let mut reader = LineReader::new(read_half, shared.max_line_bytes);
    let mut session = Session::new(out);
    loop {
        let answer = match reader.next().await {
            Ok(Line::Complete) if reader.line().iter().all(u8::is_ascii_whitespace) => continue,
            Ok(Line::Complete) => handle_line(&shared, &mut session, reader.line()).await,
            Ok(Line::TooLong) => api::error_line(
                &api::null_id(),
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
                if let Some(stream) = session.take_stream() {
                    let _ = stream.await;
                }
                break;
            }
            Err(_) => break,
        };
        if session.send(answer).await.is_err() {
            break; // The writer stopped: the peer is gone.
        }
        session
            .start_pending(&shared.telemetry, &shared.catalog)
            .await;
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
