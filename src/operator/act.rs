//! What an operator asks the robot to do, typed ([`Act`]), and what is done ([`Done`]).
//! Every edge (the control socket's JSON, the Foxglove station's services and teleop,
//! the navigator, a ROS 2 node) builds an `Act`, hands it to
//! [`super::Operator::act`] and presents the `Done` in its own terms.

use crate::controller_interface::Selection;
use crate::controller_interface::catalog::ControllerInfo;
use crate::gait::{GaitKind, GaitParams, ParamPatch};
use crate::navigation::navigator::{NavigatorConfig, Target};
use crate::rt::controller_slots::ControllerTelemetry;
use crate::rt::messages::Continuity;

/// What `controller.calibrate` asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Calibration {
    /// Measure over this many seconds (`None`: over the default cycles of the gait).
    Run(Option<f64>),
    Clear,
}

/// A request that changes what the robot does.
#[derive(Debug, Clone, PartialEq)]
pub enum Act {
    /// Blend into this gait (arms a held or limp robot).
    SetGait {
        gait: GaitKind,
    },
    /// A controlled stop: the gait at rest within `within_s`.
    StopGait {
        within_s: f64,
    },
    /// The gait moves again within `within_s`.
    ResumeGait {
        within_s: f64,
    },
    /// Change some of a gait's parameters (a driving controller follows them).
    SetParams {
        gait: GaitKind,
        patch: ParamPatch,
    },
    /// The blend time of gait switches, s.
    SetBlendTime {
        blend_time_s: f64,
    },
    /// Build `selection` for `gait` (on the gait's parameters after `patch`) and
    /// install it, with `patch` if it changes anything.
    SetController {
        gait: GaitKind,
        selection: Selection,
        patch: ParamPatch,
    },
    /// Calibrate (or clear) the controller of `gait` (the running gait's by default).
    Calibrate {
        gait: Option<GaitKind>,
        what: Calibration,
    },
    /// The nominal heading of `gait`'s controller, rad; `None`: the heading now.
    SetHeading {
        gait: Option<GaitKind>,
        heading_rad: Option<f64>,
    },
    /// Navigate in a direction (the pose estimate's world) or to a goal (the position
    /// source's world).
    Navigate {
        target: Target,
        config: NavigatorConfig,
    },
    /// Stop navigating (anyone may).
    NavigateOff,
    /// Take the drive over from whoever holds it.
    TakeOver,
    Hold,
    Limp,
    EStop,
    Arm,
}

impl Act {
    /// The control socket's name of the request (logs, the drive lease's messages).
    pub fn method(&self) -> &'static str {
        match self {
            Act::SetGait { .. } => "gait.set",
            Act::StopGait { .. } => "gait.stop",
            Act::ResumeGait { .. } => "gait.resume",
            Act::SetParams { .. } | Act::SetBlendTime { .. } => "params.set",
            Act::SetController { patch, .. } if *patch != ParamPatch::default() => "params.set",
            Act::SetController { .. } => "controller.set",
            Act::Calibrate { .. } => "controller.calibrate",
            Act::SetHeading { .. } => "controller.heading",
            Act::Navigate { .. } | Act::NavigateOff => "navigate",
            Act::TakeOver => "take_over",
            Act::Hold => "hold",
            Act::Limp => "limp",
            Act::EStop => "estop",
            Act::Arm => "arm",
        }
    }

    /// Whether it drives the robot: it needs the drive (`super::driver`).
    pub fn drives(&self) -> bool {
        !matches!(
            self,
            Act::StopGait { .. }
                | Act::NavigateOff
                | Act::TakeOver
                | Act::Hold
                | Act::Limp
                | Act::EStop
        )
    }

    /// Whether it stops the robot: anyone may, and the drive is free afterwards.
    pub fn stops(&self) -> bool {
        matches!(
            self,
            Act::StopGait { .. } | Act::Hold | Act::Limp | Act::EStop
        )
    }

    /// Whether the operator takes over from the navigator with it (navigation stops
    /// first); a change of parameters (say, a slower wave) does not.
    pub fn takes_over_navigation(&self) -> bool {
        matches!(
            self,
            Act::SetGait { .. }
                | Act::SetController { .. }
                | Act::SetHeading { .. }
                | Act::Calibrate { .. }
                | Act::TakeOver
                | Act::Hold
                | Act::Limp
                | Act::EStop
        )
    }
}

/// How a calibration ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Calibrated {
    /// Forgotten.
    Cleared,
    /// Started; the controller reports no calibration to wait for.
    Started { seconds: f64 },
    /// Finished; the controller's report then.
    Finished {
        seconds: f64,
        controller: Box<ControllerTelemetry>,
    },
}

/// What was done.
#[derive(Debug, Clone, PartialEq)]
pub enum Done {
    Gait {
        gait: GaitKind,
    },
    Motion {
        stopping: bool,
        within_s: f64,
    },
    Params {
        gait: GaitKind,
        params: GaitParams,
        /// What became of the gait's controller.
        continuity: Option<Continuity>,
    },
    BlendTime {
        blend_time_s: f64,
    },
    Controller {
        gait: GaitKind,
        info: Box<ControllerInfo>,
        /// The gait's new parameters, where the request changed them.
        params: Option<GaitParams>,
        continuity: Option<Continuity>,
    },
    Calibration {
        gait: GaitKind,
        controller: &'static str,
        outcome: Calibrated,
    },
    Heading {
        gait: GaitKind,
        controller: &'static str,
        heading_rad: Option<f64>,
    },
    Navigating {
        travel_rad: f64,
        goal_m: Option<[f64; 2]>,
        config: NavigatorConfig,
    },
    NavigationOff {
        was_navigating: bool,
    },
    TookOver {
        driver: String,
        taken_from: Option<String>,
    },
    Ok,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The drive lease's and the navigator's rules by method, as the socket has
    /// documented them (docs/control-socket.md, "One operator drives", `navigate`).
    #[test]
    fn which_acts_drive_stop_and_take_over_from_the_navigator() {
        let gait = GaitKind::Slithering;
        let all = [
            Act::SetGait { gait },
            Act::StopGait { within_s: 0.3 },
            Act::ResumeGait { within_s: 0.3 },
            Act::SetParams {
                gait,
                patch: ParamPatch::default(),
            },
            Act::SetBlendTime { blend_time_s: 2.0 },
            Act::SetController {
                gait,
                selection: Selection::named("open_loop"),
                patch: ParamPatch::default(),
            },
            Act::Calibrate {
                gait: None,
                what: Calibration::Clear,
            },
            Act::SetHeading {
                gait: None,
                heading_rad: None,
            },
            Act::Navigate {
                target: Target::Heading(0.0),
                config: NavigatorConfig::DEFAULT,
            },
            Act::NavigateOff,
            Act::TakeOver,
            Act::Hold,
            Act::Limp,
            Act::EStop,
            Act::Arm,
        ];
        let named = |f: fn(&Act) -> bool| -> Vec<&str> {
            let mut v: Vec<&str> = all.iter().filter(|a| f(a)).map(Act::method).collect();
            v.dedup();
            v
        };
        assert_eq!(
            named(Act::drives),
            [
                "gait.set",
                "gait.resume",
                "params.set",
                "controller.set",
                "controller.calibrate",
                "controller.heading",
                "navigate",
                "arm"
            ]
        );
        assert_eq!(named(Act::stops), ["gait.stop", "hold", "limp", "estop"]);
        assert_eq!(
            named(Act::takes_over_navigation),
            [
                "gait.set",
                "controller.set",
                "controller.calibrate",
                "controller.heading",
                "take_over",
                "hold",
                "limp",
                "estop"
            ]
        );
    }
}
