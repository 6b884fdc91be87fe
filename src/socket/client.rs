//! A small blocking client of the control socket, for `snakectl` and tests.
use std::io::{self, BufRead, BufReader, Write};
use std::net::TcpStream;
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::Duration;

use serde_json::{Value, json};

use super::api::{OperatorError, code};

/// Where the daemon listens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Endpoint {
    Unix(PathBuf),
    /// `host:port`.
    Tcp(String),
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Endpoint::Unix(p) => write!(f, "{}", p.display()),
            Endpoint::Tcp(a) => write!(f, "tcp {a}"),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error("cannot connect to snaked at {endpoint}: {source} (is the daemon running?)")]
    Connect {
        endpoint: String,
        #[source]
        source: io::Error,
    },
    #[error("no answer from snaked within {0:?}")]
    Timeout(Duration),
    #[error("snaked closed the connection")]
    Closed,
    #[error("connection to snaked failed: {0}")]
    Io(#[from] io::Error),
    #[error("unexpected answer from snaked: {0}")]
    Protocol(String),
    /// The daemon answered with an error.
    #[error("{}: {}", .0.code, .0.message)]
    Rpc(OperatorError),
}

/// One connection. Requests are answered in order; stream messages (no `id`)
/// that arrive while `call` waits for an answer are skipped, and the server's notices
/// (`id` null, -32004: over the client limit, idle) are kept in [`Client::notices`].
pub struct Client {
    reader: BufReader<Box<dyn io::Read + Send>>,
    writer: Box<dyn Write + Send>,
    next_id: u64,
    timeout: Option<Duration>,
    notices: Vec<OperatorError>,
}

impl Client {
    /// Connect; `timeout` bounds every later read (None: wait forever).
    pub fn connect(endpoint: &Endpoint, timeout: Option<Duration>) -> Result<Self, ClientError> {
        let connect_err = |source| ClientError::Connect {
            endpoint: endpoint.to_string(),
            source,
        };
        let (reader, writer): (Box<dyn io::Read + Send>, Box<dyn Write + Send>) = match endpoint {
            Endpoint::Unix(path) => {
                let s = UnixStream::connect(path).map_err(connect_err)?;
                s.set_read_timeout(timeout).map_err(connect_err)?;
                (Box::new(s.try_clone().map_err(connect_err)?), Box::new(s))
            }
            Endpoint::Tcp(addr) => {
                let s = TcpStream::connect(addr.as_str()).map_err(connect_err)?;
                s.set_read_timeout(timeout).map_err(connect_err)?;
                let _ = s.set_nodelay(true);
                (Box::new(s.try_clone().map_err(connect_err)?), Box::new(s))
            }
        };
        Ok(Self {
            reader: BufReader::new(reader),
            writer,
            next_id: 1,
            timeout,
            notices: Vec::new(),
        })
    }

    /// Call `method` and return its result (or the daemon's error as `Rpc`).
    pub fn call(&mut self, method: &str, params: Option<Value>) -> Result<Value, ClientError> {
        let id = self.next_id;
        self.next_id += 1;
        let mut req = json!({ "id": id, "method": method });
        if let Some(p) = params {
            req["params"] = p;
        }
        self.send_line(&req.to_string())?;
        loop {
            let msg = self.next_message()?;
            let Some(answer_id) = msg.get("id") else {
                continue; // A stream message.
            };
            if answer_id.is_null() {
                // The server could not read our id (a bad line: this is our answer), or
                // it speaks on its own (-32004: over the limit, idle): a notice, and
                // the answer still follows (a stop over the limit is served).
                let e = wire_error(&msg)?;
                if e.code == code::TOO_MANY_CLIENTS {
                    self.notices.push(e);
                    continue;
                }
                return Err(ClientError::Rpc(e));
            }
            if *answer_id != json!(id) {
                return Err(ClientError::Protocol(format!(
                    "answer for another id: {msg}"
                )));
            }
            if let Some(result) = msg.get("result") {
                return Ok(result.clone());
            }
            return Err(ClientError::Rpc(wire_error(&msg)?));
        }
    }

    /// What the server said on its own while calls waited (its -32004 notices), oldest
    /// first.
    pub fn notices(&self) -> &[OperatorError] {
        &self.notices
    }

    /// Send one raw line (a newline is appended).
    pub fn send_line(&mut self, line: &str) -> Result<(), ClientError> {
        self.writer.write_all(line.as_bytes())?;
        self.writer.write_all(b"\n")?;
        self.writer.flush()?;
        Ok(())
    }

    /// The next line from the daemon, parsed.
    pub fn next_message(&mut self) -> Result<Value, ClientError> {
        let mut line = String::new();
        match self.reader.read_line(&mut line) {
            Ok(0) => Err(ClientError::Closed),
            Ok(_) => serde_json::from_str(&line)
                .map_err(|e| ClientError::Protocol(format!("{e}: {}", line.trim_end()))),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                Err(ClientError::Timeout(self.timeout.unwrap_or_default()))
            }
            Err(e) => Err(e.into()),
        }
    }
}

#[derive(serde::Deserialize)]
struct OperatorErrorWire {
    code: i64,
    message: String,
}

/// The `error` of an answer or notice.
fn wire_error(msg: &Value) -> Result<OperatorError, ClientError> {
    serde_json::from_value::<OperatorErrorWire>(msg["error"].clone())
        .map(|e| OperatorError::new(e.code, e.message))
        .map_err(|_| ClientError::Protocol(msg.to_string()))
}

#[cfg(test)]
#[path = "client_tests.rs"]
mod tests;
