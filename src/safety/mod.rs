//! Safety logic: pure state machines with time as input.
pub mod failsafe;
