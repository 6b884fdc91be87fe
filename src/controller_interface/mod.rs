//! The controller seam: what every controller offers the loop (engaged from a
//! handover, stepped as a pure function of time and an observation, reporting named
//! signals), the typed configurations and the one registry of controllers. The
//! runtime (`rt/`), the socket, `snakectl` and the lab know controllers only through
//! this module. See `docs/architecture.md`.

pub mod catalog;
pub mod config;
pub mod interface;
pub mod nominal;
pub mod position;
pub mod registry;
pub mod report;

pub use config::ConfigError;
pub use interface::{
    BodyEstimate, CalibrationState, CannotFollow, Capabilities, CommandRefused, Controller,
    ControllerCommand, Estimator, Handover, Imu, NominalMismatch, Observation, Tick, TickClock,
    same_kind,
};
pub use registry::{BuildContext, Built, ControllerKind, Family, Selection};
pub mod testing;
