//! Steering by position (issue 48, point 4): with a valid position from an outside
//! source (`BodyEstimate::world`), the navigator goes to a goal point along the line
//! from where it started, whatever the obstacles turn the gait's travel by. Pure, with
//! time as an argument.
//!
//! The course to hold is integral line-of-sight guidance (ILOS: Børhaug, Pavlov and
//! Pettersen, "Integral LOS control for path following of underactuated marine surface
//! vessels in the presence of constant ocean currents", CDC 2008): aim at a point
//! `lookahead_m` ahead on the line, and integrate the cross-track error so a steady
//! drift (sidewinding among pegs goes head first, to the left of where it is aimed) is
//! made up for by aiming off, as a helmsman crabs into a current:
//!
//! χ = χ_line − atan((e + σ·y_i) / Δ),   ẏ_i = Δ·e / (Δ² + (e + σ·y_i)²)
//!
//! with e the cross-track error (left of the line positive), Δ the lookahead, σ the
//! integral gain. The integral is bounded so the aim-off stays within
//! `max_aim_off_rad`. Progress is the net distance moved over the last
//! `progress_window_s`: under `progress_min_m` the navigator takes it as stuck, as it
//! takes the torques' repetition (a body thrashing in place whose torques do not
//! repeat); a body moving the wrong way is steered, not stuck.

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_range};

/// How the navigator steers by position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SteeringConfig {
    /// Δ: how far ahead on the line it aims, m.
    pub lookahead_m: f64,
    /// σ: the cross-track error's integral gain (0: plain line of sight).
    pub integral_gain: f64,
    /// The most it aims off the line's direction, rad.
    pub max_aim_off_rad: f64,
    /// How often it re-aims the controller, s.
    pub reaim_s: f64,
    /// It re-aims when the heading moved more than this, rad.
    pub reaim_above_rad: f64,
    /// Sidewinding: the whole cross-track correction while the body's axis lies within
    /// the first of where it must lie to travel the line, none beyond the second, rad.
    pub authority_rad: [f64; 2],
    /// Sidewinding further than this off the line while it lies to travel across it
    /// (its axis beyond `authority_rad[1]`): turn the body in place first, m (0: never).
    pub off_line_m: f64,
    /// Arrived within this of the goal (or past it along the line), m.
    pub arrive_m: f64,
    /// No progress: moved under `progress_min_m` (net, any way) over this long, s (0:
    /// off). A body moving the wrong way is steered, not taken as stuck.
    pub progress_window_s: f64,
    pub progress_min_m: f64,
}

impl SteeringConfig {
    pub const DEFAULT: Self = Self {
        lookahead_m: 0.8,
        integral_gain: 0.5,
        max_aim_off_rad: 1.2,
        reaim_s: 1.0,
        reaim_above_rad: 0.05,
        authority_rad: [0.5, 1.0],
        off_line_m: 0.0,
        arrive_m: 0.25,
        progress_window_s: 20.0,
        progress_min_m: 0.10,
    };

    pub fn check(&self) -> Result<(), ConfigError> {
        check_range("lookahead_m", self.lookahead_m, 0.05, 100.0)?;
        check_range("integral_gain", self.integral_gain, 0.0, 10.0)?;
        check_range(
            "max_aim_off_rad",
            self.max_aim_off_rad,
            0.0,
            std::f64::consts::FRAC_PI_2 - 0.01,
        )?;
        check_range("reaim_s", self.reaim_s, 0.05, 60.0)?;
        check_range("reaim_above_rad", self.reaim_above_rad, 0.0, 1.0)?;
        let [full, none] = self.authority_rad;
        check_range("authority_rad[0]", full, 0.0, std::f64::consts::FRAC_PI_2)?;
        check_range(
            "authority_rad[1]",
            none,
            full + 0.01,
            std::f64::consts::FRAC_PI_2 + 0.01,
        )?;
        check_range("off_line_m", self.off_line_m, 0.0, 100.0)?;
        check_range("arrive_m", self.arrive_m, 0.01, 100.0)?;
        check_range(
            "progress_window_s",
            self.progress_window_s,
            0.0,
            PROGRESS_SLOTS as f64,
        )?;
        check_range("progress_min_m", self.progress_min_m, 0.0, 10.0)
    }
}

impl Default for SteeringConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where the body is, as the navigator reads it: the position in the source's world and
/// how that world is turned from the estimate's (ψ: source = estimate turned by ψ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionView {
    pub position_m: [f64; 2],
    pub yaw_offset_rad: f64,
}

impl PositionView {
    /// The fused position while it may be steered by (`WorldPosition::valid`).
    pub fn of(w: &crate::controller_interface::position::WorldPosition) -> Option<Self> {
        w.valid().then_some(Self {
            position_m: w.position_m,
            yaw_offset_rad: w.yaw_offset_rad,
        })
    }
}

/// What steering makes of a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Course {
    /// The direction to travel, the source's world, rad.
    pub travel_rad: f64,
    /// Left of the line, m.
    pub cross_track_m: f64,
    pub distance_m: f64,
    pub arrived: bool,
    /// Moved less than `progress_min_m` over the last `progress_window_s`.
    pub no_progress: bool,
    /// Came less than `progress_min_m` nearer the goal over it.
    pub no_nearer: bool,
}

/// One position a second: a window of up to this many seconds.
const PROGRESS_SLOTS: usize = 64;

/// Going to `goal` by position.
#[derive(Debug, Clone)]
pub struct GoalSteering {
    config: SteeringConfig,
    goal: [f64; 2],
    /// Where the line starts (the first position seen).
    origin: Option<[f64; 2]>,
    /// y_i.
    integral: f64,
    last_t: Option<f64>,
    /// Positions and distances to the goal, one a second, the newest at `head`.
    positions: [[f64; 2]; PROGRESS_SLOTS],
    distances: [f64; PROGRESS_SLOTS],
    head: usize,
    filled: usize,
    next_sample_s: f64,
}

impl GoalSteering {
    pub fn new(config: SteeringConfig, goal: [f64; 2]) -> Self {
        Self {
            config,
            goal,
            origin: None,
            integral: 0.0,
            last_t: None,
            positions: [[f64::NAN; 2]; PROGRESS_SLOTS],
            distances: [f64::NAN; PROGRESS_SLOTS],
            head: 0,
            filled: 0,
            next_sample_s: f64::NEG_INFINITY,
        }
    }

    pub fn goal(&self) -> [f64; 2] {
        self.goal
    }

    /// The line's direction (from where it started, or from `p` before that), the
    /// source's world, rad.
    pub fn line_rad(&self, p: [f64; 2]) -> f64 {
        let o = self.origin.unwrap_or(p);
        (self.goal[1] - o[1]).atan2(self.goal[0] - o[0])
    }

    /// The share of the correction for a body whose axis lies `axis_error_rad` from
    /// where it must lie (see [`SteeringConfig::authority_rad`]).
    pub fn authority(&self, axis_error_rad: f64) -> f64 {
        let [full, none] = self.config.authority_rad;
        ((none - axis_error_rad) / (none - full)).clamp(0.0, 1.0)
    }

    pub fn config(&self) -> &SteeringConfig {
        &self.config
    }

    /// Forgets the progress seen (after a change of what runs: the new gait starts its
    /// window afresh).
    pub fn restart_progress(&mut self) {
        self.filled = 0;
        self.next_sample_s = f64::NEG_INFINITY;
    }

    /// Forgets the time of the last update (the position went invalid: the integral
    /// does not wind over the gap).
    pub fn pause(&mut self) {
        self.last_t = None;
        self.restart_progress();
    }

    /// The course at time `t_s` from position `p` (the source's world), with
    /// `authority` (0..1) the share of the cross-track correction the gait can take
    /// now: a sidewinding body lying along the line travels across it either way, so
    /// an aim-off would only flip it from side to side; the integral waits as well.
    pub fn update(&mut self, t_s: f64, p: [f64; 2], authority: f64) -> Course {
        let authority = authority.clamp(0.0, 1.0);
        let c = self.config;
        let origin = *self.origin.get_or_insert(p);
        let (gx, gy) = (self.goal[0] - origin[0], self.goal[1] - origin[1]);
        let length = gx.hypot(gy);
        let line = gy.atan2(gx);
        let (ux, uy) = match length > 1e-9 {
            true => (gx / length, gy / length),
            false => (1.0, 0.0),
        };
        let (dx, dy) = (p[0] - origin[0], p[1] - origin[1]);
        let along = dx * ux + dy * uy;
        let e = -dx * uy + dy * ux;
        let delta = c.lookahead_m;
        if let Some(last) = self.last_t {
            let dt = (t_s - last).clamp(0.0, 1.0);
            let s = e + c.integral_gain * self.integral;
            self.integral += authority * dt * delta * e / (delta * delta + s * s);
            // Bounded so that σ·y_i alone aims off at most the limit.
            if c.integral_gain > 0.0 {
                let most = delta * c.max_aim_off_rad.tan() / c.integral_gain;
                self.integral = self.integral.clamp(-most, most);
            }
        }
        self.last_t = Some(t_s);
        let aim_off = authority
            * ((e + c.integral_gain * self.integral) / delta)
                .atan()
                .clamp(-c.max_aim_off_rad, c.max_aim_off_rad);
        let distance = (self.goal[0] - p[0]).hypot(self.goal[1] - p[1]);
        let arrived = distance <= c.arrive_m || along >= length;
        // Past the line's end the goal itself is aimed at.
        let travel = crate::num::wrap_pi(line - aim_off);
        let (no_progress, no_nearer) = self.progress(t_s, p, distance);
        Course {
            travel_rad: travel,
            cross_track_m: e,
            distance_m: distance,
            arrived,
            no_progress,
            no_nearer,
        }
    }

    /// Records `p` and `distance` once a second; whether, over the whole window, it
    /// moved less than `progress_min_m`, and whether it came less than that nearer.
    fn progress(&mut self, t_s: f64, p: [f64; 2], distance: f64) -> (bool, bool) {
        let c = self.config;
        if c.progress_window_s <= 0.0 {
            return (false, false);
        }
        if t_s >= self.next_sample_s {
            self.next_sample_s = t_s + 1.0;
            self.head = (self.head + 1) % PROGRESS_SLOTS;
            self.positions[self.head] = p;
            self.distances[self.head] = distance;
            self.filled = (self.filled + 1).min(PROGRESS_SLOTS);
        }
        let back = c.progress_window_s.round() as usize;
        if back == 0 || self.filled <= back {
            return (false, false);
        }
        let k = (self.head + PROGRESS_SLOTS - back) % PROGRESS_SLOTS;
        let then = self.positions[k];
        let moved = (p[0] - then[0]).hypot(p[1] - then[1]);
        (
            moved < c.progress_min_m,
            self.distances[k] - distance < c.progress_min_m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_the_line_it_travels_the_line_and_off_it_steers_back() {
        let mut s = GoalSteering::new(SteeringConfig::DEFAULT, [3.0, 0.0]);
        let c = s.update(0.0, [0.0, 0.0], 1.0);
        assert!(c.travel_rad.abs() < 1e-12 && !c.arrived && !c.no_progress);
        assert!((c.distance_m - 3.0).abs() < 1e-12);
        // 0.4 m left of the line: steers right (negative), at least atan(0.4/0.8).
        let c = s.update(0.05, [1.0, 0.4], 1.0);
        assert!((c.cross_track_m - 0.4).abs() < 1e-12);
        assert!(c.travel_rad < -(0.5f64).atan() + 1e-9, "{c:?}");
        let c = s.update(0.1, [1.0, -0.4], 1.0);
        assert!(c.travel_rad > 0.4, "{c:?}");
        // Without authority it travels the line's direction.
        let c = s.update(0.12, [1.0, -0.4], 0.0);
        assert!(c.travel_rad.abs() < 1e-12, "{c:?}");
        let c = s.update(0.15, [2.9, 0.0], 1.0);
        assert!(c.arrived);
        let c = s.update(0.2, [3.5, 1.0], 1.0);
        assert!(c.arrived, "past the end along the line");
    }

    /// A body whose travel bends 0.5 rad left of where it is aimed (sidewinding's
    /// head-first drift among pegs), steered by the plain line of sight, settles off the
    /// line; with the integral it comes back to the line.
    #[test]
    fn the_integral_makes_up_for_a_steady_drift() {
        let run = |integral_gain: f64| {
            let config = SteeringConfig {
                integral_gain,
                progress_window_s: 0.0,
                ..SteeringConfig::DEFAULT
            };
            let mut s = GoalSteering::new(config, [100.0, 0.0]);
            let (mut p, dt, v, drift) = ([0.0, 0.0], 0.05, 0.05, 0.5);
            let mut e = 0.0;
            for k in 0..20_000 {
                let c = s.update(k as f64 * dt, p, 1.0);
                let go = c.travel_rad + drift;
                p = [p[0] + v * dt * go.cos(), p[1] + v * dt * go.sin()];
                e = c.cross_track_m;
            }
            e
        };
        let plain = run(0.0);
        let integral = run(SteeringConfig::DEFAULT.integral_gain);
        assert!(plain > 0.3, "plain LOS settles {plain} m off");
        assert!(integral.abs() < 0.05, "ILOS settles {integral} m off");
    }

    #[test]
    fn no_progress_when_it_comes_no_nearer_over_the_window() {
        let config = SteeringConfig {
            progress_window_s: 5.0,
            ..SteeringConfig::DEFAULT
        };
        let mut s = GoalSteering::new(config, [3.0, 0.0]);
        // Moving 3 cm/s, across the line: 15 cm a window, moving (steered, not stuck).
        for k in 0..200 {
            let t = k as f64 * 0.05;
            let c = s.update(t, [0.0, 0.03 * t], 1.0);
            assert!(!c.no_progress, "{t}");
            // ...but no nearer the goal.
            assert_eq!(c.no_nearer, t > 4.99, "{t}");
        }
        // Standing: after the window, no progress.
        let mut seen = None;
        for k in 0..200 {
            let t = 10.0 + k as f64 * 0.05;
            if s.update(t, [0.0, 0.3], 1.0).no_progress {
                seen.get_or_insert(t);
            }
        }
        let seen = seen.expect("no progress seen");
        assert!((12.0..=16.5).contains(&seen), "{seen}");
        s.restart_progress();
        assert!(!s.update(20.0, [0.0, 0.3], 1.0).no_progress);
        for bad in [
            SteeringConfig {
                lookahead_m: 0.0,
                ..config
            },
            SteeringConfig {
                progress_window_s: 100.0,
                ..config
            },
            SteeringConfig {
                max_aim_off_rad: 2.0,
                ..config
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }
}
