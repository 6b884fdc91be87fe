//! `snake-lab` as a user runs it.

mod cli;
mod crossing;
mod shard;

use std::path::Path;
use std::process::{Command, Output};

/// `snake-lab ARGS`, run to its end.
fn lab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_snake-lab"))
        .args(args)
        .output()
        .expect("snake-lab runs")
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
