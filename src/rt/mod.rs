//! The real-time side: pacing, the 1 kHz loop, its statistics and the messages
//! and telemetry that connect it to the rest of the daemon.

pub mod compliance;
pub mod compliance_json;
pub mod control_loop;
pub mod harness;
pub mod messages;
pub mod pacer;
pub mod slithering_driver;
pub mod stats;
pub mod sys;
pub mod telemetry;
