//! The navigator (issue 28, point 3): given a direction of travel, it picks among the
//! gaits and controllers that exist and changes them when the body is stuck. Pure and
//! with time as an argument: it reads what the loop publishes (the body estimate, the
//! progress monitor, the active gait) and answers with a [`Decision`], which whoever
//! runs it (the daemon's control side, the lab's trial) carries out as an operator's
//! requests would be: `controller.set`, `gait.set` (the selector's blend and the
//! takeover), `controller.heading`.
//!
//! The plan, from the crossing experiment's single controllers (docs/measurements/crossing.md,
//! "Getting across"): anti-compliant sidewinding aimed across is the only gait that makes
//! way on open ground at the bare skin's friction; slithering cannot move on open ground
//! with isotropic friction (it repeats, so the monitor says stuck) but crosses from
//! among pegs in the sleeve. So: slither when the body already heads the way, else
//! sidewind; when sidewinding is stuck, back off (sidewind the other way) for a while,
//! then slither; when slithering is stuck, or has had its time, sidewind.

use serde::{Deserialize, Serialize};

use super::body_heading_for;
use super::progress::ProgressReport;
use super::steering::{Course, GoalSteering, PositionView, SteeringConfig};
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
    /// Open-loop slithering steered round until the body lies across the direction, to
    /// sidewind from there: it turns in place about 20-90° a cycle where sidewinding's
    /// taper turns 3° a cycle while it travels sideways.
    Turn,
}

impl Choice {
    pub fn gait(self) -> GaitKind {
        match self {
            Choice::Sidewind | Choice::BackOff => GaitKind::Sidewinding,
            Choice::Slither | Choice::Turn => GaitKind::Slithering,
        }
    }

    /// The controller (registry name) it runs.
    pub fn controller(self) -> &'static str {
        match self {
            Choice::Sidewind | Choice::BackOff => "ac_sfc_lead",
            Choice::Slither => "a_ws_omega",
            Choice::Turn => "open_loop",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Choice::Sidewind => "sidewind",
            Choice::BackOff => "back_off",
            Choice::Slither => "slither",
            Choice::Turn => "turn",
        }
    }

    /// A number for plots and telemetry series (0 none).
    pub fn code(self) -> f64 {
        match self {
            Choice::Sidewind => 1.0,
            Choice::BackOff => 2.0,
            Choice::Slither => 3.0,
            Choice::Turn => 4.0,
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
    /// The turn is done (or had its time): the body lies across the direction.
    Turned,
    /// Sidewinding, the body was turned off course (by the obstacles) further than its
    /// own heading control corrects quickly.
    OffCourse,
    /// Steering by position: the same choice re-aimed at the course to the goal.
    Steer,
    /// Steering by position: no progress over the progress window (sidewinding: no
    /// net motion; slithering: no nearer the goal).
    NoProgress,
    /// Steering by position: sidewinding off the line, lying to travel across it.
    OffLine,
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
    /// Before sidewinding, turn in place when the body's axis is further than this from
    /// the heading sidewinding needs (either way round: the gait reverses), rad; π/2
    /// never turns.
    pub turn_above_rad: f64,
    /// The turn ends when the axis is this close, rad.
    pub turn_done_rad: f64,
    /// The longest turn, s.
    pub turn_max_s: f64,
    /// While sidewinding, turn in place when the body's axis is further than this from
    /// where it must lie, rad (π/2: never; sidewinding's own control turns it back
    /// slowly, 3° a cycle, while the obstacles turn it faster).
    pub off_course_rad: f64,
    /// A slithering spell stuck sooner than this shows slithering cannot move here (open
    /// ground with isotropic friction): the navigator does not slither again, s.
    pub slither_fails_within_s: f64,
    /// Slither at all (false: only sidewinding, its turns and backing off).
    pub slither: bool,
    /// Back off when sidewinding is stuck (false: sidewinding goes on).
    pub back_off: bool,
    /// Steering by position to a goal (`navigation::steering`).
    pub steering: SteeringConfig,
}

impl NavigatorConfig {
    pub const DEFAULT: Self = Self {
        settle_s: 6.0,
        back_off_s: 8.0,
        slither_max_s: 90.0,
        slither_within_rad: std::f64::consts::FRAC_PI_4,
        sidewind_drift_rad: super::SIDEWINDING_DRIFT_RAD,
        turn_above_rad: std::f64::consts::FRAC_PI_2,
        turn_done_rad: 0.25,
        turn_max_s: 20.0,
        off_course_rad: std::f64::consts::FRAC_PI_2,
        slither_fails_within_s: 25.0,
        slither: true,
        back_off: true,
        steering: SteeringConfig::DEFAULT,
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
        )?;
        let half = std::f64::consts::FRAC_PI_2;
        check_range("turn_above_rad", self.turn_above_rad, 0.0, half)?;
        check_range(
            "turn_done_rad",
            self.turn_done_rad,
            0.0,
            self.turn_above_rad,
        )?;
        check_range("turn_max_s", self.turn_max_s, 0.0, 600.0)?;
        check_range(
            "off_course_rad",
            self.off_course_rad,
            self.turn_done_rad,
            half,
        )?;
        check_range(
            "slither_fails_within_s",
            self.slither_fails_within_s,
            0.0,
            3600.0,
        )?;
        self.steering.check().map_err(|e| e.under("steering"))
    }
}

impl Default for NavigatorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where to navigate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A direction of travel, the pose estimate's world, rad.
    Heading(f64),
    /// A goal point, the position source's world, m (needs a valid position to start).
    Goal([f64; 2]),
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
    /// The position from an outside source, when it is valid (`WorldPosition::valid`).
    pub position: Option<PositionView>,
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
    /// Slithering got stuck within `slither_fails_within_s`: it is not tried again.
    slither_fails: bool,
    /// Going to a goal by position, when it has one.
    goal: Option<GoalSteering>,
    /// The last course by position (while it steers by position).
    course: Option<Course>,
    /// When it last re-aimed, and the heading it asked for then.
    aimed: (f64, f64),
    arrived: bool,
}

impl Navigator {
    pub fn new(config: NavigatorConfig, travel_rad: f64) -> Self {
        Self {
            config,
            travel_rad: crate::num::wrap_pi(travel_rad),
            current: None,
            since_s: 0.0,
            switches: 0,
            slither_fails: !config.slither,
            goal: None,
            course: None,
            aimed: (f64::NEG_INFINITY, f64::NAN),
            arrived: false,
        }
    }

    /// To `goal_m` (the position source's world) by position; towards `travel_rad` (the
    /// estimate's world) while it has no valid position.
    pub fn to_goal(config: NavigatorConfig, goal_m: [f64; 2], travel_rad: f64) -> Self {
        Self {
            goal: Some(GoalSteering::new(config.steering, goal_m)),
            ..Self::new(config, travel_rad)
        }
    }

    /// The direction of travel now, the estimate's world, rad (by position: the last
    /// course, turned into the estimate's world).
    pub fn travel_rad(&self) -> f64 {
        self.travel_rad
    }

    /// The goal, the source's world, m.
    pub fn goal(&self) -> Option<[f64; 2]> {
        self.goal.as_ref().map(GoalSteering::goal)
    }

    /// The course by position, while it steers by position (`None`: by heading only).
    pub fn course(&self) -> Option<Course> {
        self.course
    }

    /// It reached the goal (it decides nothing more).
    pub fn arrived(&self) -> bool {
        self.arrived
    }

    /// What it runs now and why (`None` before its first decision).
    pub fn current(&self) -> Option<(Choice, Why)> {
        self.current
    }

    /// Changes of gait or controller it made after the first choice.
    pub fn switches(&self) -> u32 {
        self.switches
    }

    /// Whether slithering has shown it cannot move here (it is not tried again).
    pub fn slither_fails(&self) -> bool {
        self.slither_fails
    }

    /// The body heading sidewinding towards the direction needs.
    fn sidewind_heading(&self) -> f64 {
        let c = &self.config;
        body_heading_for(GaitKind::Sidewinding, self.travel_rad, c.sidewind_drift_rad)
            .unwrap_or(self.travel_rad)
    }

    /// At time `t_s` with what the loop shows: a new decision, or `None` to go on.
    /// Nothing is decided while the loop does not run the gait or the pose estimate is
    /// not valid (the runner reports that and may stop navigating).
    pub fn step(&mut self, t_s: f64, view: &NavView) -> Option<Decision> {
        if !view.running || !view.estimate_valid || self.arrived {
            return None;
        }
        self.steer_by_position(t_s, view);
        if self.arrived {
            return None;
        }
        let c = self.config;
        let across = self.sidewind_heading();
        // Sidewinding, or a turn first when the body's axis is far from where it must lie.
        let sidewind = |why| match axis_error(view.heading_rad, across) > c.turn_above_rad {
            true => (Choice::Turn, why),
            false => (Choice::Sidewind, why),
        };
        let next = match self.current {
            None if c.slither
                && crate::num::wrap_pi(view.heading_rad - self.travel_rad).abs()
                    <= c.slither_within_rad =>
            {
                (Choice::Slither, Why::Start)
            }
            None => sidewind(Why::Start),
            Some((now, _)) => {
                let age = t_s - self.since_s;
                // By position: sidewinding that does not move, slithering that comes no
                // nearer (it steers quickly, so moving elsewhere is failing: on open
                // ground with isotropic friction it drifts back).
                let no_progress = self.course.is_some_and(|k| match now {
                    Choice::Sidewind => k.no_progress,
                    Choice::Slither => k.no_nearer,
                    _ => false,
                });
                // By position: off the line further than sidewinding's slow turn makes
                // up for, lying so that it travels across the line.
                let off_line = self.course.is_some_and(|k| {
                    let s = c.steering;
                    s.off_line_m > 0.0
                        && k.cross_track_m.abs() > s.off_line_m
                        && axis_error(view.heading_rad, across) > s.authority_rad[1]
                });
                let why_stuck = match view.progress.stuck {
                    true => Why::Stuck,
                    false => Why::NoProgress,
                };
                let stuck = (view.progress.stuck || no_progress) && age >= c.settle_s;
                match now {
                    Choice::Sidewind if stuck && c.back_off => (Choice::BackOff, why_stuck),
                    Choice::Sidewind
                        if age >= c.settle_s
                            && axis_error(view.heading_rad, across) > c.off_course_rad =>
                    {
                        (Choice::Turn, Why::OffCourse)
                    }
                    Choice::Sidewind if age >= c.settle_s && off_line => {
                        (Choice::Turn, Why::OffLine)
                    }
                    Choice::BackOff if age >= c.back_off_s && !self.slither_fails => {
                        (Choice::Slither, Why::BackedOff)
                    }
                    Choice::BackOff if age >= c.back_off_s => sidewind(Why::BackedOff),
                    Choice::Slither if stuck => {
                        self.slither_fails |= age < c.slither_fails_within_s;
                        sidewind(why_stuck)
                    }
                    Choice::Slither if age >= c.slither_max_s => sidewind(Why::SlitherTimeUp),
                    Choice::Turn
                        if age >= c.turn_max_s
                            || axis_error(view.heading_rad, across) <= c.turn_done_rad =>
                    {
                        (Choice::Sidewind, Why::Turned)
                    }
                    _ => return self.reaim(t_s, now),
                }
            }
        };
        if self.current.is_some() {
            self.switches += 1;
        }
        self.current = Some(next);
        self.since_s = t_s;
        if let Some(g) = self.goal.as_mut() {
            g.restart_progress();
        }
        let (choice, why) = next;
        let travel = match choice {
            Choice::BackOff => self.travel_rad + std::f64::consts::PI,
            _ => self.travel_rad,
        };
        let heading_rad = match choice {
            // Round to the nearer of the two ways sidewinding may lie.
            Choice::Turn => nearer_way(view.heading_rad, across),
            _ => body_heading_for(choice.gait(), travel, c.sidewind_drift_rad).unwrap_or(travel),
        };
        self.aimed = (t_s, heading_rad);
        Some(Decision {
            choice,
            why,
            heading_rad,
        })
    }

    /// With a goal and a valid position: the course to it, and the direction of travel
    /// turned into the estimate's world; without a valid position the last direction
    /// stands (today's heading-only navigation) and the course is dropped.
    fn steer_by_position(&mut self, t_s: f64, view: &NavView) {
        let drift = self.config.sidewind_drift_rad;
        let sidewinding = self
            .current
            .is_none_or(|(c, _)| c.gait() == GaitKind::Sidewinding);
        let Some(g) = self.goal.as_mut() else {
            return;
        };
        let Some(p) = view.position else {
            if self.course.take().is_some() {
                g.pause();
            }
            return;
        };
        // Sidewinding travels across its axis: how far the axis is from lying across
        // the line decides how much cross-track correction it can take.
        let authority = match sidewinding {
            true => {
                let line = g.line_rad(p.position_m) - p.yaw_offset_rad;
                let across = body_heading_for(GaitKind::Sidewinding, line, drift).unwrap_or(line);
                g.authority(axis_error(view.heading_rad, across))
            }
            false => 1.0,
        };
        let course = g.update(t_s, p.position_m, authority);
        self.arrived = course.arrived;
        self.travel_rad = crate::num::wrap_pi(course.travel_rad - p.yaw_offset_rad);
        self.course = Some(course);
    }

    /// Steering by position, the same choice re-aimed when its heading has moved.
    fn reaim(&mut self, t_s: f64, now: Choice) -> Option<Decision> {
        let s = self.config.steering;
        if self.course.is_none() || now == Choice::Turn || t_s - self.aimed.0 < s.reaim_s {
            return None;
        }
        let travel = match now {
            Choice::BackOff => self.travel_rad + std::f64::consts::PI,
            _ => self.travel_rad,
        };
        let heading_rad =
            body_heading_for(now.gait(), travel, self.config.sidewind_drift_rad).unwrap_or(travel);
        let moved = crate::num::wrap_pi(heading_rad - self.aimed.1).abs();
        if moved <= s.reaim_above_rad {
            return None;
        }
        self.aimed = (t_s, heading_rad);
        Some(Decision {
            choice: now,
            why: Why::Steer,
            heading_rad,
        })
    }
}

/// How far the body's axis (heading `h`) is from lying along `target` either way
/// round, 0..π/2: sidewinding reverses when it faces the other way.
fn axis_error(h: f64, target: f64) -> f64 {
    let e = crate::num::wrap_pi(h - target).abs();
    e.min(std::f64::consts::PI - e)
}

/// `target` or `target + π`, whichever is nearer to `h`.
fn nearer_way(h: f64, target: f64) -> f64 {
    let e = crate::num::wrap_pi(h - target).abs();
    match e <= std::f64::consts::FRAC_PI_2 {
        true => target,
        false => crate::num::wrap_pi(target + std::f64::consts::PI),
    }
}

#[cfg(test)]
#[path = "navigator_tests.rs"]
mod tests;
