//! Recovery: a finished file (summary, index, footer) made of one that a crash, a power
//! loss or a full disk left without its end, as `mcap recover` does. The file is read
//! from the start; every complete chunk's messages and every metadata record are
//! written to a new file (the old one is never touched), and reading stops at the
//! first record that is cut short or does not check out: the chunk that was being
//! written. `snaked --recover` runs it.
//!
//! Bounded: the input is read record by record, no record outside a chunk and no
//! chunk's contents may exceed [`RECOVER_MAX_CHUNK_BYTES`] (a chunk declaring more is refused
//! before anything is decompressed, and none is decompressed past what it declares),
//! and the output is written as it goes. The output is written to a hidden file beside
//! it and renamed into place only once finished: a failure leaves nothing behind.

use std::collections::BTreeMap;
use std::ffi::CString;
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Read, Seek, SeekFrom};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

mod copy;

/// Largest record outside a chunk (a compressed chunk, a metadata record, an attachment)
/// and largest chunk contents (uncompressed) a recovery reads, bytes: 64 times the
/// recorder's chunk (1 MiB, `super::file::MAX_CHUNK`).
pub const RECOVER_MAX_CHUNK_BYTES: u64 = 64 * super::file::MAX_CHUNK;

/// Why a recovery could not be done.
#[derive(Debug, thiserror::Error)]
pub enum RecoverError {
    #[error("cannot read {}: {reason}", path.display())]
    Read { path: PathBuf, reason: io::Error },
    #[error("{} is not an MCAP file (it does not start with the MCAP magic)", path.display())]
    NotMcap { path: PathBuf },
    /// A FIFO, a device, a directory...: refused before anything is read from it.
    #[error("{} is {kind}, not a regular file: only a recording's file can be recovered", path.display())]
    NotAFile { path: PathBuf, kind: &'static str },
    #[error(
        "{}: the chunk at byte {offset} declares {declared} bytes uncompressed, more than the \
         {limit} bytes a recovery expands a chunk to (snaked writes chunks of about 1 MiB): \
         refused, nothing written",
        path.display()
    )]
    ChunkTooLarge {
        path: PathBuf,
        offset: u64,
        declared: u64,
        limit: u64,
    },
    #[error(
        "{}: the record at byte {offset} (opcode {opcode:#04x}) is {len} bytes long, more than \
         the {limit} bytes a recovery reads at once: refused, nothing written",
        path.display()
    )]
    RecordTooLarge {
        path: PathBuf,
        offset: u64,
        opcode: u8,
        len: u64,
        limit: u64,
    },
    /// Not one message in a complete chunk: no file is written.
    #[error("{}: nothing to recover: {why}; nothing written", path.display())]
    Nothing { path: PathBuf, why: String },
    #[error("cannot create {}: {reason}", path.display())]
    Create { path: PathBuf, reason: io::Error },
    #[error("cannot write {}: {reason}{}", path.display(), write_hint(reason))]
    Write { path: PathBuf, reason: io::Error },
}

/// What a failed write's reason means for the operator.
fn write_hint(reason: &io::Error) -> &'static str {
    match reason.raw_os_error() {
        Some(libc::ENOSPC) => {
            " (ENOSPC: the disk is full; free some space or recover to another disk)"
        }
        Some(libc::EDQUOT) => " (EDQUOT: the disk quota is used up)",
        Some(libc::EFBIG) => " (EFBIG: past the file-size limit, `ulimit -f`)",
        _ => "",
    }
}

/// What a recovery found and wrote.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recovery {
    /// The file already ended with its footer: nothing was written.
    pub already_finished: bool,
    /// Complete chunks copied.
    pub chunks: u64,
    /// Messages copied, all topics and per topic.
    pub messages: u64,
    pub per_topic: BTreeMap<String, u64>,
    /// Log times of the first and the last message copied, ns.
    pub log_time_ns: Option<(u64, u64)>,
    /// Bytes after the last complete record: the chunk being written when it stopped.
    pub lost_bytes: u64,
    /// Why reading stopped before the end of a data section (`None`: it ended cleanly).
    pub stopped: Option<String>,
}

impl Recovery {
    /// Seconds from the first to the last message copied.
    pub fn span_s(&self) -> f64 {
        self.log_time_ns
            .map_or(0.0, |(a, b)| b.saturating_sub(a) as f64 * 1e-9)
    }
}

/// `run.mcap` → `run.recovered.mcap`, beside it.
pub fn recovered_path(input: &Path) -> PathBuf {
    let stem = input.file_stem().unwrap_or_default().to_string_lossy();
    input.with_file_name(format!("{stem}.recovered.mcap"))
}

/// Writes `output` (which must not exist) from the complete part of `input`. A file
/// that already ends with its footer is left alone (`already_finished`). On any error
/// `output` is not created.
pub fn recover(input: &Path, output: &Path) -> Result<Recovery, RecoverError> {
    let read_err = |reason| RecoverError::Read {
        path: input.to_path_buf(),
        reason,
    };
    let (mut file, len) = open_input(input)?;
    if ends_finished(&mut file, len).map_err(read_err)? {
        return Ok(Recovery {
            already_finished: true,
            ..Recovery::default()
        });
    }
    file.seek(SeekFrom::Start(0)).map_err(read_err)?;
    let (mut partial, out) = Partial::create(output)?;
    let (rec, out) = copy::copy(&mut file, len, input, output, BufWriter::new(out))?;
    let write_err = |reason| RecoverError::Write {
        path: output.to_path_buf(),
        reason,
    };
    out.into_inner()
        .map_err(|e| write_err(e.into_error()))?
        .sync_all()
        .map_err(write_err)?;
    partial.persist().map_err(write_err)?;
    Ok(rec)
}

/// Opens `input` without blocking (a FIFO would wait for a writer), refuses anything
/// but a regular file, and checks its magic. Its length too.
fn open_input(input: &Path) -> Result<(File, u64), RecoverError> {
    let read_err = |reason| RecoverError::Read {
        path: input.to_path_buf(),
        reason,
    };
    let mut file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(input)
        .map_err(read_err)?;
    let meta = file.metadata().map_err(read_err)?;
    let t = meta.file_type();
    let kind = if t.is_file() {
        None
    } else if t.is_fifo() {
        Some("a FIFO")
    } else if t.is_dir() {
        Some("a directory")
    } else if t.is_char_device() {
        Some("a character device")
    } else if t.is_block_device() {
        Some("a block device")
    } else if t.is_socket() {
        Some("a socket")
    } else {
        Some("not a file")
    };
    if let Some(kind) = kind {
        return Err(RecoverError::NotAFile {
            path: input.to_path_buf(),
            kind,
        });
    }
    let mut magic = [0u8; 8];
    let not_mcap = || RecoverError::NotMcap {
        path: input.to_path_buf(),
    };
    file.read_exact(&mut magic).map_err(|_| not_mcap())?;
    if magic != mcap::MAGIC {
        return Err(not_mcap());
    }
    Ok((file, meta.len()))
}

/// Whether the file ends with the MCAP magic after room for a footer: a finished file.
fn ends_finished(file: &mut File, len: u64) -> io::Result<bool> {
    // Magic, footer record (opcode, length, 20 bytes), magic.
    if len < 8 + 9 + 20 + 8 {
        return Ok(false);
    }
    let mut tail = [0u8; 8];
    file.seek(SeekFrom::End(-8))?;
    file.read_exact(&mut tail)?;
    Ok(tail == mcap::MAGIC)
}

/// The output while it is written: a hidden file in the output's directory
/// (`.NAME.partial-PID`), renamed to the output only once finished and removed
/// otherwise, so a failure never leaves a file that a rerun would refuse to overwrite.
struct Partial {
    tmp: PathBuf,
    output: PathBuf,
    persisted: bool,
}

impl Partial {
    /// The hidden file, created, and its handle.
    fn create(output: &Path) -> Result<(Self, File), RecoverError> {
        let create_err = |reason| RecoverError::Create {
            path: output.to_path_buf(),
            reason,
        };
        if output.symlink_metadata().is_ok() {
            return Err(create_err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                "it exists, and a recovery never overwrites a file",
            )));
        }
        let name = output
            .file_name()
            .ok_or_else(|| create_err(io::Error::from(io::ErrorKind::InvalidInput)))?;
        let dir = match output.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let pid = std::process::id();
        for n in 0..100 {
            let suffix = if n == 0 {
                String::new()
            } else {
                format!(".{n}")
            };
            let tmp = dir.join(format!(".{}.partial-{pid}{suffix}", name.to_string_lossy()));
            match File::create_new(&tmp) {
                Ok(file) => {
                    let partial = Self {
                        tmp,
                        output: output.to_path_buf(),
                        persisted: false,
                    };
                    return Ok((partial, file));
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(create_err(e)),
            }
        }
        Err(create_err(io::Error::from(io::ErrorKind::AlreadyExists)))
    }

    /// Renames the finished file to the output, unless the output appeared meanwhile,
    /// and syncs the directory (at best) so the name survives a power loss.
    fn persist(&mut self) -> io::Result<()> {
        rename_no_replace(&self.tmp, &self.output)?;
        self.persisted = true;
        let dir = match self.output.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let _ = File::open(dir).and_then(|d| d.sync_all());
        Ok(())
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        if !self.persisted {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// `rename(from, to)` that fails if `to` exists (`renameat2(RENAME_NOREPLACE)`; a hard
/// link and an unlink on a file system without it).
fn rename_no_replace(from: &Path, to: &Path) -> io::Result<()> {
    let c = |p: &Path| {
        CString::new(p.as_os_str().as_bytes())
            .map_err(|_| io::Error::from(io::ErrorKind::InvalidInput))
    };
    let (f, t) = (c(from)?, c(to)?);
    // SAFETY: two NUL-terminated paths that outlive the call.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            f.as_ptr(),
            libc::AT_FDCWD,
            t.as_ptr(),
            libc::RENAME_NOREPLACE,
        )
    };
    if r == 0 {
        return Ok(());
    }
    let e = io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EINVAL | libc::ENOSYS) => {
            std::fs::hard_link(from, to)?;
            std::fs::remove_file(from)
        }
        _ => Err(e),
    }
}

#[cfg(test)]
#[path = "recover_tests.rs"]
mod tests;
