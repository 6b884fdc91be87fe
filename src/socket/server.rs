//! Binding the listeners (synchronously, so the daemon fails clearly at start),
//! the server's own tokio runtime on a background thread, accept loops and the
//! client limit.
use std::io;
use std::net::{Ipv4Addr, SocketAddr};
use std::os::unix::fs::{DirBuilderExt, FileTypeExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpListener, UnixListener};

use super::api::{self, OperatorError, code};
use super::clients::{Admission, Clients};
use super::shared::Shared;
use super::{LoopHandle, ServerConfig, conn};
use crate::operator::{Operator, OperatorConfig};

/// How long a shutdown waits for the connections to answer what they are doing and
/// close (an answer the loop owes comes within its ack timeout, or at once when the
/// loop has stopped).
const CLOSE_GRACE: Duration = Duration::from_secs(1);

/// Why the server could not start. Every variant names the path or port.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    #[error("no listener configured: give a unix socket path, a TCP port, or both")]
    NoListener,
    #[error("control socket {path}: another snaked is already listening there")]
    InUse { path: PathBuf },
    #[error("control socket {path}: exists and is not a socket; refusing to replace it")]
    NotASocket { path: PathBuf },
    #[error(
        "control socket {path}: its directory {dir} {why}; another user could replace the \
         socket. Use a directory of your own (e.g. $XDG_RUNTIME_DIR) or fix its owner and mode"
    )]
    UntrustedDirectory {
        path: PathBuf,
        dir: PathBuf,
        why: String,
    },
    #[error("control socket {path}: {what}: {source}")]
    Unix {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: io::Error,
    },
    #[error("control socket 127.0.0.1:{port}: cannot listen: {source}")]
    Tcp {
        port: u16,
        #[source]
        source: io::Error,
    },
    #[error(
        "control socket: TCP needs a token (control.tcp_token_file): without one any local \
         user could drive the robot"
    )]
    TcpWithoutToken,
    #[error("control socket: cannot start its runtime: {0}")]
    Runtime(#[source] io::Error),
}

/// A started server. `shutdown` (or dropping it) stops accepting, closes every
/// connection and removes the socket file.
pub struct RunningServer {
    unix_path: Option<PathBuf>,
    /// (device, inode) of the socket file we bound, so we never remove a successor's.
    unix_id: Option<(u64, u64)>,
    tcp_addr: Option<SocketAddr>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
    shared: Arc<Shared>,
}

impl RunningServer {
    /// The Unix socket's path, if one is bound.
    pub fn unix_path(&self) -> Option<&Path> {
        self.unix_path.as_deref()
    }

    /// The operator API the connections use (the Foxglove station uses it too).
    pub fn operator(&self) -> Operator {
        self.shared.op.clone()
    }

    /// The TCP listener's address (useful with `tcp_port: Some(0)`).
    pub fn tcp_addr(&self) -> Option<SocketAddr> {
        self.tcp_addr
    }

    /// Stop accepting, let every connection answer the request in hand and close (at
    /// most a second), remove the socket file.
    pub fn shutdown(mut self) {
        self.stop_now();
    }

    fn stop_now(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        self.shared.op.stop();
        if let (Some(path), Some(id)) = (&self.unix_path, self.unix_id.take()) {
            match std::fs::metadata(path) {
                Ok(m) if (m.dev(), m.ino()) == id => {
                    if let Err(e) = std::fs::remove_file(path) {
                        tracing::warn!("cannot remove control socket {}: {e}", path.display());
                    }
                }
                _ => {} // Gone already, or another server's socket now.
            }
        }
    }
}

impl Drop for RunningServer {
    fn drop(&mut self) {
        self.stop_now();
    }
}

/// Bind the configured listeners and start serving on a background thread.
pub fn start(cfg: ServerConfig, handle: LoopHandle) -> Result<RunningServer, ServerError> {
    if cfg.unix_path.is_none() && cfg.tcp_port.is_none() {
        return Err(ServerError::NoListener);
    }
    if cfg.tcp_port.is_some() && cfg.tcp_token.as_deref().is_none_or(str::is_empty) {
        return Err(ServerError::TcpWithoutToken);
    }
    // TCP first: if it fails, no socket file has been created yet.
    let tcp = match cfg.tcp_port {
        Some(port) => Some(
            std::net::TcpListener::bind((Ipv4Addr::LOCALHOST, port))
                .and_then(|l| l.set_nonblocking(true).map(|()| l))
                .map_err(|source| ServerError::Tcp { port, source })?,
        ),
        None => None,
    };
    let tcp_addr = tcp.as_ref().and_then(|l| l.local_addr().ok());
    let mut file_guard = SocketFile(None);
    let unix = match &cfg.unix_path {
        Some(path) => {
            let l = bind_unix(path, cfg.socket_mode)?;
            file_guard.0 = Some(path.clone());
            Some(l)
        }
        None => None,
    };
    let unix_id = match (&unix, &cfg.unix_path) {
        (Some(_), Some(path)) => std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino())),
        _ => None,
    };

    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(ServerError::Runtime)?;
    let (closing_tx, closing) = tokio::sync::watch::channel(false);
    // The API's own (it lives on, so it is not among the connections waited for).
    let (op_closing_tx, op_closing) = tokio::sync::watch::channel(false);
    let op = {
        let _enter = rt.enter();
        let config = OperatorConfig {
            ack_timeout: cfg.ack_timeout,
            driver_timeout: cfg.driver_timeout,
            record: cfg.record.clone(),
            pose: cfg.pose.clone(),
        };
        Operator::start(handle, config, op_closing).map_err(ServerError::Runtime)?
    };
    let shared = Arc::new(Shared {
        op,
        max_line_bytes: cfg.max_line_bytes.max(1),
        idle_timeout: cfg.idle_timeout,
        tcp_token: cfg.tcp_token.clone(),
    });
    let clients = Clients::new(cfg.max_clients);
    let mut accepts = Vec::new();
    {
        // Listeners must be registered with the runtime they will run on.
        let _enter = rt.enter();
        if let Some(l) = unix {
            let l = UnixListener::from_std(l).map_err(|source| ServerError::Unix {
                path: cfg.unix_path.clone().unwrap_or_default(),
                what: "cannot register listener",
                source,
            })?;
            let accept = Accept {
                shared: shared.clone(),
                clients: clients.clone(),
                closing: closing.clone(),
            };
            accepts.push(rt.spawn(accept_unix(l, accept)));
        }
        if let Some(l) = tcp {
            let port = cfg.tcp_port.unwrap_or_default();
            let l = TcpListener::from_std(l).map_err(|source| ServerError::Tcp { port, source })?;
            let accept = Accept {
                shared: shared.clone(),
                clients,
                closing,
            };
            accepts.push(rt.spawn(accept_tcp(l, accept)));
        }
    }
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let thread = std::thread::Builder::new()
        .name("snaked-ctl".into())
        .spawn(move || {
            rt.block_on(async {
                let _ = stop_rx.await;
                accepts.iter().for_each(tokio::task::JoinHandle::abort);
                // Every connection answers the request in hand (a calibration that
                // waits is told the daemon shuts down) and closes; each holds a
                // receiver until it has.
                op_closing_tx.send_replace(true);
                closing_tx.send_replace(true);
                let _ = tokio::time::timeout(CLOSE_GRACE, closing_tx.closed()).await;
            });
            // Drops what is left: a connection still waiting past the grace.
            rt.shutdown_timeout(Duration::from_secs(1));
        })
        .map_err(ServerError::Runtime)?;
    file_guard.0 = None; // Started: the server removes the file at shutdown now.
    if let Some(p) = &cfg.unix_path {
        tracing::info!("control socket listening on {}", p.display());
    }
    if let Some(a) = tcp_addr {
        tracing::info!("control socket listening on tcp {a}");
    }
    Ok(RunningServer {
        unix_path: cfg.unix_path,
        unix_id,
        tcp_addr,
        stop: Some(stop_tx),
        thread: Some(thread),
        shared,
    })
}

/// Bind the Unix socket: create the parent directory, replace a stale socket file
/// (nobody answers on it), refuse a live one, then set the file's mode.
fn bind_unix(path: &Path, mode: u32) -> Result<std::os::unix::net::UnixListener, ServerError> {
    let err = |what: &'static str| {
        move |source: io::Error| ServerError::Unix {
            path: path.to_owned(),
            what,
            source,
        }
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        if !parent.exists() {
            // Ours, tight: the owner and its group (the operators) may reach the socket.
            std::fs::DirBuilder::new()
                .recursive(true)
                .mode(0o750)
                .create(parent)
                .map_err(err("cannot create its directory"))?;
        }
        check_directory(path, parent)?;
    }
    match std::fs::symlink_metadata(path) {
        Ok(meta) if !meta.file_type().is_socket() => {
            return Err(ServerError::NotASocket {
                path: path.to_owned(),
            });
        }
        Ok(_) => match std::os::unix::net::UnixStream::connect(path) {
            Ok(_) => {
                return Err(ServerError::InUse {
                    path: path.to_owned(),
                });
            }
            Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => {
                std::fs::remove_file(path).map_err(err("cannot remove the stale socket"))?;
                tracing::info!("removed stale control socket {}", path.display());
            }
            Err(e) => return Err(err("cannot check whether it is in use")(e)),
        },
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(err("cannot inspect it")(e)),
    }
    let listener = std::os::unix::net::UnixListener::bind(path).map_err(err("cannot bind"))?;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
        .map_err(err("cannot set its permissions"))?;
    listener
        .set_nonblocking(true)
        .map_err(err("cannot make it non-blocking"))?;
    Ok(listener)
}

/// The socket's directory must be ours (or root's), and nobody else may replace files in
/// it: not writable by others unless sticky (like /tmp, where only a file's owner may
/// remove it). Otherwise another local user could swap the socket for an impostor.
fn check_directory(path: &Path, dir: &Path) -> Result<(), ServerError> {
    let meta = std::fs::metadata(dir).map_err(|source| ServerError::Unix {
        path: path.to_owned(),
        what: "cannot inspect its directory",
        source,
    })?;
    // SAFETY: geteuid has no preconditions and cannot fail.
    let euid = unsafe { libc::geteuid() };
    let mode = meta.mode();
    let why = if meta.uid() != euid && meta.uid() != 0 {
        Some(format!(
            "is owned by uid {}, not by this daemon's user (uid {euid}) or root",
            meta.uid()
        ))
    } else if mode & 0o002 != 0 && mode & 0o1000 == 0 {
        Some(format!(
            "is writable by every user (mode {:o}) without the sticky bit",
            mode & 0o7777
        ))
    } else {
        None
    };
    match why {
        Some(why) => Err(ServerError::UntrustedDirectory {
            path: path.to_owned(),
            dir: dir.to_owned(),
            why,
        }),
        None => Ok(()),
    }
}

/// Removes a socket file we bound if `start` fails after binding it.
struct SocketFile(Option<PathBuf>);

impl Drop for SocketFile {
    fn drop(&mut self) {
        if let Some(path) = self.0.take() {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// What an accept loop hands each connection.
struct Accept {
    shared: Arc<Shared>,
    clients: Arc<Clients>,
    /// Each connection holds a clone while it lives (see `start`'s shutdown).
    closing: tokio::sync::watch::Receiver<bool>,
}

async fn accept_unix(l: UnixListener, a: Accept) {
    loop {
        match l.accept().await {
            Ok((s, _)) => admit(s, &a, Transport::Unix),
            Err(e) => accept_failed(e).await,
        }
    }
}

async fn accept_tcp(l: TcpListener, a: Accept) {
    loop {
        match l.accept().await {
            Ok((s, _)) => {
                let _ = s.set_nodelay(true);
                admit(s, &a, Transport::Tcp);
            }
            Err(e) => accept_failed(e).await,
        }
    }
}

/// Out of file descriptors and the like: say so, back off, keep serving.
async fn accept_failed(e: io::Error) {
    tracing::warn!("control socket: accept failed: {e}");
    tokio::time::sleep(Duration::from_millis(100)).await;
}

/// How a connection came in: Unix socket clients are vouched for by the socket file's
/// permissions, TCP clients must authenticate with the token first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Transport {
    Unix,
    Tcp,
}

fn admit<S>(stream: S, a: &Accept, transport: Transport)
where
    S: AsyncRead + AsyncWrite + Send + Unpin + 'static,
{
    let (shared, clients, closing) = (a.shared.clone(), &a.clients, a.closing.clone());
    match clients.admit() {
        Admission::Served(client, seat) => {
            tokio::spawn(async move {
                conn::serve(stream, shared, client, transport, closing).await;
                drop(seat);
            });
        }
        // Over the limit a TCP client could not authenticate and stop in one line.
        Admission::OverLimit(_) if transport == Transport::Tcp => {
            let max = clients.max();
            tokio::spawn(refuse(stream, max));
        }
        Admission::OverLimit(seat) => {
            let max = clients.max();
            tokio::spawn(async move {
                conn::serve_over_limit(stream, shared, max, closing).await;
                drop(seat);
            });
        }
        Admission::Refused => {
            let max = clients.max();
            tokio::spawn(refuse(stream, max));
        }
    }
}

/// Tell a client over every limit why, then close.
async fn refuse<S: AsyncWrite + Unpin>(mut stream: S, max: usize) {
    let line = api::error_line(
        &api::null_id(),
        &OperatorError::new(
            code::TOO_MANY_CLIENTS,
            format!("too many clients (at most {max}); closing"),
        ),
    );
    let send = async {
        stream.write_all(line.as_bytes()).await?;
        stream.shutdown().await
    };
    let _ = tokio::time::timeout(Duration::from_secs(1), send).await;
}
