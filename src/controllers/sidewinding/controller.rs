//! Anti-compliant sidewinding (SPEC §7): the lateral wave from compliant slithering's
//! admittance engine (windowed amplitude, central spatial frequency, sign −1), the
//! dorsal wave on the lateral one's phase shifted by `δ + β`, β from the reversal, and
//! both amplitudes graded along the body by the heading adjustment ([`taper_factor`]).

use super::config::SidewindingConfig;
use std::f64::consts::TAU;

use super::heading::{HeadingAdjust, taper_factor};
use super::reversal::{Reversal, wrap_pi};
use crate::controller_interface::nominal::{Nominal, lateral_room, within};
use crate::controller_interface::report::ControllerReport;
use crate::controller_interface::{
    CannotFollow, Capabilities, CommandRefused, Controller, ControllerCommand, Handover,
    NominalMismatch, Observation, Tick, same_kind,
};
use crate::controllers::compliant_slithering::CompliantSlithering;
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};

/// Signals reported, in order (names and units in `super::report_spec`).
pub(super) const SIGNALS: usize = 12;

/// The controller. Construction allocates; nothing else does.
pub struct AntiCompliantSidewinding {
    config: SidewindingConfig,
    lateral: CompliantSlithering,
    nominal: Nominal,
    /// (joint, normalised arc length) of every joint, by plane.
    lateral_joints: Vec<(usize, f64)>,
    dorsal_joints: Vec<(usize, f64)>,
    reversal: Reversal,
    adjust: HeadingAdjust,
    /// The low-passed heading as a unit vector (cos, sin); `None` before a valid
    /// estimate since the takeover.
    heading: Option<[f64; 2]>,
    /// The nominal heading (the body axis's, in the estimate's world): the operator's,
    /// or the first valid heading after the takeover.
    nominal_heading: Option<f64>,
    /// The operator asked for the heading now to become the nominal one.
    heading_here: bool,
}

impl AntiCompliantSidewinding {
    pub fn new(layout: &BodyLayout, params: &GaitParams, config: SidewindingConfig) -> Self {
        let by_plane = |plane| {
            layout
                .planes
                .iter()
                .zip(&layout.s)
                .enumerate()
                .filter(|(_, (p, _))| **p == plane)
                .map(|(i, (_, &s))| (i, s))
                .collect::<Vec<_>>()
        };
        Self {
            lateral: CompliantSlithering::new(layout, params, config.lateral()),
            nominal: Nominal::new(params),
            lateral_joints: by_plane(Plane::Lateral),
            dorsal_joints: by_plane(Plane::Dorsal),
            reversal: Reversal::default(),
            adjust: HeadingAdjust::default(),
            heading: None,
            nominal_heading: None,
            heading_here: false,
            config,
        }
    }

    /// β now, rad.
    pub fn beta_rad(&self) -> f64 {
        self.reversal.beta_rad
    }

    /// The heading adjustment's taper now.
    pub fn taper(&self) -> f64 {
        self.adjust.taper
    }

    /// The heading adjustment's learnt trim (the taper that goes straight).
    pub fn trim(&self) -> f64 {
        self.adjust.trim
    }

    /// The low-passed heading, rad (`None` before a valid estimate).
    pub fn heading_rad(&self) -> Option<f64> {
        self.heading.map(|[c, s]| s.atan2(c))
    }

    /// How far the held heading is turned from the nominal, signed for the well β is in:
    /// towards the travel, which lies 90° clockwise of the head in the 0 well and 90°
    /// anticlockwise in the π well (the error is the heading less the held one).
    fn lead(&self, well: f64) -> f64 {
        let mirror = if well == 0.0 { 1.0 } else { -1.0 };
        mirror * self.config.heading.lead_rad
    }

    /// Heading relative to the nominal direction, wrapped.
    fn relative_heading(&self) -> Option<f64> {
        Some(wrap_pi(self.heading_rad()? - self.nominal_heading?))
    }

    /// Low-passes the estimate's heading; an invalid or round (no main axis) estimate
    /// leaves it where it was.
    fn track_heading(&mut self, dt: f64, obs: &Observation<'_>) {
        let b = obs.body;
        if !b.valid || b.round || !b.heading_rad.is_finite() {
            return;
        }
        let now = [b.heading_rad.cos(), b.heading_rad.sin()];
        let tau = self.config.heading_filter_s;
        let h = match self.heading {
            None => now,
            Some(h) => {
                let a = if tau > 0.0 { (dt / tau).min(1.0) } else { 1.0 };
                [h[0] + a * (now[0] - h[0]), h[1] + a * (now[1] - h[1])]
            }
        };
        self.heading = Some(h);
        if self.nominal_heading.is_none() || self.heading_here {
            self.nominal_heading = self.heading_rad();
            self.heading_here = false;
        }
    }
}

impl Controller for AntiCompliantSidewinding {
    /// The lateral engine's checks, with room in the joints' range for the amplitudes
    /// the heading adjustment's taper can reach (`1 + turn_taper` at one end).
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        self.lateral.accepts(params)?;
        let grow = if self.config.heading.enabled {
            1.0 + self.config.heading.turn_taper
        } else {
            1.0
        };
        let a = &self.config.amplitude;
        let reach = if a.enabled {
            a.gains.max
        } else {
            params.amplitude_lat_rad
        };
        lateral_room(params, reach * grow)?;
        let room = JOINT_LIMIT_RAD - params.amplitude_dor_rad * grow;
        within("offset_dor_rad", params.offset_dor_rad, -room, room)
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.lateral.engage(h);
        self.nominal = Nominal::engaged(h);
        // The selector's wave has β = 0 and no taper: start there, so nothing jumps.
        self.reversal = Reversal::default();
        self.adjust = HeadingAdjust::new(TAU / self.nominal.params.temporal_freq_rad_s.abs());
        self.heading = None;
    }

    /// A change of speed, amplitudes, spatial frequency, phase shift or offsets: both
    /// waves ramp to it, the windows, β, the trim and the held heading stay. A reversal
    /// of the wave swaps the sense of the reversal's wells: a fresh takeover.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        let now = self.nominal.target().temporal_freq_rad_s;
        if now * params.temporal_freq_rad_s < 0.0 {
            return Err(CannotFollow("a reversal of the wave's direction"));
        }
        self.lateral.follow(t_s, params)?;
        self.nominal.follow(t_s, params);
        self.adjust
            .set_cycle(TAU / params.temporal_freq_rad_s.abs());
        Ok(())
    }

    /// The lateral engine's gains (as compliant slithering takes them), the heading's
    /// filter, the reversal's and the heading adjustment's settings, in place.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        self.lateral.reconfigure(&mut new.lateral)?;
        std::mem::swap(&mut self.config, &mut new.config);
        Ok(())
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let dt = tick.dt_s;
        self.nominal.advance(tick.t_s);
        self.lateral.step(tick, obs, set_points_rad);
        self.track_heading(dt, obs);
        let h = self.relative_heading();
        self.reversal.step(&self.config.reversal, dt, h);
        let well = self.reversal.well();
        let error = h.map(|h| wrap_pi(h - well + self.lead(well)));
        self.adjust.step(&self.config.heading, dt, error, well);

        let p = &self.nominal.params;
        let c = self.adjust.taper;
        for &(i, s) in &self.lateral_joints {
            let wave = set_points_rad[i] - p.offset_lat_rad;
            set_points_rad[i] = p.offset_lat_rad + taper_factor(c, s) * wave;
        }
        let shift = p.phase_shift_rad + self.reversal.beta_rad;
        for &(i, s) in &self.dorsal_joints {
            let phi = self.lateral.wave_phase_at(s);
            set_points_rad[i] =
                p.offset_dor_rad + p.amplitude_dor_rad * taper_factor(c, s) * (phi + shift).sin();
        }
    }

    fn report(&self, out: &mut ControllerReport) {
        self.lateral.report(out);
        let (amplitude, spatial_freq) = (out.signals[0], out.signals[1]);
        let (force_a, force_ws) = (out.signals[6], out.signals[7]);
        let or_nan = |x: Option<f64>| x.unwrap_or(f64::NAN);
        let signals: [f64; SIGNALS] = [
            self.reversal.beta_rad,
            or_nan(self.heading_rad()),
            or_nan(self.nominal_heading),
            or_nan(self.relative_heading().map(|h| {
                let well = self.reversal.well();
                wrap_pi(h - well + self.lead(well))
            })),
            self.adjust.taper,
            self.reversal.reversals as f64,
            if self.heading.is_some() { 1.0 } else { 0.0 },
            amplitude,
            spatial_freq,
            force_a,
            force_ws,
            self.adjust.trim,
        ];
        out.signals.fill(0.0);
        out.signals[..SIGNALS].copy_from_slice(&signals);
    }

    /// It steers by its nominal heading once it has one (the operator's, or the first
    /// valid heading after the takeover).
    fn capabilities(&self) -> Capabilities {
        Capabilities {
            steers_by_heading: self.nominal_heading.is_some(),
            calibration: None,
        }
    }

    /// `SetHeading`: the nominal direction, or the heading now.
    fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        match command.nominal_heading()? {
            Some(h) => {
                self.nominal_heading = Some(h);
                self.heading_here = false;
            }
            None => self.heading_here = true,
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "controller_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "physics_tests.rs"]
mod physics;
