//! Getting across (issue 28): what the gait selector needs to pursue a direction on its
//! own. So far: knowing the body is jammed from what the daemon senses ([`stuck`]),
//! monitored by the loop over the gait it runs ([`progress`]).
//! The navigator that picks and changes gaits and controllers comes next.

pub mod navigator;
pub mod progress;
pub mod stuck;

use crate::gait::GaitKind;

/// The body heading (of the head-ward axis) that makes `gait` travel towards
/// `travel_rad`: slithering goes where its head points; sidewinding travels 90° clockwise
/// of it (measured: the sidewinding experiment's fence lies on that side,
/// scenarios/sidewinding-pegs.toml). `None` for gaits that do not travel by heading.
pub fn body_heading_for(gait: GaitKind, travel_rad: f64) -> Option<f64> {
    match gait {
        GaitKind::Slithering => Some(crate::num::wrap_pi(travel_rad)),
        GaitKind::Sidewinding => Some(crate::num::wrap_pi(
            travel_rad + std::f64::consts::FRAC_PI_2,
        )),
        _ => None,
    }
}
