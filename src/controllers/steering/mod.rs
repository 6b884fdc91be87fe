//! Steering slithering by a heading (issue 28, point 1): the body's heading from the
//! pose estimate (the virtual chassis), held toward a nominal direction by the gait's
//! steering knob, a lateral joint offset φ_lat that bends the whole body to one side.
//! Shared by the slithering controllers (not a controller itself: no registry line);
//! each adds [`HeadingHold::offset_rad`] to its lateral joints and hands it
//! `controller.heading` commands.
//!
//! Why the offset: it turns the body nearly linearly with its size on open ground
//! (docs/measurements/slithering.md: −4.3 / −8.2 / −14.7° per cycle at 0.05 / 0.1 / 0.2 rad with
//! the default wave, 5-6× that with the sleeve's one wave of A 1.1), its sign the same
//! for both waves (a positive offset turns the body clockwise), and it keeps the wave
//! itself untouched, so the compliance above it sees the same shape.
//!
//! The law, pure and with time as an argument: the heading error is taken from the
//! body's mean heading over the last gait cycle (the virtual chassis sways with the
//! wave; a whole cycle cancels the sway); outside a dead-band the offset is
//! proportional to the error beyond the band, `φ = σ·(c/G)·(|e| − band)·sign(e)`, σ the
//! turn's sign times the wave's direction (a body backing along the same arc turns
//! the other way), at most `max_offset_rad` and the joints' room, and it moves at most
//! `rate_rad_s` (the set-points never jump). No estimate: the offset returns to zero.
//! The error is the mean heading's, less what the offset turns in the half cycle the
//! mean lags by (`σ·G·φ/2`): without it a body freed among pegs with the offset at
//! its limit turned on for two cycles past the nominal.
//!
//! `G` is the wave's turn per cycle per radian of offset, learnt cycle by cycle: it is
//! 1.5 rad for the default wave and about 9 for the sleeve's (measured), so one fixed
//! gain either turned the one too slowly or made the other overshoot by half a radian.
//! With `c` = `correct_per_cycle`, each cycle corrects about that share of the error.
//! Where the error grew over the last cycle despite the offset (pegs turning the
//! body), an integral of the offset over `integral_cycles` cycles adds to it and keeps
//! what it learnt: among the sleeve board's pegs the proportional part alone let the
//! body turn 1.2 rad off in 12 s with 0.07 rad of offset. (Integrating always, or
//! whenever the error did not shrink, overshot the slow default wave on open ground.)

mod cycle_mean;

use std::f64::consts::TAU;

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_range};
use crate::controller_interface::{BodyEstimate, CommandRefused, ControllerCommand, Tick};
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};
use crate::num::wrap_pi;
use cycle_mean::CycleMean;

/// The steering's settings (a slithering controller's `steering` section).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SteeringConfig {
    /// Hold the heading the body has when the controller takes over; otherwise it
    /// steers only once it is given a heading (`controller.heading`).
    pub hold_at_engage: bool,
    /// Half-width of the dead-band around the nominal heading, rad.
    pub deadband_rad: f64,
    /// The share of the heading error beyond the band to correct in one gait cycle.
    pub correct_per_cycle: f64,
    /// The turn per gait cycle per radian of offset assumed before any is measured,
    /// rad/rad, and the range its measurements are kept in.
    pub sensitivity_prior: f64,
    pub sensitivity_min: f64,
    pub sensitivity_max: f64,
    /// The integral's time, in gait cycles, while the body turns away from the
    /// nominal despite the offset (0: no integral).
    pub integral_cycles: f64,
    /// Largest |offset|, rad (also bounded by the joints' room above the wave).
    pub max_offset_rad: f64,
    /// Largest rate of change of the offset, rad/s.
    pub rate_rad_s: f64,
    /// Which way a positive offset turns the body's heading going forwards: −1
    /// (clockwise, measured in the physics for both the default and the sleeve wave).
    pub turn_sign: f64,
}

impl SteeringConfig {
    pub const DEFAULT: Self = Self {
        hold_at_engage: false,
        deadband_rad: 0.1,
        correct_per_cycle: 0.7,
        sensitivity_prior: 8.0,
        sensitivity_min: 1.0,
        sensitivity_max: 12.0,
        integral_cycles: 1.0,
        max_offset_rad: 0.25,
        rate_rad_s: 0.1,
        turn_sign: -1.0,
    };

    /// Every bound (field paths relative to the section).
    pub fn check(&self) -> Result<(), ConfigError> {
        check_range("deadband_rad", self.deadband_rad, 0.0, 1.0)?;
        check_range("correct_per_cycle", self.correct_per_cycle, 0.0, 1.0)?;
        check_range("integral_cycles", self.integral_cycles, 0.0, 100.0)?;
        check_range("sensitivity_min", self.sensitivity_min, 0.1, 100.0)?;
        check_range(
            "sensitivity_max",
            self.sensitivity_max,
            self.sensitivity_min,
            100.0,
        )?;
        check_range(
            "sensitivity_prior",
            self.sensitivity_prior,
            self.sensitivity_min,
            self.sensitivity_max,
        )?;
        check_range("max_offset_rad", self.max_offset_rad, 0.0, 0.5)?;
        check_range("rate_rad_s", self.rate_rad_s, 1e-3, 2.0)?;
        if self.turn_sign != 1.0 && self.turn_sign != -1.0 {
            return Err(ConfigError::invalid("turn_sign", "must be 1 or -1"));
        }
        Ok(())
    }
}

impl Default for SteeringConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the steering is doing (its `steering` signal).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SteeringState {
    /// No nominal heading: no offset.
    Off = 0,
    /// Within the dead-band.
    Holding = 1,
    /// Turning toward the nominal heading.
    Turning = 2,
    /// A nominal heading but no valid pose estimate: the offset returns to zero.
    NoEstimate = 3,
}

/// The heading hold of one slithering controller.
#[derive(Debug, Clone)]
pub struct HeadingHold {
    config: SteeringConfig,
    /// The nominal heading, rad in the pose estimate's world.
    nominal: Option<f64>,
    /// Take the (mean) heading now as the nominal at the next valid estimate.
    take_here: bool,
    mean: CycleMean,
    /// σ: the turn's sign for the wave's direction.
    sign: f64,
    /// |The nominal lateral offset|, rad: the steering's room is above it.
    nominal_offset_rad: f64,
    offset: f64,
    error: f64,
    state: SteeringState,
    /// The learnt turn per cycle per radian of offset (`G`).
    sensitivity: f64,
    cycle: CycleTurn,
    /// The integral part of the offset, rad.
    trim: f64,
}

/// What one gait cycle turned, for learning `G`.
#[derive(Debug, Clone, Copy, Default)]
struct CycleTurn {
    cycle_s: f64,
    elapsed_s: f64,
    /// ∫offset dt over the cycle so far, and the previous cycle's mean offset.
    offset_integral: f64,
    last_offset_mean: Option<f64>,
    /// The mean heading at the cycle's start.
    start_heading: Option<f64>,
    /// Measurements of `G` so far.
    measured: u32,
    /// |Heading error| at the cycle's start, and whether it grew over the last cycle
    /// (then the integral runs: the terrain turns the body against the offset).
    start_error: Option<f64>,
    losing: bool,
}

/// A gait cycle of a wave at `omega` rad/s, s (a stopped wave counts as 2π s).
fn cycle_of(omega: f64) -> f64 {
    if omega.abs() > 1e-6 {
        TAU / omega.abs()
    } else {
        TAU
    }
}

/// A cycle whose |heading error| grew by this much was lost to the terrain, rad.
const LOSING_RAD: f64 = 0.05;

/// Below this mean offset over two cycles a cycle's turn says little about `G`, rad.
const LEARN_ABOVE_RAD: f64 = 0.02;

impl HeadingHold {
    pub fn new(config: SteeringConfig) -> Self {
        Self {
            config,
            nominal: None,
            take_here: false,
            mean: CycleMean::new(TAU),
            sign: config.turn_sign,
            nominal_offset_rad: 0.0,
            offset: 0.0,
            error: 0.0,
            state: SteeringState::Off,
            sensitivity: config.sensitivity_prior,
            cycle: CycleTurn::default(),
            trim: 0.0,
        }
    }

    /// Starts afresh for a wave of `params`. A nominal heading the operator gave
    /// survives a takeover; `hold_at_engage` takes the heading now.
    pub fn engage(&mut self, params: &GaitParams) {
        let omega = params.temporal_freq_rad_s;
        let cycle_s = cycle_of(omega);
        self.mean = CycleMean::new(cycle_s);
        self.cycle = CycleTurn {
            cycle_s,
            ..CycleTurn::default()
        };
        self.sensitivity = self.config.sensitivity_prior;
        self.trim = 0.0;
        self.sign = self.config.turn_sign * if omega < 0.0 { -1.0 } else { 1.0 };
        self.nominal_offset_rad = params.offset_lat_rad.abs();
        self.offset = 0.0;
        self.error = 0.0;
        if self.config.hold_at_engage && self.nominal.is_none() {
            self.take_here = true;
        }
        self.state = SteeringState::Off;
    }

    /// The wave changes to `params` while it drives (a followed change): the cycle
    /// its means span and the room the nominal offset leaves follow, what it has learnt
    /// stays. A reversal of the wave reverses the turn's sign. The nominal offset
    /// follows the ramp by [`HeadingHold::set_nominal_offset`].
    pub fn follow(&mut self, params: &GaitParams) {
        let omega = params.temporal_freq_rad_s;
        let cycle_s = cycle_of(omega);
        self.mean.set_cycle(cycle_s);
        self.cycle.cycle_s = cycle_s;
        if omega != 0.0 {
            self.sign = self.config.turn_sign * omega.signum();
        }
    }

    /// Whether it holds a nominal heading (given, or to take at the next estimate).
    pub fn holds_heading(&self) -> bool {
        self.nominal.is_some() || self.take_here
    }

    pub fn config(&self) -> &SteeringConfig {
        &self.config
    }

    /// The nominal offset while a followed change ramps it, rad (each step).
    pub fn set_nominal_offset(&mut self, offset_lat_rad: f64) {
        self.nominal_offset_rad = offset_lat_rad.abs();
    }

    /// A new configuration in place (a gain edit), keeping the learnt sensitivity,
    /// the integral and the nominal heading.
    pub fn set_config(&mut self, config: SteeringConfig) {
        self.config = config;
        self.sensitivity = self
            .sensitivity
            .clamp(config.sensitivity_min, config.sensitivity_max);
    }

    /// `controller.heading`: hold `Some(h)`, or the heading now (`None`).
    pub fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        match command.nominal_heading()? {
            Some(h) => {
                self.nominal = Some(h);
                self.take_here = false;
            }
            None => self.take_here = true,
        }
        Ok(())
    }

    /// The offset at `tick` from the pose estimate `body`, rad (add it to every lateral
    /// joint), with the wave's largest lateral amplitude now `reach_rad`: the offset
    /// leaves the joints within their limit (it shrinks as the compliance widens the
    /// wave, as smoothly as the amplitude grows).
    pub fn step(&mut self, tick: Tick, body: &BodyEstimate, reach_rad: f64) -> f64 {
        let room = (JOINT_LIMIT_RAD - reach_rad - self.nominal_offset_rad)
            .clamp(0.0, self.config.max_offset_rad);
        let valid = body.valid && body.heading_rad.is_finite();
        if valid {
            self.mean.push(tick.dt_s, body.heading_rad);
        }
        let mean = self.mean.mean().filter(|_| valid);
        if let (true, Some(now)) = (self.take_here, mean) {
            self.nominal = Some(now);
            self.take_here = false;
        }
        let target = match (self.nominal, mean) {
            (None, _) => {
                self.state = SteeringState::Off;
                0.0
            }
            (Some(_), None) => {
                self.state = SteeringState::NoEstimate;
                0.0
            }
            (Some(nominal), Some(now)) => {
                self.error = wrap_pi(nominal - now);
                // The cycle mean lags half a cycle: what the offset turns meanwhile.
                let turning = self.sign * self.sensitivity * self.offset / 2.0;
                let error = wrap_pi(self.error - turning);
                let beyond = (error.abs() - self.config.deadband_rad).max(0.0);
                self.state = if beyond > 0.0 {
                    SteeringState::Turning
                } else {
                    SteeringState::Holding
                };
                let gain = self.config.correct_per_cycle / self.sensitivity;
                let proportional = self.sign * gain * beyond * error.signum();
                // A turn the terrain forces against the offset (pegs) is met by the
                // integral, which keeps what it learnt.
                if self.config.integral_cycles > 0.0 && self.cycle.losing {
                    let ti = self.config.integral_cycles * self.cycle.cycle_s;
                    self.trim = (self.trim + proportional * tick.dt_s / ti).clamp(-room, room);
                }
                proportional + self.trim
            }
        };
        let step = self.config.rate_rad_s * tick.dt_s;
        self.offset += (target.clamp(-room, room) - self.offset).clamp(-step, step);
        self.offset = self.offset.clamp(-room, room);
        self.learn(tick.dt_s, mean);
        self.offset
    }

    /// At each whole cycle: the turn of the mean heading over it against the mean
    /// offset of this cycle and the last (the cycle mean lags half a cycle), a
    /// measurement of `G` where the offset was large enough to tell.
    fn learn(&mut self, dt_s: f64, mean: Option<f64>) {
        let c = &mut self.cycle;
        c.elapsed_s += dt_s;
        c.offset_integral += self.offset * dt_s;
        if c.elapsed_s < c.cycle_s {
            return;
        }
        let offset_mean = c.offset_integral / c.elapsed_s;
        let both = c.last_offset_mean.map(|last| 0.5 * (last + offset_mean));
        if let (Some(u), Some(start), Some(now)) = (both, c.start_heading, mean)
            && u.abs() >= LEARN_ABOVE_RAD
        {
            let measured = self.sign * wrap_pi(now - start) / u;
            let (lo, hi) = (self.config.sensitivity_min, self.config.sensitivity_max);
            // The first measurement replaces the prior; later ones are averaged in.
            let weight = if c.measured == 0 { 1.0 } else { 0.5 };
            self.sensitivity += weight * (measured.clamp(lo, hi) - self.sensitivity);
            c.measured += 1;
        }
        // Losing: outside the band, the error grew over the cycle.
        let error = self.nominal.zip(mean).map(|(n, m)| wrap_pi(n - m).abs());
        c.losing = matches!((c.start_error, error),
            (Some(a), Some(b)) if b > a + LOSING_RAD && b > self.config.deadband_rad);
        c.start_error = error;
        c.elapsed_s = 0.0;
        c.offset_integral = 0.0;
        c.last_offset_mean = Some(offset_mean);
        c.start_heading = mean;
    }

    /// The offset of the last step, rad.
    pub fn offset_rad(&self) -> f64 {
        self.offset
    }

    /// Adds the offset to the lateral joints of `set_points_rad`.
    pub fn add_to(&self, layout: &BodyLayout, set_points_rad: &mut [f64]) {
        for (x, plane) in set_points_rad.iter_mut().zip(&layout.planes) {
            if *plane == Plane::Lateral {
                *x += self.offset;
            }
        }
    }

    /// The report's signals: offset (rad), heading error (rad; 0 without a nominal),
    /// state ([`SteeringState`] as a number), the learnt `G`.
    pub fn signals(&self) -> [f64; 4] {
        let error = if self.nominal.is_some() {
            self.error
        } else {
            0.0
        };
        [
            self.offset,
            error,
            self.state as u8 as f64,
            self.sensitivity,
        ]
    }

    /// The names and units of [`HeadingHold::signals`].
    pub const SIGNALS: [(&'static str, &'static str); 4] = [
        ("steer_offset_rad", "rad"),
        ("heading_error_rad", "rad"),
        ("steering", "0 off, 1 holding, 2 turning, 3 no estimate"),
        ("turn_per_cycle_per_rad", "rad/rad"),
    ];
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod physics_tests;
