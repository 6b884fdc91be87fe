//! The real-time side: pacing, the 1 kHz loop, its statistics and the messages
//! and telemetry that connect it to the rest of the daemon.

pub mod channels;
pub mod control_loop;
pub mod controller_slots;
pub mod gait_clock;
pub mod harness;
pub mod messages;
pub mod observer;
pub mod pacer;
pub mod setpoint_guard;
pub mod stats;
pub mod sys;
pub mod telemetry;

#[cfg(test)]
mod hebi_loop_tests;
