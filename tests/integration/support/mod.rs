//! What the integration tests share. Each test module uses its own part, hence the
//! `dead_code` allowance.
#![allow(dead_code)]

/// The binary's allocator counts each thread's allocator calls (the `alloc` tests).
pub mod counting_alloc;
/// A v2 host spoken by hand against the UDP emulator.
pub mod emu_client;
/// Least-squares sinusoid fit (the gait tests).
pub mod fit;
/// A Foxglove WebSocket client (service calls, client publishing).
pub mod foxglove_ws;
/// Synthetic recordings and an independent reader (the recorder's tests).
pub mod record_fixture;
/// Hardware-in-loop rig: free ports, child processes, a line-JSON client.
pub mod rig;
/// A fake loop behind the real control-socket server, and a client.
pub mod socket;
