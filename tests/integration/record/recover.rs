//! `snaked --recover` against crafted files: a chunk that expands to 4 GiB, one that
//! expands past what it declares, a record past the limit after good chunks, a file of
//! only the magic, a FIFO. Each is refused or stopped at once with the input named, and
//! no output (not even an empty or partial one) is left to block a rerun.

use crate::support::record_fixture as fixture;
use crate::support::rig::exe;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use fixture::*;
use mcap::records::op;
use snaked::record::{
    McapOptions, RECOVER_MAX_CHUNK_BYTES, RecordOptions, RecoverError, recover, recovered_path,
    start,
};

/// A record as it is in a file: opcode, length, body.
fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
    let mut r = vec![opcode];
    r.extend_from_slice(&(body.len() as u64).to_le_bytes());
    r.extend_from_slice(body);
    r
}

/// A chunk record of `compressed` bytes (zstd) that declares `uncompressed` bytes (no
/// CRC).
fn chunk(uncompressed: u64, compressed: &[u8]) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(&0u64.to_le_bytes()); // message start time
    b.extend_from_slice(&0u64.to_le_bytes()); // message end time
    b.extend_from_slice(&uncompressed.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes()); // CRC 0: not checked
    b.extend_from_slice(&4u32.to_le_bytes());
    b.extend_from_slice(b"zstd");
    b.extend_from_slice(&(compressed.len() as u64).to_le_bytes());
    b.extend_from_slice(compressed);
    record(op::CHUNK, &b)
}

/// A zstd frame of `blocks` RLE blocks of 128 KiB of zeros each: 4 bytes a block, so
/// 4 GiB fits in 128 KiB (how a 209 KB file expanded to gigabytes).
fn zeros_zstd(blocks: u32) -> Vec<u8> {
    const BLOCK: u32 = 128 * 1024;
    // Magic; frame header descriptor (no size, no checksum); window 128 KiB.
    let mut z = vec![0x28, 0xB5, 0x2F, 0xFD, 0x00, 0x38];
    for k in 0..blocks {
        let last = u32::from(k + 1 == blocks);
        let header = last | (1 << 1) | (BLOCK << 3); // an RLE block of BLOCK bytes
        z.extend_from_slice(&header.to_le_bytes()[..3]);
        z.push(0);
    }
    z
}

/// 4 GiB of zeros, compressed.
fn four_gib() -> Vec<u8> {
    zeros_zstd(32 * 1024)
}

/// The magic and a header record: a file's start.
fn start_of_file() -> Vec<u8> {
    let mut header = Vec::new();
    for s in ["", "crafted"] {
        header.extend_from_slice(&(s.len() as u32).to_le_bytes());
        header.extend_from_slice(s.as_bytes());
    }
    let mut bytes = mcap::MAGIC.to_vec();
    bytes.extend(record(op::HEADER, &header));
    bytes
}

/// `dir/name`: a recording of the scripted run in chunks of 50 ms, its end cut off as a
/// crash leaves it (up to its data end record), followed by `tail`.
fn recorded_then(dir: &Path, name: &str, tail: &[u8]) -> PathBuf {
    let path = dir.join(name);
    let (catalog, id) = catalog();
    let items = run(1000, id, false);
    let opts = RecordOptions {
        mcap: Some(McapOptions {
            chunk_duration_s: 0.05,
            ..McapOptions::new(&path)
        }),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    push_all(&tx, &items);
    rec.finish().expect("finish");
    let mut bytes = std::fs::read(&path).expect("read");
    let mut at = mcap::MAGIC.len();
    while bytes[at] != op::DATA_END {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().expect("8 bytes"));
        at += 9 + len as usize;
    }
    bytes.truncate(at);
    bytes.extend_from_slice(tail);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// What `dir` holds, by name.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

/// `snaked --recover ARGS`: its output and how long it took.
fn snaked_recover(args: &[&Path]) -> (Output, Duration) {
    let t = Instant::now();
    let out = Command::new(exe("snaked"))
        .arg("--recover")
        .args(args)
        .env("RUST_LOG", "off")
        .output()
        .expect("snaked --recover");
    (out, t.elapsed())
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_chunk_declaring_4_gib_is_refused_at_once_naming_it_and_nothing_is_left() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bomb = chunk(1 << 32, &four_gib());
    let path = recorded_then(dir.path(), "bomb.mcap", &bomb);
    let offset = std::fs::metadata(&path).expect("size").len() - bomb.len() as u64;

    let err = recover(&path, &recovered_path(&path)).expect_err("refused");
    let RecoverError::ChunkTooLarge {
        offset: at,
        declared,
        limit,
        ..
    } = &err
    else {
        panic!("{err:?}");
    };
    assert_eq!(
        (*at, *declared, *limit),
        (offset, 1 << 32, RECOVER_MAX_CHUNK_BYTES)
    );

    // The command, twice: the same refusal, nothing written either time.
    for _ in 0..2 {
        let (out, took) = snaked_recover(&[&path]);
        let text = stderr(&out);
        println!("{took:?}: {text}");
        assert_eq!(out.status.code(), Some(1), "{text}");
        for needle in [
            "bomb.mcap",
            &format!("chunk at byte {offset}"),
            "declares 4294967296 bytes",
            &RECOVER_MAX_CHUNK_BYTES.to_string(),
        ] {
            assert!(text.contains(needle), "{needle:?} in {text}");
        }
        // Refused on the chunk's header, before any of it is decompressed: far below
        // the minutes (and the gigabytes) expanding it took. Generous for a busy machine.
        assert!(took < Duration::from_secs(20), "{took:?}");
        assert_eq!(
            names(dir.path()),
            ["bomb.mcap"],
            "no output, no partial file"
        );
    }
}

#[test]
fn a_chunk_is_never_decompressed_past_what_it_declares() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Declares 900 kB, expands to 4 GiB: read to 900 kB (zero-length records of opcode
    // 0, 9 bytes each: no message) and no further.
    let path = dir.path().join("bomb.mcap");
    let mut bytes = start_of_file();
    bytes.extend(chunk(900_000, &four_gib()));
    std::fs::write(&path, bytes).expect("write");
    let t = Instant::now();
    let err = recover(&path, &dir.path().join("out.mcap")).expect_err("no message");
    assert!(t.elapsed() < Duration::from_secs(20), "{:?}", t.elapsed());
    assert!(matches!(err, RecoverError::Nothing { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("no message in its 1 complete chunks"), "{msg}");
    assert_eq!(names(dir.path()), ["bomb.mcap"]);
}

#[test]
fn a_record_past_the_limit_after_good_chunks_leaves_no_output_and_a_rerun_works() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A metadata record, whole in the file but longer than the limit.
    let big = record(
        op::METADATA,
        &vec![0u8; RECOVER_MAX_CHUNK_BYTES as usize + 1],
    );
    let path = recorded_then(dir.path(), "run.mcap", &big);
    let offset = std::fs::metadata(&path).expect("size").len() - big.len() as u64;
    let out = recovered_path(&path);
    let err = recover(&path, &out).expect_err("past the limit");
    assert!(
        matches!(err, RecoverError::RecordTooLarge { offset: o, .. } if o == offset),
        "{err:?}"
    );
    // The good chunks were being written: the partial file is gone with the failure.
    assert_eq!(names(dir.path()), ["run.mcap"]);

    // Cut short by a byte, it is the torn end of a crash: the chunks before are kept.
    let bytes = std::fs::read(&path).expect("read");
    std::fs::write(&path, &bytes[..bytes.len() - 1]).expect("cut");
    let (done, _) = snaked_recover(&[&path]);
    let text = String::from_utf8_lossy(&done.stdout);
    assert!(done.status.success(), "{text}{}", stderr(&done));
    assert!(
        text.contains("not finished") && text.contains("wrote"),
        "{text}"
    );
    let r = recover(&path, &dir.path().join("again.mcap")).expect("recover");
    assert!(r.chunks >= 10 && r.messages > 1000, "{r:?}");
    assert_eq!(r.lost_bytes, big.len() as u64 - 1);
    assert_eq!(
        names(dir.path()),
        ["again.mcap", "run.mcap", "run.recovered.mcap"]
    );
}

#[test]
fn files_with_nothing_to_recover_are_blamed_on_the_input_and_exit_non_zero() {
    let dir = tempfile::tempdir().expect("tempdir");
    let magic = dir.path().join("magic.mcap");
    std::fs::write(&magic, mcap::MAGIC).expect("write");
    let header_only = dir.path().join("header.mcap");
    std::fs::write(&header_only, start_of_file()).expect("write");
    let out = dir.path().join("out.mcap");
    for (input, why) in [
        (&magic, "only the MCAP magic"),
        (&header_only, "no complete chunk"),
    ] {
        let (done, _) = snaked_recover(&[input, &out]);
        let text = stderr(&done);
        assert_eq!(done.status.code(), Some(1), "{text}");
        assert!(
            text.contains(&*input.to_string_lossy()) && text.contains("nothing to recover"),
            "{text}"
        );
        assert!(text.contains(why), "{why:?} in {text}");
        assert!(
            !text.contains("cannot write"),
            "the output is not to blame: {text}"
        );
        assert!(String::from_utf8_lossy(&done.stdout).is_empty());
    }
    assert_eq!(names(dir.path()), ["header.mcap", "magic.mcap"]);
}

#[test]
fn a_fifo_is_refused_at_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("pipe.mcap");
    let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).expect("path");
    // SAFETY: a NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    let mut child = Command::new(exe("snaked"))
        .arg("--recover")
        .arg(&fifo)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    // Before, it waited for a writer forever: kill it past a generous bound.
    let t = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if t.elapsed() > Duration::from_secs(20) {
            child.kill().expect("kill");
            panic!("snaked --recover FIFO still waits after {:?}", t.elapsed());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let done = child.wait_with_output().expect("output");
    let text = stderr(&done);
    assert_eq!(done.status.code(), Some(1), "{text}");
    assert!(
        text.contains("pipe.mcap") && text.contains("a FIFO"),
        "{text}"
    );
    assert_eq!(names(dir.path()), ["pipe.mcap"]);
}
