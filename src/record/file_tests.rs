//! The file as a crash, a full disk and a normal close leave it.

use std::path::Path;
use std::sync::Arc;

use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel};
use mcap::records::Record;

use super::*;

pub(crate) const MS: u64 = 1_000_000;

/// A JSON channel in `ctx` (every sink of `ctx` gets its messages).
pub(crate) fn channel(ctx: &Arc<Context>) -> Arc<RawChannel> {
    ChannelBuilder::new("/t")
        .context(ctx)
        .message_encoding("json")
        .build_raw()
        .expect("channel")
}

/// Message `k`, at `k` ms: 200 bytes that compress poorly, so the file grows.
pub(crate) fn log(ch: &RawChannel, k: u64) {
    let mut x = k.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let noise: String = (0..180)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            char::from(b'a' + (x % 26) as u8)
        })
        .collect();
    let body = format!(r#"{{"k":{k},"n":"{noise}"}}"#);
    let meta = PartialMetadata {
        log_time: Some(k * MS),
    };
    ch.log_with_meta(body.as_bytes(), meta);
}

pub(crate) fn options(path: &Path, chunk_s: f64) -> McapOptions {
    McapOptions {
        chunk_duration_s: chunk_s,
        ..McapOptions::new(path)
    }
}

/// A file of `n` messages, one a ms, chunks of at most `chunk_s`, left open (as a
/// crash leaves it) or closed.
pub(crate) fn write(path: &Path, n: u64, chunk_s: f64, close: bool) -> McapFile {
    let ctx = Context::new();
    let mut f = McapFile::create(&options(path, chunk_s), &ctx, Arc::default()).expect("create");
    f.write_metadata("test", BTreeMap::from([("a".into(), "b".into())]))
        .expect("metadata");
    let ch = channel(&ctx);
    for k in 0..n {
        f.before_item(k * MS);
        log(&ch, k);
        f.item_written(k * MS);
    }
    if close {
        f.close().expect("close");
    }
    f
}

/// Message time spans of the complete chunks on the disk, read from the start until a
/// record fails (the end of a file that was not closed).
fn chunk_spans(path: &Path) -> Vec<(u64, u64)> {
    let bytes = std::fs::read(path).expect("read");
    mcap::read::LinearReader::new(&bytes)
        .expect("magic")
        .map_while(Result::ok)
        .filter_map(|r| match r {
            Record::Chunk { header, .. } => {
                Some((header.message_start_time, header.message_end_time))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn chunks_reach_the_disk_whole_within_the_chunk_duration() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("open.mcap");
    let f = write(&path, 500, 0.05, false);
    // Not closed, as after SIGKILL: every chunk but the open one is on the disk, whole.
    let spans = chunk_spans(&path);
    assert!(spans.len() >= 9, "{spans:?}");
    assert!(
        spans.iter().all(|(a, b)| b - a < 50 * MS),
        "a chunk spans 50 ms or more: {spans:?}"
    );
    let last = spans.last().expect("chunks").1;
    assert_eq!(f.complete_ns(), last, "what is on the disk is reported");
    assert!(499 * MS - last <= 50 * MS, "{last} ns on the disk");
    assert_eq!(f.state(), FileState::Writing);
}

#[test]
fn a_closed_file_is_finished_with_every_message() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("closed.mcap");
    let mut f = write(&path, 200, 1.0, true);
    assert_eq!(f.state(), FileState::Finished);
    assert_eq!(f.complete_ns(), 199 * MS);
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("a summary");
    assert_eq!(summary.stats.expect("statistics").message_count, 200);
    f.close().expect("closing again is fine");
}

#[test]
fn a_full_disk_leaves_an_unfinished_file_that_says_what_it_holds() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("full.mcap");
    let room = 64 * 1024;
    let ctx = Context::new();
    let opts = options(&path, 0.02);
    let mut f =
        McapFile::create_with_room(&opts, &ctx, Arc::default(), Some(room)).expect("create");
    let ch = channel(&ctx);
    let mut k = 0;
    while f.cap_reached(k * MS).is_none() {
        assert!(k < 100_000, "the disk never filled");
        f.before_item(k * MS);
        log(&ch, k);
        f.item_written(k * MS);
        k += 1;
    }
    assert_eq!(f.cap_reached(k * MS), Some(CapReason::WriteError));
    let complete = f.complete_ns();
    assert!(complete > 0 && complete < k * MS, "{complete} of {k} ms");

    let err = f.close().expect_err("the end cannot be written");
    assert_eq!(f.state(), FileState::Unfinished);
    let RecordError::Unfinished {
        complete_s, reason, ..
    } = &err
    else {
        panic!("{err:?}");
    };
    assert_eq!(*complete_s, complete as f64 * 1e-9);
    assert!(reason.contains("No space left"), "{reason}");
    let msg = err.to_string();
    assert!(
        msg.contains("was not finished") && msg.contains("snaked --recover"),
        "{msg}"
    );
    assert!(std::fs::metadata(&path).expect("size").len() <= room);
    assert!(matches!(f.close(), Err(RecordError::Unfinished { .. })));

    // What it holds: every message up to the reported time.
    let out = dir.path().join("full.recovered.mcap");
    let r = super::super::recover(&path, &out).expect("recover");
    let (_, last) = r.log_time_ns.expect("messages");
    assert!(last >= complete, "{last} < {complete}");
    assert_eq!(r.per_topic["/t"], last / MS + 1, "none missing");
}
