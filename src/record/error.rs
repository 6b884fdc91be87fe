//! Why a recording could not start or finish.

use std::net::SocketAddr;
use std::path::PathBuf;

/// A recorder error: the path or address and the reason in one message (the reason is
/// not also a `source()`, so printing the chain does not say it twice).
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
    #[error("cannot create recording {}: {reason}", path.display())]
    Create {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error("cannot write recording {}: {reason}", path.display())]
    Mcap {
        path: PathBuf,
        reason: foxglove::FoxgloveError,
    },
    #[error("cannot finish recording {}: {reason}", path.display())]
    Finish {
        path: PathBuf,
        reason: std::io::Error,
    },
    /// The summary or footer could not be written (e.g. a full disk): what the file
    /// holds and how to make a finished file of it.
    #[error(
        "recording {} was not finished ({reason}): its complete chunks hold the first \
         {complete_s:.3} s; `snaked --recover {}` makes a finished file of them",
        path.display(),
        path.display()
    )]
    Unfinished {
        path: PathBuf,
        complete_s: f64,
        reason: String,
    },
    #[error("cannot start the live view on {addr}: {reason}")]
    Live {
        addr: SocketAddr,
        reason: foxglove::FoxgloveError,
    },
    #[error("cannot set up the recorder's channels: {0}")]
    Setup(foxglove::FoxgloveError),
    #[error("cannot start the live view's runtime: {0}")]
    Runtime(std::io::Error),
    #[error("cannot spawn the recorder thread: {0}")]
    Thread(std::io::Error),
    #[error("the recorder thread panicked")]
    Panicked,
    #[error("the recorder was already finished")]
    Finished,
}

impl RecordError {
    /// The [`super::McapOptions`] field an error of [`super::McapOptions::check`] is about
    /// (`path`, `max_bytes`, `max_duration_s`, `chunk_duration_s`); `None` for the others.
    pub fn mcap_field(&self) -> Option<&'static str> {
        match self {
            Self::MissingDirectory { .. } | Self::Create { .. } => Some("path"),
            // Their messages start with the field.
            Self::InvalidOption(m) => m.split(' ').next(),
            _ => None,
        }
    }
}

/// The live view's errors as the recorder's (their messages unchanged).
impl From<crate::live::LiveError> for RecordError {
    fn from(e: crate::live::LiveError) -> Self {
        match e {
            crate::live::LiveError::Bind { addr, reason } => Self::Live { addr, reason },
            crate::live::LiveError::Runtime(e) => Self::Runtime(e),
        }
    }
}
