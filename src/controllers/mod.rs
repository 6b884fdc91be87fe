//! Every controller the daemon and the lab can run, one folder each, and the one
//! registry that lists them. Adding a controller is a folder here plus one line in
//! [`REGISTRY`]: the loop, the socket, `snakectl` and the lab find it there.

pub mod compliant_slithering;
pub mod cpg;
pub mod directional_compliance;
pub mod helix_radius;
pub mod open_loop;
pub mod serpenoid_admittance;
pub mod sidewinding;
pub mod steering;

use crate::controller_interface::registry::{Entry, Family};

/// The registry, one line per controller. The first that runs a gait is its default.
pub static REGISTRY: &[&dyn Family] = &[
    &Entry::<open_loop::OpenLoopKind>::NEW,
    &Entry::<compliant_slithering::CompliantSlitheringKind>::NEW,
    &Entry::<cpg::CpgKind>::NEW,
    &Entry::<serpenoid_admittance::SerpenoidAdmittanceKind>::NEW,
    &Entry::<directional_compliance::DirectionalComplianceKind>::NEW,
    &Entry::<sidewinding::SidewindingKind>::NEW,
    &Entry::<helix_radius::HelixRadiusKind>::NEW,
];
