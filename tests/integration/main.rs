//! The integration tests, one binary: linking the daemon, rapier and foxglove once
//! rather than once per test file is most of what a cold CI run spends
//! (docs/measurements/lab-and-ci.md). A folder per concern; `support` is shared.
//!
//! One group: `cargo test --test integration socket::`; one test: its full path.

mod alloc;
mod daemon;
mod emu;
mod hebi;
mod hil;
mod lab;
mod protocol;
mod record;
mod ros2;
mod socket;
mod structure;
mod support;
mod systemd;
mod world;
