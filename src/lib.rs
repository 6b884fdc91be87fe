//! snaked: a real-time control daemon for modular series-elastic snake robots.
//!
//! Layout, one folder per concern:
//! - [`protocol`]: the module network's wire format.
//! - [`bus`]: the loop's view of the modules (UDP or in-process emulator).
//! - [`emu`]: the module emulator (plant, module endpoints, faults).
//! - [`estimation`]: the body's pose from its IMUs and joint angles (virtual chassis).
//! - [`gait`]: open-loop gaits and the selector that blends between them.
//! - [`safety`]: the failsafe state machine.
//! - [`shape`]: shape-based compliance and the controllers built on it.
//! - [`rt`]: pacing, the 1 kHz loop, statistics, telemetry.
//! - [`control`]: the JSON control socket.
//! - [`lab`]: controller comparisons in simulation (`snake-lab`).
//! - [`daemon`]: configuration and wiring of the service.

pub mod bus;
pub mod controller_interface;
pub mod controllers;
pub mod daemon;
pub mod emu;
pub mod estimation;
pub mod gait;
pub mod lab;
pub mod module;
pub mod num;
pub mod protocol;
pub mod record;
pub mod rt;
pub mod safety;
pub mod shape;
pub mod socket;
