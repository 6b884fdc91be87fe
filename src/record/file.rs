//! The MCAP file: created (never overwritten, its directory never created), written
//! through foxglove's MCAP sink (zstd chunks, summary and index at close), its size
//! counted as it grows so the caps can stop it before the disk fills.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use foxglove::{Context, McapCompression, McapWriteOptions, McapWriterHandle};

use super::error::RecordError;
use super::options::{CapReason, McapOptions};

/// Largest chunk (uncompressed), bytes: the writer's default.
const MAX_CHUNK: u64 = 1024 * 1024;
/// Smallest chunk, bytes: below this compression suffers for little gain.
const MIN_CHUNK: u64 = 32 * 1024;

/// A `File` that counts how far it reaches and remembers a failed write.
struct Counting {
    file: File,
    pos: u64,
    size: Arc<AtomicU64>,
    failed: Arc<AtomicBool>,
}

impl Write for Counting {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf).inspect_err(|_| {
            self.failed.store(true, Ordering::Relaxed);
        })?;
        self.pos += n as u64;
        self.size.fetch_max(self.pos, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Counting {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.pos = self.file.seek(to)?;
        Ok(self.pos)
    }
}

type Handle = McapWriterHandle<BufWriter<Counting>>;

/// An open recording.
pub struct McapFile {
    path: PathBuf,
    handle: Option<Handle>,
    size: Arc<AtomicU64>,
    failed: Arc<AtomicBool>,
    max_bytes: Option<u64>,
    max_duration_ns: Option<u64>,
}

impl McapFile {
    /// Creates the file and adds it as a sink of `ctx`. `size` follows the file's size.
    pub fn create(
        opts: &McapOptions,
        ctx: &Arc<Context>,
        size: Arc<AtomicU64>,
    ) -> Result<Self, RecordError> {
        let path = opts.path.clone();
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if !dir.exists() {
            return Err(RecordError::MissingDirectory {
                dir: dir.to_path_buf(),
                path,
            });
        }
        // `create_new`: an earlier recording is never overwritten.
        let file = File::create_new(&path).map_err(|source| RecordError::Create {
            path: path.clone(),
            reason: source,
        })?;
        let failed = Arc::new(AtomicBool::new(false));
        size.store(0, Ordering::Relaxed);
        let counting = Counting {
            file,
            pos: 0,
            size: size.clone(),
            failed: failed.clone(),
        };
        // A size cap is checked as chunks reach the disk: small chunks keep the
        // overshoot within 1/8 of the cap.
        let chunk = opts
            .max_bytes
            .map_or(MAX_CHUNK, |m| (m / 8).clamp(MIN_CHUNK, MAX_CHUNK));
        let options = McapWriteOptions::new()
            .compression(Some(McapCompression::Zstd))
            .chunk_size(Some(chunk));
        let handle = ctx
            .mcap_writer_with_options(options)
            .create(BufWriter::new(counting))
            .map_err(|source| RecordError::Mcap {
                path: path.clone(),
                reason: source,
            })?;
        let max_duration_ns = opts
            .max_duration_s
            .map(|s| (s.max(0.0) * 1e9).min(u64::MAX as f64) as u64);
        Ok(Self {
            path,
            handle: Some(handle),
            size,
            failed,
            max_bytes: opts.max_bytes,
            max_duration_ns,
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

    /// Which cap, if any, `recorded_ns` of loop time and the file's size have reached.
    pub fn cap_reached(&self, recorded_ns: u64) -> Option<CapReason> {
        if self.failed.load(Ordering::Relaxed) {
            Some(CapReason::WriteError)
        } else if self.max_bytes.is_some_and(|m| self.size() >= m) {
            Some(CapReason::MaxBytes)
        } else if self.max_duration_ns.is_some_and(|m| recorded_ns >= m) {
            Some(CapReason::MaxDuration)
        } else {
            None
        }
    }

    /// Writes the summary and index, flushes and syncs. Idempotent.
    pub fn close(&mut self) -> Result<(), RecordError> {
        let Some(h) = self.handle.take() else {
            return Ok(());
        };
        let path = self.path.clone();
        let buffered = h.close().map_err(|source| RecordError::Mcap {
            path: path.clone(),
            reason: source,
        })?;
        let counting = buffered.into_inner().map_err(|e| RecordError::Finish {
            path: path.clone(),
            reason: e.into_error(),
        })?;
        counting
            .file
            .sync_all()
            .map_err(|source| RecordError::Finish {
                path,
                reason: source,
            })
    }
}

impl Drop for McapFile {
    fn drop(&mut self) {
        if let Err(e) = self.close() {
            tracing::warn!("recorder: {e}");
        }
    }
}
