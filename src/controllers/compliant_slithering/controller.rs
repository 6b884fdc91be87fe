//! Compliant slithering (SPEC §5): the slithering shape whose amplitude, spatial
//! frequency and temporal phase follow shape-space admittance driven by the joints'
//! torques, each central, windowed (travelling half-wave windows) or per joint.

use super::config::{Centralization, CompliantSlitheringConfig};
use crate::controller_interface::nominal::{Nominal, lateral_room, within};
use crate::controller_interface::report::{
    ControllerReport, MAX_WINDOWS as REPORT_WINDOWS, WindowField,
};
use crate::controller_interface::{
    CannotFollow, Capabilities, CommandRefused, Controller, ControllerCommand, Handover,
    NominalMismatch, Observation, Tick, same_kind,
};
use crate::controllers::steering::HeadingHold;
use crate::gait::{BodyLayout, GaitParams, Plane};
use crate::shape::ShapeFunction;
use crate::shape::admittance::ParamState;
use crate::shape::slithering_shape::{Param, SlitheringShape};
use crate::shape::torque::TorqueFilter;
use crate::shape::window::{Window, steepness_for_width};
use crate::shape::window_manager::{Slope, WindowEvents, WindowManager};

/// Most travelling windows on the body (ωS ≤ 4π gives at most 5).
const MAX_WINDOWS: usize = 16;

/// Signals reported, in order (names and units in `super::report_spec`).
pub(super) const SIGNALS: usize = 13;

/// The controller. Construction allocates; nothing else does.
pub struct CompliantSlithering {
    config: CompliantSlitheringConfig,
    layout: BodyLayout,
    /// Nominal A, ωS, ωT, offsets; the phase's nominal is `ψ₀ + ωT·(t − t₀)`.
    nominal: Nominal,
    windows_born: u64,
    windows_dropped: u64,
    shape: SlitheringShape,
    manager: WindowManager<[ParamState; 3]>,
    /// States of the fields that are not windowed (1 when central, one per lateral
    /// joint when per joint), by parameter.
    fixed: [Vec<ParamState>; 3],
    /// The windowed fields: they share the manager's windows.
    windowed: Vec<Param>,
    filter: TorqueFilter,
    reported: Vec<f64>,
    tau_ext: Vec<f64>,
    sigma: Vec<f64>,
    forces: Vec<f64>,
    t: f64,
    last_events: WindowEvents,
    heading: HeadingHold,
}

impl CompliantSlithering {
    /// For `layout`, following `params` from phase 0 at t = 0 until engaged. The
    /// configuration has passed its checks.
    pub fn new(
        layout: &BodyLayout,
        params: &GaitParams,
        config: CompliantSlitheringConfig,
    ) -> Self {
        let n = layout.len();
        let width = config.edge_width_modules / (n as f64 + 1.0);
        let lateral = layout
            .planes
            .iter()
            .filter(|&&p| p == Plane::Lateral)
            .count();
        let with = |c| -> Vec<Param> {
            let is = |p: &Param| config.param(*p).centralization == c;
            Param::ALL.into_iter().filter(is).collect()
        };
        let max_windows = Param::ALL.map(|p| match config.param(p).centralization {
            Centralization::Central => 1,
            Centralization::Windowed => MAX_WINDOWS,
            Centralization::PerJoint => lateral,
        });
        let mut shape = SlitheringShape::new(layout, steepness_for_width(width), max_windows);
        let lat: Vec<f64> = shape.lateral_s().collect();
        let mut per_joint_windows = Vec::with_capacity(lat.len());
        for (k, _) in lat.iter().enumerate() {
            let a = if k == 0 {
                f64::NEG_INFINITY
            } else {
                0.5 * (lat[k - 1] + lat[k])
            };
            let b = if k + 1 == lat.len() {
                f64::INFINITY
            } else {
                0.5 * (lat[k] + lat[k + 1])
            };
            per_joint_windows.push(Window { a, b });
        }
        shape.set_windows(&with(Centralization::PerJoint), per_joint_windows);
        let fixed = [Param::Amplitude, Param::SpatialFreq, Param::Phase].map(|p| {
            let count = match config.param(p).centralization {
                Centralization::Central => 1,
                Centralization::Windowed => 0,
                Centralization::PerJoint => lat.len(),
            };
            vec![ParamState::default(); count]
        });
        let values = max_windows.iter().sum();
        let mut c = Self {
            config,
            layout: layout.clone(),
            nominal: Nominal::new(params),
            windows_born: 0,
            windows_dropped: 0,
            manager: WindowManager::new(n + 9, MAX_WINDOWS),
            shape,
            fixed,
            windowed: with(Centralization::Windowed),
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            reported: vec![0.0; n],
            tau_ext: vec![0.0; n],
            sigma: Vec::with_capacity(values),
            forces: Vec::with_capacity(values),
            t: 0.0,
            last_events: WindowEvents::default(),
            heading: HeadingHold::new(config.steering),
        };
        c.start_nominal();
        c
    }

    /// The nominal shape at t = 0, so everything can be read before the first step.
    /// Allocates nothing (capacities are set at construction).
    fn start_nominal(&mut self) {
        let (ws0, omega0) = (
            self.nominal.params.spatial_freq_rad,
            self.nominal_phase(self.t),
        );
        let slope = if ws0 > 0.0 {
            Slope::Increasing
        } else {
            Slope::Unknown
        };
        self.manager
            .update(|s| ws0 * s - omega0, [ParamState::default(); 3], slope);
        self.place_windows();
        self.fill_sigma();
    }

    pub fn config(&self) -> &CompliantSlitheringConfig {
        &self.config
    }

    /// Nominal value of `p` at the current time.
    fn nominal(&self, p: Param) -> f64 {
        match p {
            Param::Amplitude => self.nominal.params.amplitude_lat_rad,
            Param::SpatialFreq => self.nominal.params.spatial_freq_rad,
            Param::Phase => self.nominal_phase(self.t),
        }
    }

    /// The nominal temporal phase Ω₀ at `t_s`.
    fn nominal_phase(&self, t_s: f64) -> f64 {
        self.nominal.phase_at(t_s)
    }

    fn windowed(&self, p: Param) -> bool {
        self.config.param(p).centralization == Centralization::Windowed
    }

    /// Gives the windowed fields the manager's windows (the others' never change).
    fn place_windows(&mut self) {
        let windows = self.manager.windows().map(|w| w.window);
        self.shape.set_windows(&self.windowed, windows);
    }

    /// σ from the states.
    fn fill_sigma(&mut self) {
        self.sigma.clear();
        for p in Param::ALL {
            let nominal = self.nominal(p);
            if self.windowed(p) {
                let i = p.index();
                self.sigma
                    .extend(self.manager.windows().map(|w| w.payload[i].value(nominal)));
            } else {
                self.sigma
                    .extend(self.fixed[p.index()].iter().map(|s| s.value(nominal)));
            }
        }
    }

    /// Shape forces on σ from the external torques (see
    /// [`SlitheringShape::local_forces`]).
    fn compute_forces(&mut self) {
        self.forces.clear();
        self.forces.resize(self.sigma.len(), 0.0);
        let (sigma, tau) = (&self.sigma, &self.tau_ext);
        self.shape.local_forces(sigma, tau, &mut self.forces);
    }

    /// What the window manager may assume of φ along the body: with windows that tile
    /// it (weights ≥ 0 summing to 1), `φ′ = Σ ωS_j·w_j − Σ Ω_j·w_j′` is positive when
    /// the phase is one value and every ωS is positive.
    fn slope(&self) -> Slope {
        let ws = self.shape.windows(Param::SpatialFreq);
        let at = self.shape.offset(Param::SpatialFreq);
        let increasing = self.shape.windows(Param::Phase).len() == 1
            && ws.iter().all(|w| w.a <= w.b)
            && self.sigma[at..at + ws.len()].iter().all(|&v| v > 0.0);
        if increasing {
            Slope::Increasing
        } else {
            Slope::Unknown
        }
    }

    fn integrate(&mut self, dt: f64) {
        let sign = self.config.sign;
        for p in Param::ALL {
            let pc = *self.config.param(p);
            if !pc.enabled {
                continue;
            }
            let (nominal, at) = (self.nominal(p), self.shape.offset(p));
            let forces = &self.forces[at..];
            if self.windowed(p) {
                for (w, &f) in self.manager.payloads_mut().zip(forces) {
                    w[p.index()].step(&pc.gains, sign, f, nominal, dt);
                }
            } else {
                for (st, &f) in self.fixed[p.index()].iter_mut().zip(forces) {
                    st.step(&pc.gains, sign, f, nominal, dt);
                }
            }
        }
    }

    /// The windows and the last update's births and drops.
    pub fn window_events(&self) -> WindowEvents {
        self.last_events
    }

    /// `p`'s windows, current values and last shape forces.
    pub fn field(&self, p: Param) -> (&[Window], &[f64], &[f64]) {
        let at = self.shape.offset(p);
        let len = self.shape.windows(p).len();
        let forces = self.forces.get(at..at + len).unwrap_or(&[]);
        (self.shape.windows(p), &self.sigma[at..at + len], forces)
    }

    /// `p`'s mean over the lateral joints.
    pub fn lateral_mean(&self, p: Param) -> f64 {
        self.shape.lateral_mean(&self.sigma, p)
    }

    /// The wave's phase `φ(s)` at normalised arc length `s` (what a second wave on the
    /// other plane follows, e.g. sidewinding's dorsal one).
    pub fn wave_phase_at(&self, s: f64) -> f64 {
        self.shape.phase_at(&self.sigma, s)
    }

    /// `p`'s value at normalised arc length `s`.
    pub fn value_at(&self, p: Param, s: f64) -> f64 {
        self.shape.field_at(&self.sigma, p, s)
    }
}

impl CompliantSlithering {
    /// Forgets everything learnt: the next step is a fresh controller's.
    fn reset(&mut self) {
        self.manager.clear();
        for states in &mut self.fixed {
            states.fill(ParamState::default());
        }
        self.filter.reset();
        self.sigma.clear();
        self.forces.clear();
        self.t = self.nominal.t0_s;
        self.last_events = WindowEvents::default();
        self.windows_born = 0;
        self.windows_dropped = 0;
        self.start_nominal();
    }

    /// One step of the shape (without the steering offsets).
    fn step_shape(&mut self, tick: Tick, torque_nm: &[f64], set_points_rad: &mut [f64]) {
        let Tick { t_s, dt_s: dt } = tick;
        self.t = t_s;
        for (r, &m) in self.reported.iter_mut().zip(torque_nm) {
            *r = m;
        }
        self.filter.update(dt, &self.reported, &mut self.tau_ext);
        if !self.windowed.is_empty() {
            // Anchor the windows to the wave as it stands (last step's fields; σ always
            // matches the shape: construction and reset fill it).
            let slope = self.slope();
            let (shape, sigma) = (&self.shape, &self.sigma);
            let phase_at = |s| shape.phase_at(sigma, s);
            self.last_events = self
                .manager
                .update(phase_at, [ParamState::default(); 3], slope);
            let ev = self.last_events;
            self.windows_born += (ev.born_at_head + ev.born_at_tail) as u64;
            self.windows_dropped += (ev.dropped_at_tail + ev.dropped_at_head) as u64;
            self.place_windows();
        }
        self.fill_sigma();
        self.compute_forces();
        self.integrate(dt);
        self.fill_sigma();
        self.shape.set_points(&self.sigma, set_points_rad);
    }

    fn fill_field(&self, p: Param, out: &mut WindowField) {
        let (windows, values, forces) = self.field(p);
        let offset = if p == Param::Phase {
            self.nominal_phase(self.t)
        } else {
            0.0
        };
        out.count = windows.len();
        for (k, w) in windows.iter().take(REPORT_WINDOWS).enumerate() {
            out.a[k] = w.a;
            out.b[k] = w.b;
            out.columns[0][k] = values.get(k).map_or(f64::NAN, |v| v - offset);
            out.columns[1][k] = forces.get(k).copied().unwrap_or(0.0);
        }
    }
}

impl CompliantSlithering {
    /// Whether `next` can replace the configuration in place: the same shape (which
    /// parameters comply, how each is spread, the windows' edges) and every complying
    /// parameter's value now within its new range (else the next step would clamp it:
    /// a jump).
    fn config_fits(&self, next: &CompliantSlitheringConfig) -> Result<(), CannotFollow> {
        let old = &self.config;
        if old.edge_width_modules != next.edge_width_modules {
            return Err(CannotFollow("the windows' edge width changes the shape"));
        }
        for p in Param::ALL {
            let (a, b) = (old.param(p), next.param(p));
            if a.centralization != b.centralization || a.enabled != b.enabled {
                return Err(CannotFollow(
                    "which parameters comply, or how they are spread, changes the shape",
                ));
            }
            // Not stepped since construction or reset: nothing to keep in range.
            let stepped = self.sigma.len() == self.shape.param_count();
            let (lo, hi) = (b.gains.min, b.gains.max);
            if b.enabled && stepped && !self.field(p).1.iter().all(|v| (lo..=hi).contains(v)) {
                return Err(CannotFollow(
                    "a parameter's value now lies outside its new range",
                ));
            }
        }
        Ok(())
    }

    /// The largest lateral amplitude the controller may command with `params`, rad.
    fn reach(&self, params: &GaitParams) -> f64 {
        let a = &self.config.amplitude;
        if a.enabled {
            a.gains.max
        } else {
            params.amplitude_lat_rad
        }
    }
}

impl CompliantSlithering {
    /// The largest lateral amplitude the shape commands now, rad.
    fn amplitude_now(&self) -> f64 {
        if !self.config.amplitude.enabled || self.sigma.len() != self.shape.param_count() {
            return self.nominal.params.amplitude_lat_rad;
        }
        self.field(Param::Amplitude)
            .1
            .iter()
            .fold(0.0_f64, |m, a| m.max(a.abs()))
    }
}

impl Controller for CompliantSlithering {
    /// Each compliant parameter's nominal value lies in its range (else the first
    /// step would clamp it and the wave would jump), and the amplitude's range with
    /// the lateral offset stays within the joints' range.
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        for (p, value, field) in [
            (
                Param::Amplitude,
                params.amplitude_lat_rad,
                "amplitude_lat_rad",
            ),
            (
                Param::SpatialFreq,
                params.spatial_freq_rad,
                "spatial_freq_rad",
            ),
        ] {
            let pc = self.config.param(p);
            if pc.enabled {
                within(field, value, pc.gains.min, pc.gains.max)?;
            }
        }
        lateral_room(params, self.reach(params))
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.nominal = Nominal::engaged(h);
        self.heading.engage(h.params);
        self.reset();
    }

    /// Any change the checks accept: the nominal ramps to it (`Nominal::follow`), the
    /// windows and their states stay, and the steering's cycle follows the speed.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        self.nominal.follow(t_s, params);
        self.heading.follow(params);
        Ok(())
    }

    /// Gains, rates, ranges that hold the values now, the torque filter, the sign and
    /// the steering, in place; a change of which parameters comply or how they are
    /// spread, or of the windows' edges, changes the shape itself: rebuilt.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        self.config_fits(&new.config)?;
        std::mem::swap(&mut self.config, &mut new.config);
        let c = &self.config;
        self.filter.set(c.torque_cutoff_hz, c.torque_deadband_nm);
        self.heading.set_config(c.steering);
        Ok(())
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        self.nominal.advance(tick.t_s);
        self.heading
            .set_nominal_offset(self.nominal.params.offset_lat_rad);
        self.step_shape(tick, obs.torque_nm, set_points_rad);
        self.nominal.add_offsets(&self.layout, set_points_rad);
        self.heading.step(tick, obs.body, self.amplitude_now());
        self.heading.add_to(&self.layout, set_points_rad);
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            steers_by_heading: self.heading.holds_heading(),
            calibration: None,
        }
    }

    /// `SetHeading`: the direction the steering holds.
    fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        self.heading.command(command)
    }

    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        let mean = |p: Param| self.lateral_mean(p);
        let peak = |p: Param| self.field(p).2.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let steer = self.heading.signals();
        let signals: [f64; SIGNALS] = [
            mean(Param::Amplitude),
            mean(Param::SpatialFreq),
            mean(Param::Phase) - self.nominal_phase(self.t),
            self.manager.len() as f64,
            self.windows_born as f64,
            self.windows_dropped as f64,
            peak(Param::Amplitude),
            peak(Param::SpatialFreq),
            peak(Param::Phase),
            steer[0],
            steer[1],
            steer[2],
            steer[3],
        ];
        out.signals[..SIGNALS].copy_from_slice(&signals);
        if self.sigma.len() != self.shape.param_count() {
            return; // Not stepped since construction or reset.
        }
        for p in Param::ALL {
            self.fill_field(p, &mut out.fields[p.index()]);
        }
    }
}

#[cfg(test)]
#[path = "controller_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "reference_tests.rs"]
mod reference;
