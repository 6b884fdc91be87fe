//! The navigator (issue 28, point 3): given a direction of travel, it picks among the
//! gaits and controllers that exist and changes them when the body is stuck. Pure and
//! with time as an argument: it reads what the loop publishes (the body estimate, the
//! progress monitor, the active gait) and answers with a [`Decision`], which whoever
//! runs it (the daemon's control side, the lab's trial) carries out as an operator's
//! requests would be: `controller.set`, `gait.set` (the selector's blend and the
//! takeover), `controller.heading`.
//!
//! The plan, from the crossing experiment's single controllers (docs/measurements.md,
//! "Getting across"): anti-compliant sidewinding aimed across is the only gait that makes
//! way on open ground at the bare skin's friction; slithering cannot move on open ground
//! with isotropic friction (it repeats, so the monitor says stuck) but crosses from
//! among pegs in the sleeve. So: slither when the body already heads the way, else
//! sidewind; when sidewinding is stuck, back off (sidewind the other way) for a while,
//! then slither; when slithering is stuck, or has had its time, sidewind.

use serde::{Deserialize, Serialize};

use super::body_heading_for;
use super::progress::ProgressReport;
use crate::controller_interface::config::{ConfigError, check_range};
use crate::gait::GaitKind;

/// What the navigator runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Choice {
    /// Anti-compliant sidewinding towards the direction.
    Sidewind,
    /// Sidewinding away from it, to free the body.
    BackOff,
    /// Compliant slithering towards the direction.
    Slither,
}

impl Choice {
    pub fn gait(self) -> GaitKind {
        match self {
            Choice::Sidewind | Choice::BackOff => GaitKind::Sidewinding,
            Choice::Slither => GaitKind::Slithering,
        }
    }

    /// The controller (registry name) it runs.
    pub fn controller(self) -> &'static str {
        match self {
            Choice::Sidewind | Choice::BackOff => "ac_sfc",
            Choice::Slither => "a_ws_omega",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Choice::Sidewind => "sidewind",
            Choice::BackOff => "back_off",
            Choice::Slither => "slither",
        }
    }

    /// A number for plots and telemetry series (0 none).
    pub fn code(self) -> f64 {
        match self {
            Choice::Sidewind => 1.0,
            Choice::BackOff => 2.0,
            Choice::Slither => 3.0,
        }
    }
}

/// Why it chose what it runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Why {
    /// Navigation started.
    Start,
    /// The progress monitor said stuck.
    Stuck,
    /// Backing off lasted its time.
    BackedOff,
    /// Slithering had its time without getting stuck or free.
    SlitherTimeUp,
}

/// The navigator's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NavigatorConfig {
    /// After a change, the stuck signal is not acted on for this long, s (the blend and
    /// a whole cycle to measure).
    pub settle_s: f64,
    /// How long backing off lasts, s.
    pub back_off_s: f64,
    /// The longest slithering spell, s.
    pub slither_max_s: f64,
    /// At the start, slither when the body heads within this of the direction (else
    /// sidewind), rad.
    pub slither_within_rad: f64,
    /// Sidewinding is aimed this much to the right of its plain heading, because among
    /// obstacles it bends left ([`super::SIDEWINDING_DRIFT_RAD`]), rad.
    pub sidewind_drift_rad: f64,
}

impl NavigatorConfig {
    pub const DEFAULT: Self = Self {
        settle_s: 6.0,
        back_off_s: 8.0,
        slither_max_s: 90.0,
        slither_within_rad: std::f64::consts::FRAC_PI_4,
        sidewind_drift_rad: super::SIDEWINDING_DRIFT_RAD,
    };

    pub fn check(&self) -> Result<(), ConfigError> {
        check_range("settle_s", self.settle_s, 0.0, 120.0)?;
        check_range("back_off_s", self.back_off_s, 0.0, 120.0)?;
        check_range("slither_max_s", self.slither_max_s, 1.0, 3600.0)?;
        check_range(
            "slither_within_rad",
            self.slither_within_rad,
            0.0,
            std::f64::consts::PI,
        )?;
        check_range(
            "sidewind_drift_rad",
            self.sidewind_drift_rad,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        )
    }
}

impl Default for NavigatorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the navigator wants done: run `choice` (its gait and controller) with the
/// nominal body heading `heading_rad` (the estimate's world), because of `why`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    pub choice: Choice,
    pub why: Why,
    pub heading_rad: f64,
}

/// What the navigator reads each step.
#[derive(Debug, Clone, Copy)]
pub struct NavView {
    /// The loop runs the gait (not holding, limp or stopped).
    pub running: bool,
    /// The pose estimate is valid.
    pub estimate_valid: bool,
    /// Its heading (the body's head-ward axis, the estimate's world), rad.
    pub heading_rad: f64,
    pub progress: ProgressReport,
}

/// The navigator's state.
#[derive(Debug, Clone)]
pub struct Navigator {
    config: NavigatorConfig,
    /// The direction of travel, the estimate's world, rad.
    travel_rad: f64,
    current: Option<(Choice, Why)>,
    since_s: f64,
    switches: u32,
}

impl Navigator {
    pub fn new(config: NavigatorConfig, travel_rad: f64) -> Self {
        Self {
            config,
            travel_rad: crate::num::wrap_pi(travel_rad),
            current: None,
            since_s: 0.0,
            switches: 0,
        }
    }

    pub fn travel_rad(&self) -> f64 {
        self.travel_rad
    }

    /// What it runs now and why (`None` before its first decision).
    pub fn current(&self) -> Option<(Choice, Why)> {
        self.current
    }

    /// Changes of gait or controller it made after the first choice.
    pub fn switches(&self) -> u32 {
        self.switches
    }

    /// At time `t_s` with what the loop shows: a new decision, or `None` to go on.
    /// Nothing is decided while the loop does not run the gait or the pose estimate is
    /// not valid (the runner reports that and may stop navigating).
    pub fn step(&mut self, t_s: f64, view: &NavView) -> Option<Decision> {
        if !view.running || !view.estimate_valid {
            return None;
        }
        let c = &self.config;
        let next = match self.current {
            None if crate::num::wrap_pi(view.heading_rad - self.travel_rad).abs()
                <= c.slither_within_rad =>
            {
                (Choice::Slither, Why::Start)
            }
            None => (Choice::Sidewind, Why::Start),
            Some((now, _)) => {
                let age = t_s - self.since_s;
                let stuck = view.progress.stuck && age >= c.settle_s;
                match now {
                    Choice::Sidewind if stuck => (Choice::BackOff, Why::Stuck),
                    Choice::BackOff if age >= c.back_off_s => (Choice::Slither, Why::BackedOff),
                    Choice::Slither if stuck => (Choice::Sidewind, Why::Stuck),
                    Choice::Slither if age >= c.slither_max_s => {
                        (Choice::Sidewind, Why::SlitherTimeUp)
                    }
                    _ => return None,
                }
            }
        };
        if self.current.is_some() {
            self.switches += 1;
        }
        self.current = Some(next);
        self.since_s = t_s;
        let (choice, why) = next;
        let travel = match choice {
            Choice::BackOff => self.travel_rad + std::f64::consts::PI,
            _ => self.travel_rad,
        };
        let heading_rad =
            body_heading_for(choice.gait(), travel, c.sidewind_drift_rad).unwrap_or(travel);
        Some(Decision {
            choice,
            why,
            heading_rad,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::navigation::stuck::StuckReason;

    fn view(stuck: bool) -> NavView {
        NavView {
            running: true,
            estimate_valid: true,
            heading_rad: 2.0,
            progress: ProgressReport {
                stuck,
                reason: if stuck {
                    StuckReason::TorquesRepeat
                } else {
                    StuckReason::Changing
                },
                ..ProgressReport::NONE
            },
        }
    }

    #[test]
    fn sidewinds_backs_off_when_stuck_then_slithers_and_returns() {
        let c = NavigatorConfig::DEFAULT;
        let mut n = Navigator::new(c, 0.3);
        // Nothing while the estimate is not valid.
        let mut v = view(false);
        v.estimate_valid = false;
        assert_eq!(n.step(0.0, &v), None);
        let d = n.step(0.1, &view(false)).unwrap();
        assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Start));
        assert!((d.heading_rad - (0.3 + std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
        // Stuck too soon after a change is not acted on.
        assert_eq!(n.step(1.0, &view(true)), None);
        let d = n.step(0.1 + c.settle_s, &view(true)).unwrap();
        assert_eq!((d.choice, d.why), (Choice::BackOff, Why::Stuck));
        assert!(
            (crate::num::wrap_pi(d.heading_rad - (0.3 - std::f64::consts::FRAC_PI_2))).abs()
                < 1e-12
        );
        let t = 0.1 + c.settle_s + c.back_off_s;
        let d = n.step(t, &view(false)).unwrap();
        assert_eq!((d.choice, d.why), (Choice::Slither, Why::BackedOff));
        assert!((d.heading_rad - 0.3).abs() < 1e-12);
        let d = n.step(t + c.slither_max_s, &view(false)).unwrap();
        assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::SlitherTimeUp));
        assert_eq!(n.switches(), 3);
        assert_eq!(n.current(), Some((Choice::Sidewind, Why::SlitherTimeUp)));
    }

    #[test]
    fn a_body_heading_the_way_slithers_first_and_sidewinds_when_stuck() {
        let c = NavigatorConfig::DEFAULT;
        let mut n = Navigator::new(c, 0.3);
        let mut v = view(false);
        v.heading_rad = 0.3 + 0.7;
        let d = n.step(0.0, &v).unwrap();
        assert_eq!((d.choice, d.why), (Choice::Slither, Why::Start));
        v.progress = view(true).progress;
        let d = n.step(c.settle_s, &v).unwrap();
        assert_eq!((d.choice, d.why), (Choice::Sidewind, Why::Stuck));
        assert!(
            NavigatorConfig {
                slither_within_rad: 4.0,
                ..c
            }
            .check()
            .is_err()
        );
    }
}
