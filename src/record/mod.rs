//! Recording every run: the loop pushes `Copy` items ([`RecordItem`]) into a bounded
//! lock-free ring; a writer thread encodes them as MCAP and, when asked, starts the live
//! view (`crate::live`, the Foxglove WebSocket server) on the same channels. Channels,
//! rates, caps and how to read a file: `docs/recording.md`.
//!
//! # API
//! ```text
//! pub fn start(opts: RecordOptions, info: RecordingInfo) -> Result<(RecordTx, Recorder), RecordError>;
//!
//! RecordOptions { mcap: Option<McapOptions>, live: Option<LiveOptions>,
//!                 ring_capacity: usize /* 1024 */, scene_rate_hz: f64 /* 50 */ }   // Default
//! McapOptions   { path: PathBuf, max_bytes: Option<u64> /* ≥ MIN_MAX_BYTES, 1 MB */,
//!                 max_duration_s: Option<f64>,
//!                 chunk_duration_s: f64 /* 1: a chunk reaches the disk whole at least this often */ } // ::new(path)
//!     fn check(&self) -> Result<(), RecordError>;  // what start refuses before creating the file;
//!                                                  // RecordError::mcap_field names the field
//! live::LiveOptions { addr: SocketAddr /* 127.0.0.1:8765; port 0 = any */, station, caps } // Default
//! RecordingInfo { source: String /* "snaked" | "snake-lab" */, module_names: Vec<String>,
//!                 layout: BodyLayout, world: Option<WorldSpec>, catalog: Catalog,
//!                 metadata: Vec<(String, String)> }
//!
//! impl RecordTx {            // Send + Clone; the 1 kHz loop's end
//!     fn push(&self, item: &RecordItem) -> bool;  // never blocks, never allocates;
//!                                                 // false (and counted) when full
//!     fn dropped(&self) -> u64;  fn len(&self) -> usize;  fn capacity(&self) -> usize;
//! }
//! impl Recorder {            // Drop finishes the file too
//!     fn finish(self) -> Result<RecordSummary, RecordError>;  // drain, summary + index, join;
//!                     // RecordError::Unfinished { path, complete_s, reason } if it could not
//!     fn live_addr(&self) -> Option<SocketAddr>;
//!     fn status(&self) -> RecorderStatus;  // state: RecordState, path, error, lost, items,
//!                                          // messages_written, dropped, bytes, capped:
//!                                          // Option<CapReason>, file: Option<FileState>,
//!                                          // complete_s, live_clients (Serialize)
//!     fn probe(&self) -> RecorderProbe;    // Clone + Send + Sync: .status() from anywhere
//! }
//! RecordState   { Off, Recording, Capped, Failed, Finished }
//! RecordSummary { path, items, messages_written, per_topic, dropped, bytes, capped }
//! FileState     { Writing, Finished, Unfinished }
//!
//! // A file a crash or a full disk left unfinished → a finished one (`snaked --recover`).
//! // Bounded (RECOVER_MAX_CHUNK_BYTES, 64 MiB, a record or a chunk's contents), written to a
//! // hidden file renamed into place once finished: a failure leaves no output.
//! pub fn recover(input: &Path, output: &Path) -> Result<Recovery, RecoverError>;
//! pub fn recovered_path(input: &Path) -> PathBuf;   // run.mcap → run.recovered.mcap
//! Recovery { already_finished, chunks, messages, per_topic, log_time_ns, lost_bytes, stopped }
//! ```
//!
//! # What the loop pushes
//! One [`RecordItem::Cycle`] per cycle, a [`RecordItem::Event`] for every mode change,
//! applied or refused request, engage/release and set-point fault, and a
//! [`RecordItem::Stats`] once a second. Times are the loop's `t_ns`.
//!
//! # Files
//! `ring` (loop ↔ writer), `recorder` (start, finish, status), `writer` (the thread,
//! caps), `topics` (the topics and their foxglove channels), `encode` + `schemas` (JSON bodies and their schemas),
//! `scene` + `kinematics` (3-D), `file` (MCAP, append only), `recover` (a finished file
//! from an unfinished one), `urdf` (the robot's model, served by the live view).

pub mod cycle;
mod encode;
mod error;
mod file;
pub mod kinematics;
mod loop_recorder;
mod options;
mod recorder;
mod recover;
mod ring;
mod scene;
mod schemas;
mod topics;
pub mod urdf;
mod writer;

pub use cycle::{
    CycleRecord, JointSample, RECORD_MAX_LINKS, RECORD_MAX_MODULES, RecordEvent, RecordItem,
};
pub use error::RecordError;
pub use file::MIN_MAX_BYTES;
pub use loop_recorder::{LoopRecorder, LoopRecording};
pub use options::{
    CapReason, DEFAULT_CHUNK_DURATION_S, FileState, McapOptions, RecordOptions, RecordState,
    RecordSummary, RecorderStatus, RecordingInfo,
};
pub use recorder::{CycleSink, Recorder, RecorderProbe, start, start_with};
pub use recover::{RECOVER_MAX_CHUNK_BYTES, RecoverError, Recovery, recover, recovered_path};
pub use ring::RecordTx;
pub use scene::{BODY_FRAME, WORLD_FRAME, link_frame};
pub use topics::Topic;
