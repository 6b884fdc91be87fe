//! The MCAP file: created (never overwritten, its directory never created), written
//! through foxglove's MCAP sink (zstd chunks, summary and index at close), its size
//! counted as it grows so the caps can stop it before the disk fills.
//!
//! Crash safety: the writer never seeks. Each chunk is built in memory and appended
//! whole, with its real length (a seeking writer leaves a placeholder length of
//! u64::MAX on an open chunk that a crash makes permanent), and a chunk is closed and
//! the file synced at least every `chunk_duration_s` of loop time. A file cut short by
//! a crash, a power loss or a full disk is then its complete chunks plus at most one
//! torn one, which `super::recover` drops.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use foxglove::{Context, McapCompression, McapWriteOptions, McapWriterHandle};
use mcap::write::NoSeek;

use super::error::RecordError;
use super::options::{CapReason, FileState, McapOptions};

/// Largest chunk (uncompressed), bytes: the writer's default.
pub(super) const MAX_CHUNK: u64 = 1024 * 1024;
/// Smallest chunk, bytes: below this compression suffers for little gain.
const MIN_CHUNK: u64 = 32 * 1024;
/// Smallest size cap, bytes (1 MB, under a second of a run at 1 kHz): a smaller file
/// would hold its metadata and a chunk or two.
pub const MIN_MAX_BYTES: u64 = 1_000_000;

impl McapOptions {
    /// What the recorder refuses before it creates the file: [`super::start`] runs it,
    /// and so does the daemon's configuration check (`snaked --check-config`). A bad
    /// number is [`RecordError::InvalidOption`], its message starting with the field
    /// ([`RecordError::mcap_field`]); a missing directory [`RecordError::MissingDirectory`]; a path
    /// that exists, is a directory or whose directory is not one, [`RecordError::Create`]
    /// with the OS's reason.
    pub fn check(&self) -> Result<(), RecordError> {
        if self
            .max_duration_s
            .is_some_and(|s| !(s.is_finite() && s > 0.0))
        {
            return Err(RecordError::InvalidOption(
                "max_duration_s must be positive and finite",
            ));
        }
        if !(self.chunk_duration_s.is_finite() && self.chunk_duration_s > 0.0) {
            return Err(RecordError::InvalidOption(
                "chunk_duration_s must be positive and finite",
            ));
        }
        if self.max_bytes.is_some_and(|m| m < MIN_MAX_BYTES) {
            return Err(RecordError::InvalidOption(
                "max_bytes must be at least 1000000 (1 MB): a smaller file would hold its \
                 metadata and a chunk or two",
            ));
        }
        let path = &self.path;
        let create = |code| {
            Err(RecordError::Create {
                path: path.clone(),
                reason: io::Error::from_raw_os_error(code),
            })
        };
        let dir = directory(path);
        match std::fs::metadata(dir) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                return Err(RecordError::MissingDirectory {
                    dir: dir.to_path_buf(),
                    path: path.clone(),
                });
            }
            Err(e) => return create(e.raw_os_error().unwrap_or(libc::EACCES)),
            Ok(m) if !m.is_dir() => return create(libc::ENOTDIR),
            Ok(_) => {}
        }
        // An earlier recording is never overwritten (`create_new` refuses it too).
        match std::fs::symlink_metadata(path) {
            Ok(m) if m.is_dir() => create(libc::EISDIR),
            Ok(_) => create(libc::EEXIST),
            Err(_) => Ok(()),
        }
    }
}

/// The directory a file of `path` goes in.
fn directory(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// A `File` that counts how far it reaches and keeps the first failed write's reason.
struct Counting {
    file: File,
    pos: u64,
    size: Arc<AtomicU64>,
    failed: Arc<OnceLock<String>>,
    /// Bytes the disk has room for (`None`: as many as the OS takes); tests fill a
    /// disk with it.
    room: Option<u64>,
}

impl Write for Counting {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let buf = match self.room {
            Some(room) if self.pos + buf.len() as u64 > room => {
                &buf[..room.saturating_sub(self.pos) as usize]
            }
            _ => buf,
        };
        let written = if buf.is_empty() {
            Err(io::Error::from_raw_os_error(libc::ENOSPC))
        } else {
            self.file.write(buf)
        };
        let n = written.inspect_err(|e| {
            if e.kind() != io::ErrorKind::Interrupted {
                let _ = self.failed.set(e.to_string());
            }
        })?;
        self.pos += n as u64;
        self.size.fetch_max(self.pos, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

/// Append only: `NoSeek` answers the writer's position queries and refuses any seek.
type Handle = McapWriterHandle<NoSeek<BufWriter<Counting>>>;

/// An open recording.
pub struct McapFile {
    path: PathBuf,
    handle: Option<Handle>,
    /// The same file, synced after each timed chunk (the handle owns the writer).
    sync: File,
    size: Arc<AtomicU64>,
    failed: Arc<OnceLock<String>>,
    max_bytes: Option<u64>,
    max_duration_ns: Option<u64>,
    chunk_ns: u64,
    /// Loop time at which the open chunk is closed (set by its first item).
    chunk_due_ns: Option<u64>,
    /// Loop time of the last item written, and the part of it complete in the file.
    last_ns: u64,
    complete_ns: u64,
    /// The file's size when `complete_ns` was last set.
    complete_size: u64,
    state: FileState,
    /// Why the file is unfinished.
    error: Option<String>,
}

impl McapFile {
    /// Creates the file and adds it as a sink of `ctx`. `size` follows the file's size.
    pub fn create(
        opts: &McapOptions,
        ctx: &Arc<Context>,
        size: Arc<AtomicU64>,
    ) -> Result<Self, RecordError> {
        Self::create_with_room(opts, ctx, size, None)
    }

    fn create_with_room(
        opts: &McapOptions,
        ctx: &Arc<Context>,
        size: Arc<AtomicU64>,
        room: Option<u64>,
    ) -> Result<Self, RecordError> {
        opts.check()?;
        let path = opts.path.clone();
        let create = |reason| RecordError::Create {
            path: path.clone(),
            reason,
        };
        // `create_new`: an earlier recording is never overwritten.
        let file = File::create_new(&path).map_err(create)?;
        let sync = file.try_clone().map_err(create)?;
        let failed = Arc::new(OnceLock::new());
        size.store(0, Ordering::Relaxed);
        let counting = Counting {
            file,
            pos: 0,
            size: size.clone(),
            failed: failed.clone(),
            room,
        };
        // A size cap is checked as chunks reach the disk: small chunks keep the
        // overshoot within 1/8 of the cap.
        let chunk = opts
            .max_bytes
            .map_or(MAX_CHUNK, |m| (m / 8).clamp(MIN_CHUNK, MAX_CHUNK));
        // `disable_seeking`: each chunk is built in memory and written whole.
        let options = McapWriteOptions::new()
            .compression(Some(McapCompression::Zstd))
            .chunk_size(Some(chunk))
            .disable_seeking(true);
        let handle = ctx
            .mcap_writer_with_options(options)
            .create(NoSeek::new(BufWriter::new(counting)))
            .map_err(|source| RecordError::Mcap {
                path: path.clone(),
                reason: source,
            })?;
        let to_ns = |s: f64| (s.max(0.0) * 1e9).min(u64::MAX as f64) as u64;
        Ok(Self {
            path,
            handle: Some(handle),
            sync,
            size,
            failed,
            max_bytes: opts.max_bytes,
            max_duration_ns: opts.max_duration_s.map(to_ns),
            chunk_ns: to_ns(opts.chunk_duration_s).max(1),
            chunk_due_ns: None,
            last_ns: 0,
            complete_ns: 0,
            complete_size: 0,
            state: FileState::Writing,
            error: None,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn is_open(&self) -> bool {
        self.handle.is_some()
    }

    pub fn size(&self) -> u64 {
        self.size.load(Ordering::Relaxed)
    }

    pub fn state(&self) -> FileState {
        self.state
    }

    /// Loop time (since the first item) that complete chunks in the file hold, ns.
    pub fn complete_ns(&self) -> u64 {
        self.complete_ns
    }

    /// Writes an MCAP metadata record (an empty map writes nothing).
    pub fn write_metadata(
        &self,
        name: &str,
        map: BTreeMap<String, String>,
    ) -> Result<(), RecordError> {
        let Some(h) = &self.handle else {
            return Ok(());
        };
        h.write_metadata(name, map)
            .map_err(|source| RecordError::Mcap {
                path: self.path.clone(),
                reason: source,
            })
    }

    /// Before an item at `recorded_ns` of loop time is written: if it would take the
    /// open chunk to `chunk_duration_s`, closes that chunk, writes it and syncs the file
    /// (so a chunk spans less than `chunk_duration_s` of loop time).
    pub fn before_item(&mut self, recorded_ns: u64) {
        if self.chunk_due_ns.is_some_and(|due| recorded_ns >= due) && self.failed.get().is_none() {
            self.chunk_due_ns = None;
            if let Err(e) = self.flush_chunk() {
                let _ = self.failed.set(e);
            }
        }
    }

    /// After an item at `recorded_ns` has been written: notes what reached the file.
    pub fn item_written(&mut self, recorded_ns: u64) {
        // The file grew while this item was logged: a chunk closed by size reached it,
        // and with it everything buffered before (the buffer is written out whole), so
        // every earlier item is complete.
        if self.size() > self.complete_size && self.failed.get().is_none() {
            self.complete_size = self.size();
            self.complete_ns = self.last_ns;
        }
        self.last_ns = recorded_ns;
        self.chunk_due_ns
            .get_or_insert(recorded_ns.saturating_add(self.chunk_ns));
    }

    /// Writes the open chunk whole and syncs the file.
    fn flush_chunk(&mut self) -> Result<(), String> {
        let Some(h) = &self.handle else {
            return Ok(());
        };
        h.flush().map_err(|e| e.to_string())?;
        self.sync.sync_data().map_err(|e| e.to_string())?;
        self.complete_size = self.size();
        self.complete_ns = self.last_ns;
        Ok(())
    }

    /// Which cap, if any, `recorded_ns` of loop time and the file's size have reached.
    pub fn cap_reached(&self, recorded_ns: u64) -> Option<CapReason> {
        if self.failed.get().is_some() {
            Some(CapReason::WriteError)
        } else if self.max_bytes.is_some_and(|m| self.size() >= m) {
            Some(CapReason::MaxBytes)
        } else if self.max_duration_ns.is_some_and(|m| recorded_ns >= m) {
            Some(CapReason::MaxDuration)
        } else {
            None
        }
    }

    /// Writes the last chunk, the summary and index, and syncs: the file is then
    /// [`FileState::Finished`], or [`FileState::Unfinished`] (a write failed) and the error
    /// says what it holds. Idempotent.
    pub fn close(&mut self) -> Result<(), RecordError> {
        if self.handle.is_some() {
            // The data first: if the summary then fails, no message is lost with it.
            if self.failed.get().is_none()
                && let Err(e) = self.flush_chunk()
            {
                let _ = self.failed.set(e);
            }
            let h = self.handle.take().expect("open");
            // Closing also takes the sink out of the context, even after a failure.
            let closed = h.close().map_err(|e| e.to_string()).and_then(|buffered| {
                let counting = buffered
                    .into_inner()
                    .into_inner()
                    .map_err(|e| e.to_string())?;
                counting.file.sync_all().map_err(|e| e.to_string())
            });
            // The first failure is the cause; later ones follow from it.
            match self.failed.get().cloned().map_or(closed, Err) {
                Ok(()) => {
                    self.state = FileState::Finished;
                    self.complete_ns = self.last_ns;
                }
                Err(first) => {
                    self.state = FileState::Unfinished;
                    self.error = Some(first);
                }
            }
        }
        match &self.error {
            None => Ok(()),
            Some(reason) => Err(RecordError::Unfinished {
                path: self.path.clone(),
                complete_s: self.complete_ns as f64 * 1e-9,
                reason: reason.clone(),
            }),
        }
    }
}

impl Drop for McapFile {
    fn drop(&mut self) {
        if self.handle.is_some()
            && let Err(e) = self.close()
        {
            tracing::error!("recorder: {e}");
        }
    }
}

#[cfg(test)]
#[path = "file_tests.rs"]
pub(crate) mod tests;
