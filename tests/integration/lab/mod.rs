//! `snake-lab` as a user runs it.

mod cli;
mod crossing;
mod protocol;
mod shard;
mod slurm;

use std::path::Path;
use std::process::{Command, Output};

/// `snake-lab ARGS`, run to its end.
fn lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_snake-lab"))
        .args(args)
        .output()
        .expect("snake-lab runs")
}

/// `snake-lab` with the words of `line` then `extra` (paths), which must succeed.
fn lab_ok(line: &str, extra: &[&str]) -> Output {
    let mut args: Vec<&str> = line.split_whitespace().collect();
    args.extend_from_slice(extra);
    let o = lab(&args);
    assert!(
        o.status.success(),
        "snake-lab {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
