//! Recovery: a finished file (summary, index, footer) made of one that a crash, a power
//! loss or a full disk left without its end, as `mcap recover` does. The file is read
//! from the start; every complete chunk's messages and every metadata record are
//! written to a new file (the old one is never touched), and reading stops at the
//! first record that is cut short or does not check out: the chunk that was being
//! written. `snaked --recover` runs it.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use mcap::records::{MessageHeader, Record};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::write::NoSeek;
use mcap::{McapError, WriteOptions, Writer};

/// Chunk size of the recovered file, bytes (uncompressed), as the recorder writes.
const CHUNK: u64 = 1024 * 1024;

/// Why a recovery could not be done.
#[derive(Debug, thiserror::Error)]
pub enum RecoverError {
    #[error("cannot read {}: {reason}", path.display())]
    Read { path: PathBuf, reason: io::Error },
    #[error("{} is not an MCAP file (it does not start with the MCAP magic)", path.display())]
    NotMcap { path: PathBuf },
    #[error("cannot create {}: {reason}", path.display())]
    Create { path: PathBuf, reason: io::Error },
    #[error("cannot write {}: {reason}", path.display())]
    Write { path: PathBuf, reason: McapError },
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
/// that already ends with its footer is left alone (`already_finished`).
pub fn recover(input: &Path, output: &Path) -> Result<Recovery, RecoverError> {
    let read_err = |reason| RecoverError::Read {
        path: input.to_path_buf(),
        reason,
    };
    let mut file = File::open(input).map_err(read_err)?;
    let len = file.metadata().map_err(read_err)?.len();
    let mut magic = [0u8; 8];
    file.read_exact(&mut magic)
        .map_err(|_| RecoverError::NotMcap {
            path: input.to_path_buf(),
        })?;
    if magic != mcap::MAGIC {
        return Err(RecoverError::NotMcap {
            path: input.to_path_buf(),
        });
    }
    if ends_finished(&mut file, len).map_err(read_err)? {
        return Ok(Recovery {
            already_finished: true,
            ..Recovery::default()
        });
    }
    file.seek(SeekFrom::Start(0)).map_err(read_err)?;
    let out = File::create_new(output).map_err(|reason| RecoverError::Create {
        path: output.to_path_buf(),
        reason,
    })?;
    let mut copy = Copy {
        out: Some(out),
        writer: None,
        rec: Recovery::default(),
        channels: BTreeMap::new(),
    };
    let write_err = |reason| RecoverError::Write {
        path: output.to_path_buf(),
        reason,
    };
    let done = match copy.run(&mut file, len) {
        Ok(()) => copy.finish(input).map_err(write_err),
        Err(Stop::Input(McapError::Io(e))) => Err(read_err(e)),
        Err(Stop::Input(e) | Stop::Output(e)) => Err(write_err(e)),
    };
    if done.is_err() {
        // A half-written copy would only mislead.
        let _ = std::fs::remove_file(output);
    }
    done.map(|()| copy.rec)
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

type Out = Writer<NoSeek<BufWriter<File>>>;

/// The copy in progress.
struct Copy {
    /// The output file until the input's header is read (the writer writes its header
    /// with the input's profile).
    out: Option<File>,
    writer: Option<Out>,
    rec: Recovery,
    /// Topic of each channel id.
    channels: BTreeMap<u16, String>,
}

impl Copy {
    /// Reads `input` record by record until its data section ends or a record fails.
    /// Only reading the file itself is an error; a record that fails ends the copy.
    fn run(&mut self, input: &mut File, len: u64) -> Result<(), Stop> {
        // A length beyond the file (a chunk that never got its length) fails at once.
        let limit = usize::try_from(len).unwrap_or(usize::MAX);
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_emit_chunks(true)
                .with_record_length_limit(limit),
        );
        // The reader asks for exactly the bytes of the record it reads: after a record,
        // everything fed so far is complete.
        let (mut fed, mut complete) = (0u64, 0u64);
        while let Some(event) = reader.next_event() {
            let record = match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let n = input
                        .read(reader.insert(need))
                        .map_err(|e| Stop::Input(McapError::Io(e)))?;
                    reader.notify_read(n);
                    fed += n as u64;
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => mcap::parse_record(opcode, data),
                Err(e) => Err(e),
            };
            match record.map_err(Stop::Input).and_then(|r| self.record(r)) {
                Ok(end) => {
                    complete = fed;
                    if end {
                        break;
                    }
                }
                Err(Stop::Input(e)) => {
                    self.rec.stopped = Some(e.to_string());
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        self.rec.lost_bytes = len.saturating_sub(complete);
        Ok(())
    }

    /// Copies one record; `Ok(true)` at the end of the data section.
    fn record(&mut self, record: Record<'_>) -> Result<bool, Stop> {
        match record {
            Record::Header(h) => {
                let Some(out) = self.out.take() else {
                    return Ok(false); // a second header: nothing to copy
                };
                let options = WriteOptions::new()
                    .profile(h.profile)
                    .compression(Some(mcap::Compression::Zstd))
                    .chunk_size(Some(CHUNK))
                    .disable_seeking(true);
                self.writer = Some(
                    options
                        .create(NoSeek::new(BufWriter::new(out)))
                        .map_err(Stop::Output)?,
                );
            }
            Record::Chunk { header, data } => {
                // Decompressed and checked whole before any of it is copied.
                let inner: Vec<Record<'_>> = mcap::read::ChunkReader::new(header, &data)
                    .map_err(Stop::Input)?
                    .collect::<Result<_, _>>()
                    .map_err(Stop::Input)?;
                for r in inner {
                    self.record(r)?;
                }
                self.rec.chunks += 1;
            }
            Record::DataEnd(_) | Record::Footer(_) => return Ok(true),
            r => self.copy(r)?,
        }
        Ok(false)
    }

    fn copy(&mut self, record: Record<'_>) -> Result<(), Stop> {
        if self.writer.is_none() {
            // Records before a header: not an MCAP file we can copy.
            return Err(Stop::Input(McapError::UnexpectedEof));
        }
        self.copy_into(record).map_err(Stop::Output)
    }

    fn copy_into(&mut self, record: Record<'_>) -> Result<(), McapError> {
        let w = self.writer.as_mut().expect("checked by copy");
        match record {
            Record::Schema { header, data } => {
                w.add_schema_with_id(header.id, &header.name, &header.encoding, &data)?;
            }
            Record::Channel(c) => {
                w.add_channel_with_id(
                    c.id,
                    c.schema_id,
                    &c.topic,
                    &c.message_encoding,
                    &c.metadata,
                )?;
                self.channels.insert(c.id, c.topic);
            }
            Record::Message { header, data } => {
                w.write_to_known_channel(&header, &data)?;
                self.count(&header);
            }
            Record::Metadata(m) => w.write_metadata(&m)?,
            Record::Attachment { header, data, .. } => w.attach(&mcap::Attachment {
                log_time: header.log_time,
                create_time: header.create_time,
                name: header.name,
                media_type: header.media_type,
                data,
            })?,
            // Indexes and statistics are rebuilt by the writer.
            _ => {}
        }
        Ok(())
    }

    fn count(&mut self, h: &MessageHeader) {
        let rec = &mut self.rec;
        rec.messages += 1;
        let topic = self
            .channels
            .get(&h.channel_id)
            .cloned()
            .unwrap_or_default();
        *rec.per_topic.entry(topic).or_insert(0) += 1;
        rec.log_time_ns = Some(match rec.log_time_ns {
            None => (h.log_time, h.log_time),
            Some((a, b)) => (a.min(h.log_time), b.max(h.log_time)),
        });
    }

    /// Notes the recovery in the file, writes its summary and footer, syncs.
    fn finish(&mut self, input: &Path) -> Result<(), McapError> {
        let Some(mut w) = self.writer.take() else {
            return Err(McapError::UnexpectedEof);
        };
        let r = &self.rec;
        let note = BTreeMap::from([
            ("from".to_owned(), input.display().to_string()),
            ("chunks".to_owned(), r.chunks.to_string()),
            ("messages".to_owned(), r.messages.to_string()),
            ("lost_bytes".to_owned(), r.lost_bytes.to_string()),
            ("stopped".to_owned(), r.stopped.clone().unwrap_or_default()),
        ]);
        w.write_metadata(&mcap::records::Metadata {
            name: "snaked.recovery".into(),
            metadata: note,
        })?;
        w.finish()?;
        let file = w
            .into_inner()
            .into_inner()
            .into_inner()
            .map_err(|e| e.into_error())?;
        file.sync_all()?;
        Ok(())
    }
}

/// Why copying stopped: the input's end (expected after a crash; only a failed read of
/// the file is an error) or a failed write.
enum Stop {
    Input(McapError),
    Output(McapError),
}

#[cfg(test)]
#[path = "recover_tests.rs"]
mod tests;
