//! The copy behind [`super::recover`]: the input read record by record, each chunk
//! checked whole (its declared size within [`RECOVER_MAX_CHUNK_BYTES`], decompressed no further
//! than it declares, every record parsed, its CRC) before any of it is copied, and the
//! output written through the `mcap` crate's writer as it goes.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use mcap::records::{MessageHeader, Record, op};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::write::NoSeek;
use mcap::{McapError, WriteOptions, Writer};

use super::{RECOVER_MAX_CHUNK_BYTES, RecoverError, Recovery};

/// A record's opcode and length fields, bytes.
const PREFIX: u64 = 9;

/// Copies the complete part of `input` (`len` bytes, read from its start, the magic
/// already checked) into `out` as a finished file, and hands `out` back. `from` names
/// the input (in errors and the file's note), `to` the output (in errors).
pub(super) fn copy<R: Read, W: Write>(
    input: &mut R,
    len: u64,
    from: &Path,
    to: &Path,
    out: W,
) -> Result<(Recovery, W), RecoverError> {
    let failed = Rc::new(RefCell::new(None));
    let mut c = Copy {
        from: from.to_path_buf(),
        out: Some(Noting {
            inner: out,
            failed: failed.clone(),
        }),
        writer: None,
        failed,
        rec: Recovery::default(),
        channels: BTreeMap::new(),
    };
    let stopped = c.run(input, len).and_then(|()| {
        if c.rec.messages == 0 {
            return Err(Stop::Refused(RecoverError::Nothing {
                path: from.to_path_buf(),
                why: c.nothing(len),
            }));
        }
        c.finish()
    });
    match stopped {
        Ok(out) => Ok((c.rec, out)),
        Err(Stop::Read(reason)) => Err(RecoverError::Read {
            path: from.to_path_buf(),
            reason,
        }),
        Err(Stop::Output(reason)) => Err(RecoverError::Write {
            path: to.to_path_buf(),
            reason,
        }),
        Err(Stop::Refused(e)) => Err(e),
        // Only from writing the summary: the writer's own complaint.
        Err(Stop::Input(why)) => Err(RecoverError::Write {
            path: to.to_path_buf(),
            reason: io::Error::other(why),
        }),
    }
}

/// Why copying stopped.
enum Stop {
    /// The input ends here or does not check out: expected after a crash, the copy
    /// ends and keeps what came before.
    Input(String),
    /// Reading the input failed.
    Read(io::Error),
    /// Writing the output failed.
    Output(io::Error),
    /// The input is refused whole (a chunk or a record past the limits, nothing in it).
    Refused(RecoverError),
}

/// The output, keeping the first error a write met: the `mcap` writer wraps it in an
/// error that does not say what it was (ENOSPC, EFBIG...).
struct Noting<W> {
    inner: W,
    failed: Rc<RefCell<Option<io::Error>>>,
}

impl<W: Write> Write for Noting<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.inner.write(buf).inspect_err(|e| self.note(e))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush().inspect_err(|e| self.note(e))
    }
}

impl<W> Noting<W> {
    fn note(&self, e: &io::Error) {
        if e.kind() != io::ErrorKind::Interrupted {
            self.failed.borrow_mut().get_or_insert_with(|| same(e));
        }
    }
}

/// An `io::Error` like `e` (it is not `Clone`).
fn same(e: &io::Error) -> io::Error {
    match e.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code),
        None => io::Error::new(e.kind(), e.to_string()),
    }
}

type Out<W> = Writer<NoSeek<Noting<W>>>;

/// The copy in progress.
struct Copy<W: Write> {
    from: PathBuf,
    /// The output until the input's header is read (the writer writes its header with
    /// the input's profile).
    out: Option<Noting<W>>,
    writer: Option<Out<W>>,
    /// The first error a write of the output met.
    failed: Rc<RefCell<Option<io::Error>>>,
    rec: Recovery,
    /// Topic of each channel id.
    channels: BTreeMap<u16, String>,
}

impl<W: Write> Copy<W> {
    /// Reads `input` record by record until its data section ends or a record fails
    /// (`rec.stopped` says why). Only reading the file, writing the output and a
    /// refusal are errors.
    fn run<R: Read>(&mut self, input: &mut R, len: u64) -> Result<(), Stop> {
        // A length beyond the file (a chunk that never got its length) fails at once, and
        // none beyond the limit is ever buffered.
        let limit = usize::try_from(len.min(RECOVER_MAX_CHUNK_BYTES)).unwrap_or(usize::MAX);
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_emit_chunks(true)
                .with_record_length_limit(limit),
        );
        // The reader asks for exactly the bytes of the record it reads: after a record,
        // everything fed so far is complete (the magic was checked before).
        let (mut fed, mut complete) = (0u64, mcap::MAGIC.len() as u64);
        while let Some(event) = reader.next_event() {
            let done = match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let n = read(input, reader.insert(need)).map_err(Stop::Read)?;
                    reader.notify_read(n);
                    fed += n as u64;
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => self.record(opcode, data, complete),
                // Within the file, but longer than the limit: refused, not taken for the
                // torn end.
                Err(McapError::RecordTooLarge { opcode, len: n })
                    if n.saturating_add(PREFIX) <= len.saturating_sub(complete) =>
                {
                    Err(Stop::Refused(RecoverError::RecordTooLarge {
                        path: self.from.clone(),
                        offset: complete,
                        opcode,
                        len: n,
                        limit: RECOVER_MAX_CHUNK_BYTES,
                    }))
                }
                Err(e) => Err(Stop::Input(e.to_string())),
            };
            match done {
                Ok(end) => {
                    complete = fed;
                    if end {
                        break;
                    }
                }
                Err(Stop::Input(why)) => {
                    self.rec.stopped = Some(why);
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        self.rec.lost_bytes = len.saturating_sub(complete);
        Ok(())
    }

    /// Copies one record (a chunk's messages); `Ok(true)` at the end of the data section.
    fn record(&mut self, opcode: u8, data: &[u8], offset: u64) -> Result<bool, Stop> {
        let input = |e: McapError| Stop::Input(e.to_string());
        if opcode == op::CHUNK {
            return self.chunk(data, offset).map(|()| false);
        }
        match mcap::parse_record(opcode, data).map_err(input)? {
            Record::Header(h) => {
                let Some(out) = self.out.take() else {
                    return Ok(false); // a second header: nothing to copy
                };
                let options = WriteOptions::new()
                    .profile(h.profile)
                    .compression(Some(mcap::Compression::Zstd))
                    .chunk_size(Some(super::super::file::MAX_CHUNK))
                    .disable_seeking(true);
                let writer = options.create(NoSeek::new(out));
                self.writer = Some(writer.map_err(|e| self.written(e))?);
            }
            Record::DataEnd(_) | Record::Footer(_) => return Ok(true),
            r => self.copy(r)?,
        }
        Ok(false)
    }

    /// A chunk: its declared size checked, decompressed and checked whole, then copied.
    fn chunk(&mut self, body: &[u8], offset: u64) -> Result<(), Stop> {
        let at = |e: McapError| Stop::Input(format!("the chunk at byte {offset}: {e}"));
        let Record::Chunk { header, .. } = mcap::parse_record(op::CHUNK, body).map_err(at)? else {
            unreachable!("a chunk's opcode parses as a chunk");
        };
        if header.uncompressed_size > RECOVER_MAX_CHUNK_BYTES {
            return Err(Stop::Refused(RecoverError::ChunkTooLarge {
                path: self.from.clone(),
                offset,
                declared: header.uncompressed_size,
                limit: RECOVER_MAX_CHUNK_BYTES,
            }));
        }
        let raw = unpack(body).map_err(at)?;
        for (opcode, data) in records(&raw) {
            // Parsed once already: cannot fail.
            let r = mcap::parse_record(opcode, data).map_err(at)?;
            if matches!(
                r,
                Record::Schema { .. } | Record::Channel(_) | Record::Message { .. }
            ) {
                self.copy(r)?;
            }
        }
        self.rec.chunks += 1;
        Ok(())
    }

    fn copy(&mut self, record: Record<'_>) -> Result<(), Stop> {
        if self.writer.is_none() {
            return Err(Stop::Input("a record before the header".into()));
        }
        self.copy_into(record).map_err(|e| self.written(e))
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

    /// What a failed call of the writer means: the output's fault if a write failed
    /// (with that write's error), the input's if its records disagree (a message on a
    /// channel never defined...).
    fn written(&self, e: McapError) -> Stop {
        if let Some(io) = self.failed.borrow().as_ref() {
            return Stop::Output(same(io));
        }
        match e {
            McapError::Io(io) => Stop::Output(io),
            McapError::InvalidSchemaId
            | McapError::ConflictingSchemas(_)
            | McapError::ConflictingChannels(_)
            | McapError::UnknownSchema(..)
            | McapError::UnknownChannel(..)
            | McapError::TooManyChannels
            | McapError::TooManySchemas => Stop::Input(e.to_string()),
            e => Stop::Output(io::Error::other(e.to_string())),
        }
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

    /// Why there is nothing to recover from a file of `len` bytes.
    fn nothing(&self, len: u64) -> String {
        let r = &self.rec;
        let found = match r.chunks {
            0 if len == mcap::MAGIC.len() as u64 => {
                return "it holds only the MCAP magic (8 bytes), no record".into();
            }
            0 => format!("no complete chunk in its {len} bytes"),
            n => format!("no message in its {n} complete chunks"),
        };
        match &r.stopped {
            // Cut at a record's end: nothing more to say.
            Some(_) if r.lost_bytes == 0 => found,
            Some(why) => format!(
                "{found} (reading stopped at byte {}: {why})",
                len - r.lost_bytes
            ),
            None => found,
        }
    }

    /// Notes the recovery in the file, writes its summary and footer, and hands the
    /// output back.
    fn finish(&mut self) -> Result<W, Stop> {
        let r = &self.rec;
        let note = BTreeMap::from([
            ("from".to_owned(), self.from.display().to_string()),
            ("chunks".to_owned(), r.chunks.to_string()),
            ("messages".to_owned(), r.messages.to_string()),
            ("lost_bytes".to_owned(), r.lost_bytes.to_string()),
            ("stopped".to_owned(), r.stopped.clone().unwrap_or_default()),
        ]);
        let mut w = self.writer.take().expect("messages were copied through it");
        let finished = w
            .write_metadata(&mcap::records::Metadata {
                name: "snaked.recovery".into(),
                metadata: note,
            })
            .and_then(|()| w.finish().map(drop));
        finished.map_err(|e| self.written(e))?;
        Ok(w.into_inner().into_inner().inner)
    }
}

/// Reads into `buf`, again when interrupted.
fn read<R: Read>(input: &mut R, buf: &mut [u8]) -> io::Result<usize> {
    loop {
        match input.read(buf) {
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            r => return r,
        }
    }
}

/// A chunk record's body → its records (opcode, length, data, as in the file), every
/// one parsed and the chunk's CRC checked. Decompressed as the `mcap` crate's reader
/// does, which stops at the size the chunk declares: what this holds is at most that.
fn unpack(body: &[u8]) -> Result<Vec<u8>, McapError> {
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(RECOVER_MAX_CHUNK_BYTES as usize),
    );
    let mut prefix = [0u8; PREFIX as usize];
    prefix[0] = op::CHUNK;
    prefix[1..].copy_from_slice(&(body.len() as u64).to_le_bytes());
    let mut src = (&prefix[..]).chain(body);
    let mut raw = Vec::new();
    while let Some(event) = reader.next_event() {
        match event? {
            LinearReadEvent::ReadRequest(need) => {
                let n = src.read(reader.insert(need))?;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                mcap::parse_record(opcode, data)?;
                raw.push(opcode);
                raw.extend_from_slice(&(data.len() as u64).to_le_bytes());
                raw.extend_from_slice(data);
            }
        }
    }
    Ok(raw)
}

/// The records [`unpack`] laid out: (opcode, data).
fn records(raw: &[u8]) -> impl Iterator<Item = (u8, &[u8])> {
    let mut rest = raw;
    std::iter::from_fn(move || {
        let (&opcode, after) = rest.split_first()?;
        let (len, after) = after.split_first_chunk::<8>()?;
        let (data, next) = after.split_at(u64::from_le_bytes(*len) as usize);
        rest = next;
        Some((opcode, data))
    })
}
