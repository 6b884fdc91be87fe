//! Recovery of a file cut short, and what it refuses.

use std::collections::BTreeMap;
use std::io;

use mcap::records::Record;

use super::*;
use crate::record::file::tests::{MS, write};

/// Names of the metadata records and every message's sequence, in file order.
fn contents(path: &Path) -> (BTreeMap<String, BTreeMap<String, String>>, Vec<u32>) {
    let bytes = std::fs::read(path).expect("read");
    let metadata = mcap::read::LinearReader::new(&bytes)
        .expect("an MCAP file")
        .map(|r| r.expect("a whole file"))
        .filter_map(|r| match r {
            Record::Metadata(m) => Some((m.name, m.metadata)),
            _ => None,
        })
        .collect();
    let sequences = mcap::MessageStream::new(&bytes)
        .expect("an MCAP file")
        .map(|m| m.expect("a message").sequence)
        .collect();
    (metadata, sequences)
}

/// `cut.mcap` in `dir`: a finished file of `n` messages cut to `keep(its length)` bytes.
fn cut(dir: &Path, n: u64, chunk_s: f64, keep: fn(usize) -> usize) -> PathBuf {
    let path = dir.join("cut.mcap");
    write(&path, n, chunk_s, true);
    let bytes = std::fs::read(&path).expect("read");
    std::fs::write(&path, &bytes[..keep(bytes.len())]).expect("cut");
    path
}

#[test]
fn a_cut_file_is_recovered_up_to_its_last_complete_chunk() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Cut in the middle, as a crash while a chunk was being written would.
    let cut = cut(dir.path(), 300, 0.02, |len| len / 2);

    let out = recovered_path(&cut);
    let r = recover(&cut, &out).expect("recover");
    assert!(!r.already_finished);
    assert!(r.chunks >= 3, "{r:?}");
    assert!(r.messages > 50 && r.messages < 300, "{r:?}");
    assert_eq!(r.per_topic["/t"], r.messages);
    assert!(r.lost_bytes > 0 && r.stopped.is_some(), "{r:?}");
    assert_eq!(r.log_time_ns, Some((0, (r.messages - 1) * MS)));

    // A finished file: summary, statistics, the messages in order, the metadata.
    let out_bytes = std::fs::read(&out).expect("read");
    let summary = mcap::Summary::read(&out_bytes)
        .expect("summary")
        .expect("a summary");
    assert_eq!(summary.stats.expect("statistics").message_count, r.messages);
    let (metadata, sequences) = contents(&out);
    assert_eq!(sequences, (1..=r.messages as u32).collect::<Vec<_>>());
    assert_eq!(metadata["test"]["a"], "b");
    let note = &metadata["snaked.recovery"];
    assert_eq!(note["messages"], r.messages.to_string());
    assert_eq!(note["lost_bytes"], r.lost_bytes.to_string());
    assert!(note["from"].ends_with("cut.mcap"));
}

#[test]
fn a_finished_file_is_left_alone() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    write(&path, 20, 1.0, true);
    let out = dir.path().join("out.mcap");
    let r = recover(&path, &out).expect("recover");
    assert!(r.already_finished);
    assert!(!out.exists());
}

#[test]
fn an_existing_output_is_not_overwritten_and_other_files_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = cut(dir.path(), 20, 0.005, |len| len - 50);
    let out = dir.path().join("taken.mcap");
    std::fs::write(&out, b"keep").expect("write");
    let err = recover(&path, &out).expect_err("exists");
    assert!(matches!(err, RecoverError::Create { .. }), "{err:?}");
    assert_eq!(std::fs::read(&out).expect("read"), b"keep");

    let text = dir.path().join("notes.txt");
    std::fs::write(&text, b"not a recording").expect("write");
    let err = recover(&text, &dir.path().join("x.mcap")).expect_err("not MCAP");
    assert!(matches!(err, RecoverError::NotMcap { .. }), "{err:?}");
    assert!(err.to_string().contains("notes.txt"), "{err}");
    let missing = dir.path().join("missing.mcap");
    let err = recover(&missing, &dir.path().join("y.mcap")).expect_err("missing");
    assert!(matches!(err, RecoverError::Read { .. }), "{err:?}");
}

#[test]
fn the_recovered_file_sits_beside_the_input() {
    assert_eq!(
        recovered_path(Path::new("/var/lib/snaked/run-1.mcap")),
        Path::new("/var/lib/snaked/run-1.recovered.mcap")
    );
}

// Files refused, and what is left after a failure.

/// How many files `dir` holds: the input alone, after a failure (no output, no partial
/// file).
fn files(dir: &Path) -> usize {
    std::fs::read_dir(dir).expect("read_dir").count()
}

#[test]
fn only_the_magic_is_blamed_on_the_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("magic.mcap");
    std::fs::write(&path, mcap::MAGIC).expect("write");
    let err = recover(&path, &dir.path().join("out.mcap")).expect_err("nothing");
    assert!(matches!(err, RecoverError::Nothing { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("magic.mcap") && msg.contains("only the MCAP magic"),
        "{msg}"
    );
    assert!(!msg.contains("out.mcap"), "{msg}");
    assert_eq!(files(dir.path()), 1);
}

#[test]
fn a_file_without_a_complete_chunk_has_nothing_to_recover() {
    let dir = tempfile::tempdir().expect("tempdir");
    // One chunk (10 s of chunk, 300 ms of messages), cut in its middle.
    let path = cut(dir.path(), 300, 10.0, |len| len / 2);
    let out = dir.path().join("out.mcap");
    let err = recover(&path, &out).expect_err("nothing");
    let msg = err.to_string();
    assert!(matches!(err, RecoverError::Nothing { .. }), "{err:?}");
    assert!(
        msg.contains("no complete chunk") && msg.contains("cut.mcap"),
        "{msg}"
    );
    assert_eq!(files(dir.path()), 1, "no empty 'finished' file");
}

#[test]
fn a_directory_is_refused() {
    // A FIFO too, at once (`tests/integration/record/recover.rs`, through snaked).
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.mcap");
    let err = recover(dir.path(), &out).expect_err("a directory");
    assert!(
        matches!(
            err,
            RecoverError::NotAFile {
                kind: "a directory",
                ..
            }
        ),
        "{err:?}"
    );
    assert!(!out.exists());
}

/// A disk with room for `room` bytes.
struct Full {
    room: usize,
}

impl io::Write for Full {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.room == 0 {
            return Err(io::Error::from_raw_os_error(libc::ENOSPC));
        }
        let n = buf.len().min(self.room);
        self.room -= n;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_full_output_disk_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = cut(dir.path(), 3000, 0.02, |len| len - 100);
    let mut input = File::open(&path).expect("open");
    let len = input.metadata().expect("len").len();
    let out = Path::new("/media/full/out.mcap");
    let Err(err) = copy::copy(&mut input, len, &path, out, Full { room: 16 * 1024 }) else {
        panic!("the disk filled");
    };
    assert!(matches!(err, RecoverError::Write { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("cannot write /media/full/out.mcap")
            && msg.contains("No space left on device")
            && msg.contains("ENOSPC"),
        "{msg}"
    );
}
