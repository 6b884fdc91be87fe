//! snaked: a real-time control daemon for modular series-elastic snake robots.
//!
//! Layout, one folder per concern (docs/architecture.md has the table):
//! - [`protocol`], [`module`]: the module network's wire format; a module's command and
//!   feedback and the body's constants.
//! - [`bus`]: the loop's view of the modules (UDP or in-process emulator).
//! - [`emu`]: the module emulator (plant, module endpoints, faults).
//! - [`estimation`]: the body's pose from its IMUs and joint angles (virtual chassis).
//! - [`gait`]: open-loop gaits and the selector that blends between them.
//! - [`controller_interface`], [`controllers`]: the controller seam and registry, and
//!   every controller (one folder each).
//! - [`shape`]: shape-based compliance the controllers are built on.
//! - [`navigation`]: pursuing a direction on its own: stuck detection, the navigator.
//! - [`safety`]: the failsafe state machine.
//! - [`rt`]: pacing, the 1 kHz loop, statistics, telemetry.
//! - [`operator`]: the operator API: one typed path for everything an operator asks
//!   (`Act` → `Done`, one error and code table), the drive lease, the navigator's runner.
//! - [`socket`]: the JSON control socket, a thin adapter over [`operator`].
//! - [`station`]: operating from Foxglove (services, teleop, parameters), a thin adapter
//!   over [`operator`].
//! - [`record`]: MCAP recording.
//! - [`live`]: the Foxglove live view (WebSocket server) the recorder starts; it carries
//!   the station.
//! - [`foxglove_json`]: JSON channels on a foxglove context (shared by `live` and
//!   `station`).
//! - [`lab`]: controller comparisons in simulation (`snake-lab`).
//! - [`daemon`]: configuration and wiring of the service.
//! - [`num`]: numbers as people read them, angles wrapped.

pub mod bus;
pub mod controller_interface;
pub mod controllers;
pub mod daemon;
pub mod emu;
pub mod estimation;
pub mod foxglove_json;
pub mod gait;
pub mod lab;
pub mod live;
pub mod module;
pub mod navigation;
pub mod num;
pub mod operator;
pub mod protocol;
pub mod record;
pub mod ros2;
pub mod rt;
pub mod safety;
pub mod shape;
pub mod socket;
pub mod station;
