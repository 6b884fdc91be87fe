//! What a recording is asked to do ([`RecordOptions`]) and what it describes
//! ([`RecordingInfo`]), and what it reports back ([`RecorderStatus`], [`RecordSummary`]).

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::controller_interface::catalog::Catalog;
use crate::emu::world::WorldSpec;
use crate::gait::BodyLayout;
use crate::live::LiveOptions;

/// A chunk is closed (and reaches the disk whole) at least this often, s of loop time:
/// what a crash can lose of the file beyond what the ring held.
pub const DEFAULT_CHUNK_DURATION_S: f64 = 1.0;

/// What to record and where.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOptions {
    /// Write an MCAP file.
    pub mcap: Option<McapOptions>,
    /// Serve the same channels live over the Foxglove WebSocket protocol.
    pub live: Option<LiveOptions>,
    /// Items the ring holds (one per cycle, plus events and stats): 1024 ≈ 1 s at 1 kHz,
    /// about 13 MB preallocated.
    pub ring_capacity: usize,
    /// Rate of the 3-D channels (`/tf`, `/scene/body`), Hz.
    pub scene_rate_hz: f64,
}

impl Default for RecordOptions {
    fn default() -> Self {
        Self {
            mcap: None,
            live: None,
            ring_capacity: 1024,
            scene_rate_hz: 50.0,
        }
    }
}

/// The MCAP file and its caps. The file must not exist yet and its directory must.
#[derive(Debug, Clone, PartialEq)]
pub struct McapOptions {
    pub path: PathBuf,
    /// Stop writing once the file reaches this size (it may exceed it by about one
    /// chunk, at most 1/8 of the cap, plus the summary).
    pub max_bytes: Option<u64>,
    /// Stop writing once this much loop time has been recorded, s.
    pub max_duration_s: Option<f64>,
    /// Close the open chunk, write it whole and sync the file at least this often, s of
    /// loop time ([`DEFAULT_CHUNK_DURATION_S`]): a crash or power loss then loses at most
    /// this much of the file, plus what the ring held.
    pub chunk_duration_s: f64,
}

impl McapOptions {
    /// A file without caps, chunks of at most [`DEFAULT_CHUNK_DURATION_S`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            max_bytes: None,
            max_duration_s: None,
            chunk_duration_s: DEFAULT_CHUNK_DURATION_S,
        }
    }
}

/// What the recording is of: written as MCAP metadata, and used to name and draw.
#[derive(Debug, Clone)]
pub struct RecordingInfo {
    /// Who records: `"snaked"` or `"snake-lab"`.
    pub source: String,
    /// One name per module, head first.
    pub module_names: Vec<String>,
    /// The body (module length, joint planes) the 3-D view is drawn from.
    pub layout: BodyLayout,
    /// The simulated world, drawn once in `/scene/world` (None on the robot).
    pub world: Option<WorldSpec>,
    /// Where controller ids are named.
    pub catalog: Catalog,
    /// Anything else worth keeping (configuration, scenario, seed, git revision...),
    /// written as the `snaked.metadata` record.
    pub metadata: Vec<(String, String)>,
}

/// Why the file stopped growing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CapReason {
    MaxBytes,
    MaxDuration,
    /// A write failed (e.g. the disk is full); the file was closed as well as it could be.
    WriteError,
}

/// What state the MCAP file is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FileState {
    /// Being written. Its chunks reach the disk whole; after a crash `snaked --recover`
    /// makes a finished file of them.
    Writing,
    /// Summary, index and footer written: every reader opens it.
    Finished,
    /// A write failed (e.g. a full disk), so it has no summary or footer: its complete
    /// chunks hold the first [`RecorderStatus::complete_s`] of the recording, and
    /// `snaked --recover` makes a finished file of them.
    Unfinished,
}

/// What the recorder does with its file, in one word (`status` and `stats`' `record`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RecordState {
    /// No file (the live view alone, or nothing).
    Off,
    /// Writing the file.
    Recording,
    /// A size or duration cap was reached: the file is finished, later items are not
    /// written.
    Capped,
    /// A write failed (a full disk, a file-size limit): the file is unfinished
    /// ([`RecorderStatus::error`] says why and what it holds), later items are lost
    /// ([`RecorderStatus::lost`]).
    Failed,
    /// The file is finished (the recorder has stopped).
    Finished,
}

/// A snapshot of a running recorder. Serialised as the control socket's `record`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RecorderStatus {
    pub state: RecordState,
    /// The file (`None`: no file).
    pub path: Option<PathBuf>,
    /// Why the file failed: the unfinished file's error, with how to recover it.
    pub error: Option<String>,
    /// Items taken from the ring after a failed write stopped the file: lost to the
    /// file (the live view still had them).
    pub lost: u64,
    /// Items taken from the ring.
    pub items: u64,
    /// Messages written to the MCAP file.
    pub messages_written: u64,
    /// Items the loop could not push because the ring was full.
    pub dropped: u64,
    /// Bytes in the MCAP file so far (grows a chunk at a time).
    pub bytes: u64,
    /// Set once a cap was reached: the file is closed, the ring is still drained.
    pub capped: Option<CapReason>,
    /// The file's state (`None`: no file).
    pub file: Option<FileState>,
    /// Loop time, s since the first item, that complete chunks in the file hold (all of
    /// it once finished).
    pub complete_s: f64,
    /// Live-view clients connected now.
    pub live_clients: usize,
}

impl RecordState {
    /// The state a file in `file` (`None`: no file), stopped by `capped`, is in.
    pub fn of(file: Option<FileState>, capped: Option<CapReason>) -> Self {
        match (file, capped) {
            (None, _) => Self::Off,
            (Some(FileState::Unfinished), _) | (_, Some(CapReason::WriteError)) => Self::Failed,
            (Some(FileState::Writing), _) => Self::Recording,
            (Some(FileState::Finished), Some(_)) => Self::Capped,
            (Some(FileState::Finished), None) => Self::Finished,
        }
    }
}

/// What a finished recording holds.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordSummary {
    pub path: Option<PathBuf>,
    /// Items taken from the ring.
    pub items: u64,
    /// Messages written to the MCAP file, all channels.
    pub messages_written: u64,
    /// Messages written per topic.
    pub per_topic: BTreeMap<String, u64>,
    /// Items the loop could not push because the ring was full.
    pub dropped: u64,
    /// Size of the finished file.
    pub bytes: u64,
    pub capped: Option<CapReason>,
}
