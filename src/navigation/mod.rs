//! Getting across (issue 28): what the gait selector needs to pursue a direction on its
//! own. So far: knowing the body is jammed from what the daemon senses ([`stuck`]),
//! monitored by the loop over the gait it runs ([`progress`]); the navigator that picks
//! and changes gaits and controllers ([`navigator`]), steering by position to a goal
//! when an outside source gives one ([`steering`]), and its state as the loop reports
//! it ([`state`]).

pub mod navigator;
pub mod progress;
pub mod state;
pub mod steering;
pub mod stuck;

use crate::gait::GaitKind;

/// The body heading (of the head-ward axis) that makes `gait` travel towards
/// `travel_rad`: slithering goes where its head points; sidewinding travels 90° clockwise
/// of it (measured: the sidewinding experiment's fence lies on that side,
/// scenarios/sidewinding-pegs.toml), less `sidewind_drift_rad`, the angle its travel
/// bends to the left among obstacles (turned the other way to make up for it:
/// [`SIDEWINDING_DRIFT_RAD`]). `None` for gaits that do not travel by heading.
pub fn body_heading_for(gait: GaitKind, travel_rad: f64, sidewind_drift_rad: f64) -> Option<f64> {
    match gait {
        GaitKind::Slithering => Some(crate::num::wrap_pi(travel_rad)),
        GaitKind::Sidewinding => Some(crate::num::wrap_pi(
            travel_rad + std::f64::consts::FRAC_PI_2 - sidewind_drift_rad,
        )),
        _ => None,
    }
}

/// How far to the left of where it faces (less 90°) anti-compliant sidewinding travels
/// among obstacles, rad: its lateral wave pushes on them as slithering's does, which
/// drives the body along its axis as well as across it. Measured on the crossing
/// boards (docs/measurements/crossing.md, "Sidewinding goes head first among
/// obstacles"): side exits went left in 24 of 28 trials.
pub const SIDEWINDING_DRIFT_RAD: f64 = 0.0;
