//! Recording every run: the loop pushes `Copy` items ([`cycle::RecordItem`]) into a
//! bounded lock-free ring; a writer thread encodes them as MCAP (and serves them live
//! over the Foxglove WebSocket protocol). See `docs/recording.md`.

pub mod cycle;

pub use cycle::{
    CycleRecord, JointSample, RECORD_MAX_LINKS, RECORD_MAX_MODULES, RecordEvent, RecordItem,
};
