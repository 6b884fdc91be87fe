//! Why a recording could not start or finish.

use std::net::SocketAddr;
use std::path::PathBuf;

/// A recorder error. Paths and addresses are named, OS reasons kept as the source.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("invalid recorder option: {0}")]
    InvalidOption(&'static str),
    /// Missing directories are not created, so a typo in the path is caught.
    #[error(
        "cannot record to {}: directory {} does not exist (create it first)",
        path.display(),
        dir.display()
    )]
    MissingDirectory { path: PathBuf, dir: PathBuf },
    #[error("cannot create recording {}: {source}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write recording {}: {source}", path.display())]
    Mcap {
        path: PathBuf,
        #[source]
        source: foxglove::FoxgloveError,
    },
    #[error("cannot finish recording {}: {source}", path.display())]
    Finish {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot start the live view on {addr}: {source}")]
    Live {
        addr: SocketAddr,
        #[source]
        source: foxglove::FoxgloveError,
    },
    #[error("cannot set up the recorder's channels: {0}")]
    Setup(#[source] foxglove::FoxgloveError),
    #[error("cannot start the live view's runtime: {0}")]
    Runtime(#[source] std::io::Error),
    #[error("cannot spawn the recorder thread: {0}")]
    Thread(#[source] std::io::Error),
    #[error("the recorder thread panicked")]
    Panicked,
    #[error("the recorder was already finished")]
    Finished,
}
