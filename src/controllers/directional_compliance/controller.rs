//! Directional compliance (reference 001, SPEC §8): the lateral serpenoid (and in 3-D
//! a dorsal one on the other joints, eq. 10) whose amplitudes are windowed per plane
//! on travelling half-wave windows, each following shape-space admittance through the
//! filter (NC, PDC, NDC) of the body section its centre is in, the sections keeping
//! the absitions; the temporal phase compliant and central; optionally the windows'
//! spatial frequency compliant too (compliant slithering's, in every mode).

use super::absition::{AmplitudeState, Mode};
use super::calibration::Calibration;
use super::config::{DirectionalComplianceConfig, MAX_SECTIONS, SPATIAL_FREQ_RANGE, Strategy};
use super::report::centre_of;
use super::sections::Sections;
use crate::controller_interface::nominal::{Nominal, lateral_room, within};
use crate::controller_interface::report::ControllerReport;
use crate::controller_interface::{
    CannotFollow, Capabilities, CommandRefused, Controller, ControllerCommand, Handover,
    NominalMismatch, Observation, Tick, same_kind,
};
use crate::controllers::steering::HeadingHold;
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};
use crate::shape::admittance::{AdmittanceSign, ParamState};
use crate::shape::torque::TorqueFilter;
use crate::shape::window::{Window, steepness_for_width};
use crate::shape::window_manager::{Slope, WindowEvents, WindowManager};

/// Most travelling windows on the body.
pub(super) const MAX_WINDOWS: usize = 16;
/// Planes by index.
pub(super) const LAT: usize = 0;
pub(super) const DOR: usize = 1;
/// Signals reported before the per-section ones (names in `super::report_spec`).
pub(super) const FIXED_SIGNALS: usize = 18;

/// A travelling window's state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WindowState {
    /// Its amplitude in each plane (lateral, dorsal).
    pub amplitude: [AmplitudeState; 2],
    /// Its lateral spatial frequency's deviation from nominal (0 unless it complies).
    pub spatial_freq: ParamState,
}

type Payload = WindowState;

/// The controller. Construction allocates; nothing else does.
pub struct DirectionalCompliance {
    pub(super) config: DirectionalComplianceConfig,
    pub(super) layout: BodyLayout,
    pub(super) nominal: Nominal,
    /// Windows anchored to the lateral wave's zero crossings; both planes share them.
    pub(super) manager: WindowManager<Payload>,
    /// Edge steepness of the windows.
    pub(super) m: f64,
    pub(super) phase: ParamState,
    pub(super) filter: TorqueFilter,
    pub(super) tau_ext: Vec<f64>,
    /// `w_j(s_i)`, window-major (`MAX_WINDOWS × joints`).
    pub(super) weights: Vec<f64>,
    /// `∫₀^{s_i} w_j`, the same layout (where window `j`'s spatial frequency moves the
    /// phase of joint `i`).
    pub(super) integrals: Vec<f64>,
    pub(super) forces: [[f64; MAX_WINDOWS]; 2],
    /// Each window's force on its spatial frequency.
    pub(super) spatial_forces: [f64; MAX_WINDOWS],
    pub(super) phase_force: f64,
    pub(super) calibration: Calibration,
    pub(super) sections: Sections,
    /// Each section's amplitude deviation this step, per plane (mean over its joints).
    pub(super) section_deviation: [[f64; MAX_SECTIONS]; 2],
    pub(super) switches: u64,
    /// Dorsal fade-in factor now (0..1).
    pub(super) ramp: f64,
    pub(super) t: f64,
    pub(super) last_events: WindowEvents,
    pub(super) heading: HeadingHold,
}

impl DirectionalCompliance {
    /// For `layout`, following `params` from phase 0 at t = 0 until engaged. The
    /// configuration has passed its checks.
    pub fn new(
        layout: &BodyLayout,
        params: &GaitParams,
        config: DirectionalComplianceConfig,
    ) -> Self {
        let n = layout.len();
        let width = config.edge_width_modules / (n as f64 + 1.0);
        let mut c = Self {
            config,
            layout: layout.clone(),
            nominal: Nominal::new(params),
            manager: WindowManager::new(n + 9, MAX_WINDOWS),
            m: steepness_for_width(width),
            phase: ParamState::default(),
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            tau_ext: vec![0.0; n],
            weights: vec![0.0; MAX_WINDOWS * n],
            integrals: vec![0.0; MAX_WINDOWS * n],
            forces: [[0.0; MAX_WINDOWS]; 2],
            spatial_forces: [0.0; MAX_WINDOWS],
            phase_force: 0.0,
            calibration: Calibration::new(config.friction_offset, config.sections.count),
            sections: Sections::new(config.sections.count, 1.0, Mode::Nc),
            section_deviation: [[0.0; MAX_SECTIONS]; 2],
            switches: 0,
            ramp: 0.0,
            t: 0.0,
            last_events: WindowEvents::default(),
            heading: HeadingHold::new(config.steering),
        };
        c.reset();
        c
    }

    pub fn config(&self) -> &DirectionalComplianceConfig {
        &self.config
    }

    /// What a window is born with: the nominal amplitudes.
    fn born(&self) -> Payload {
        WindowState::default()
    }

    /// The mode a section starts in (and the fixed strategies' for good).
    fn start_mode(&self) -> Mode {
        match self.config.strategy {
            Strategy::Nc | Strategy::Switching => Mode::Nc,
            Strategy::Pdc => Mode::Pdc,
            Strategy::Ndc => Mode::Ndc,
        }
    }

    /// The span of the sections' mean amplitude: `mean_cycles` nominal gait cycles (a
    /// stopped wave, ωT = 0, counts as a cycle of 2π s).
    fn mean_span_s(&self) -> f64 {
        self.config.sections.mean_cycles * self.cycle_s()
    }

    /// A nominal gait cycle, s (a wave slower than 1 rad/s counts as 2π s).
    fn cycle_s(&self) -> f64 {
        std::f64::consts::TAU / self.nominal.params.temporal_freq_rad_s.abs().max(1.0)
    }

    /// Forgets everything learnt but the calibration.
    fn reset(&mut self) {
        self.manager.clear();
        self.phase = ParamState::default();
        self.filter.reset();
        self.forces = [[0.0; MAX_WINDOWS]; 2];
        self.spatial_forces = [0.0; MAX_WINDOWS];
        self.phase_force = 0.0;
        self.switches = 0;
        self.ramp = 0.0;
        self.t = self.nominal.t0_s;
        self.calibration.restart();
        self.sections = Sections::new(
            self.config.sections.count,
            self.mean_span_s(),
            self.start_mode(),
        );
        self.section_deviation = [[0.0; MAX_SECTIONS]; 2];
        self.anchor_windows();
    }

    /// The temporal phase Ω now (nominal plus its compliant lag).
    fn omega(&self) -> f64 {
        self.nominal.phase_at(self.t) + self.phase.deviation
    }

    pub(super) fn spatial_freq(&self) -> f64 {
        self.nominal.params.spatial_freq_rad
    }

    /// Nominal amplitude of a plane.
    pub(super) fn amplitude0(&self, plane: usize) -> f64 {
        if plane == LAT {
            self.nominal.params.amplitude_lat_rad
        } else {
            self.config.dorsal.amplitude_rad
        }
    }

    /// Planes that comply: lateral, and dorsal in 3-D.
    pub(super) fn planes(&self) -> usize {
        if self.config.dorsal.enabled { 2 } else { 1 }
    }

    /// Re-anchors the windows to the lateral wave `φ(s) = ωS·s + Σ_j δωS_j·∫₀^s w_j − Ω`
    /// (the windows' spatial frequencies as they were) and samples their weights and
    /// integrals at the joints. The phase rises along the body: every window's spatial
    /// frequency stays in a positive range.
    fn anchor_windows(&mut self) {
        let (ws, omega, born, m) = (self.spatial_freq(), self.omega(), self.born(), self.m);
        let mut old = [(Window::EVERYWHERE, 0.0); MAX_WINDOWS];
        let mut count = 0;
        for (slot, w) in old.iter_mut().zip(self.manager.windows()) {
            *slot = (w.window, w.payload.spatial_freq.deviation);
            count += 1;
        }
        let old = &old[..count];
        let phase = |s: f64| {
            let shift: f64 = old
                .iter()
                .filter(|(_, d)| *d != 0.0)
                .map(|(w, d)| d * w.integral(s, m))
                .sum();
            ws * s + shift - omega
        };
        self.last_events = self.manager.update(phase, born, Slope::Increasing);
        let n = self.layout.len();
        // The integrals only matter while the spatial frequency complies (else they
        // stay 0 and every deviation is 0): no softplus on the hot path otherwise.
        let spatial = self.config.spatial_freq.enabled;
        for (j, w) in self.manager.windows().enumerate() {
            for (i, &s) in self.layout.s.iter().enumerate() {
                self.weights[j * n + i] = w.window.weight(s, self.m);
                if spatial {
                    self.integrals[j * n + i] = w.window.integral(s, self.m);
                }
            }
        }
    }

    /// Joint `i` in its plane: `(plane, φ_i, A_i, g)` with `θ_i = g·A_i·sin φ_i` (`g`: the
    /// dorsal fade-in, 0 for a planar controller's dorsal joints, 1 for lateral ones).
    fn joint_wave(&self, i: usize) -> (usize, f64, f64, f64) {
        let n = self.layout.len();
        let s = self.layout.s[i];
        let omega = self.omega();
        let (plane, phi, gain) = match self.layout.planes[i] {
            Plane::Lateral => {
                let mut shift = 0.0;
                for (j, w) in self.manager.windows().enumerate() {
                    shift += self.integrals[j * n + i] * w.payload.spatial_freq.deviation;
                }
                (LAT, self.spatial_freq() * s + shift - omega, 1.0)
            }
            Plane::Dorsal => {
                let d = &self.config.dorsal;
                let phi = d.spatial_ratio * self.spatial_freq() * s - d.temporal_ratio * omega
                    + d.phase_shift_rad;
                (DOR, phi, if d.enabled { self.ramp } else { 0.0 })
            }
        };
        let mut deviation = 0.0;
        for (j, w) in self.manager.windows().enumerate() {
            deviation += self.weights[j * n + i] * w.payload.amplitude[plane].deviation;
        }
        (plane, phi, self.amplitude0(plane) + deviation, gain)
    }

    /// Shape forces from the external torques: per window and plane
    /// `F = Σ_i w_j(s_i)·∂θ_i/∂A·τ_i`, on the phase `Σ_i ∂θ_i/∂Ω·τ_i`, and on a
    /// window's spatial frequency the window-local `Σ_i w_j(s_i)·A_i·cos φ_i·∫₀^{s_i} w_j·τ_i`
    /// (compliant slithering's: a window collects the torques of the joints it covers).
    fn compute_forces(&mut self) {
        let n = self.layout.len();
        self.forces = [[0.0; MAX_WINDOWS]; 2];
        self.spatial_forces = [0.0; MAX_WINDOWS];
        self.phase_force = 0.0;
        let spatial = self.config.spatial_freq.enabled;
        let windows = self.manager.len();
        for i in 0..n {
            let (plane, phi, amplitude, gain) = self.joint_wave(i);
            let tau = self.tau_ext[i];
            if gain == 0.0 || tau == 0.0 {
                continue;
            }
            let (sin, cos) = phi.sin_cos();
            for j in 0..windows {
                let w = self.weights[j * n + i];
                self.forces[plane][j] += w * gain * sin * tau;
                if spatial && plane == LAT {
                    self.spatial_forces[j] += w * amplitude * cos * self.integrals[j * n + i] * tau;
                }
            }
            let dphi_domega = if plane == LAT {
                -1.0
            } else {
                -self.config.dorsal.temporal_ratio
            };
            self.phase_force += gain * amplitude * cos * dphi_domega * tau;
        }
    }

    fn integrate(&mut self, dt: f64) {
        let planes = self.planes();
        let calibrating = self.calibration.running();
        let gains = [self.config.lateral, self.config.dorsal.gains];
        let nominal = [self.amplitude0(LAT), self.amplitude0(DOR)];
        let shift = self.config.thresholds.shift_rad;
        let sections = &self.sections;
        let spatial = &self.config.spatial_freq;
        let ws0 = self.nominal.params.spatial_freq_rad;
        for (j, w) in self.manager.windows_mut().enumerate() {
            let centre = centre_of(w.window.a, w.window.b);
            for p in 0..planes {
                let mode = if calibrating {
                    Mode::Nc
                } else {
                    sections.mode_at(centre, p)
                };
                let force = self.forces[p][j];
                w.payload.amplitude[p].step(&gains[p], mode, force, nominal[p], shift, dt);
            }
            if spatial.enabled {
                let force = self.spatial_forces[j];
                w.payload.spatial_freq.step(
                    &spatial.gains,
                    AdmittanceSign::Compliant,
                    force,
                    ws0,
                    dt,
                );
            }
        }
        if self.config.phase.enabled {
            let g = &self.config.phase.gains;
            let nominal = self.nominal.phase_at(self.t);
            self.phase
                .step(g, AdmittanceSign::Compliant, self.phase_force, nominal, dt);
        }
    }

    /// Each section's amplitude deviation now, per plane: the mean over the section's
    /// joints of that plane of `Σ_j w_j(s_i)·δ_j` (what the joints there are driven by).
    fn measure_sections(&mut self) {
        let n = self.layout.len();
        let (mut sum, mut count) = ([[0.0; MAX_SECTIONS]; 2], [[0usize; MAX_SECTIONS]; 2]);
        for i in 0..n {
            let plane = match self.layout.planes[i] {
                Plane::Lateral => LAT,
                Plane::Dorsal => DOR,
            };
            let k = self.sections.index_of(self.layout.s[i]);
            let mut deviation = 0.0;
            for (j, w) in self.manager.windows().enumerate() {
                deviation += self.weights[j * n + i] * w.payload.amplitude[plane].deviation;
            }
            sum[plane][k] += deviation;
            count[plane][k] += 1;
        }
        for p in 0..2 {
            for k in 0..MAX_SECTIONS {
                self.section_deviation[p][k] = if count[p][k] > 0 {
                    sum[p][k] / count[p][k] as f64
                } else {
                    0.0
                };
            }
        }
    }

    /// The sections' means and absitions, and their modes when switching (not while
    /// calibrating).
    fn observe_sections(&mut self, dt: f64) {
        let switching = (self.config.strategy == Strategy::Switching
            && !self.calibration.running())
        .then_some(&self.config.thresholds);
        let o = self.calibration.offsets();
        let offsets = [o.lateral_rad.padded(), o.dorsal_rad.padded()];
        let hold = self.config.hold;
        let max_dwell_s = if hold.max_dwell_cycles > 0.0 {
            hold.max_dwell_cycles * self.cycle_s()
        } else {
            f64::INFINITY
        };
        self.switches += self.sections.update(
            self.planes(),
            &self.section_deviation,
            &offsets,
            dt,
            &hold,
            max_dwell_s,
            switching,
        );
    }

    /// Feeds the calibration this step's section deviations; when it ends, every
    /// section starts afresh in its start mode with zero absition.
    fn calibrate_step(&mut self, dt: f64) {
        if !self.calibration.running() {
            return;
        }
        for p in 0..self.planes() {
            for k in 0..self.sections.count() {
                self.calibration.add(p, k, self.section_deviation[p][k], dt);
            }
        }
        if self.calibration.advance(dt) {
            let mode = self.start_mode();
            self.sections.restart_absitions(mode);
        }
    }

    fn set_points(&self, out: &mut [f64]) {
        for (i, x) in out.iter_mut().enumerate() {
            let (_, phi, amplitude, gain) = self.joint_wave(i);
            *x = gain * amplitude * phi.sin();
        }
    }

    /// Each plane's amplitude averaged over its joints (NaN for a plane without joints
    /// or a planar controller's dorsal plane).
    pub fn mean_amplitude(&self, plane: usize) -> f64 {
        if plane >= self.planes() {
            return f64::NAN;
        }
        let (mut sum, mut count) = (0.0, 0);
        for i in 0..self.layout.len() {
            let (p, _, a, _) = self.joint_wave(i);
            if p == plane {
                sum += a;
                count += 1;
            }
        }
        if count == 0 {
            f64::NAN
        } else {
            sum / count as f64
        }
    }

    /// The windows head to tail: edges and each plane's state.
    pub fn windows(&self) -> impl Iterator<Item = (crate::shape::window::Window, &Payload)> {
        self.manager.windows().map(|w| (w.window, &w.payload))
    }

    pub fn window_events(&self) -> WindowEvents {
        self.last_events
    }

    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// Mode switches since the takeover.
    pub fn switches(&self) -> u64 {
        self.switches
    }

    /// The sections, head to tail.
    pub fn sections(&self) -> &Sections {
        &self.sections
    }
}

impl Controller for DirectionalCompliance {
    /// The nominal lateral amplitude lies in the windows' range, the spatial frequency
    /// is positive (the windows are anchored to a wave running head to tail), and the
    /// amplitudes' ranges with the offsets stay within the joints' range.
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        let g = &self.config.lateral;
        within("amplitude_lat_rad", params.amplitude_lat_rad, g.min, g.max)?;
        let (lo, hi) = if self.config.spatial_freq.enabled {
            let g = &self.config.spatial_freq.gains;
            (g.min, g.max)
        } else {
            SPATIAL_FREQ_RANGE
        };
        within("spatial_freq_rad", params.spatial_freq_rad, lo, hi)?;
        lateral_room(params, g.max)?;
        if self.config.dorsal.enabled {
            let room = JOINT_LIMIT_RAD - self.config.dorsal.gains.max;
            within("offset_dor_rad", params.offset_dor_rad, -room, room)?;
        }
        Ok(())
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.nominal = Nominal::engaged(h);
        self.heading.engage(h.params);
        self.reset();
    }

    /// A change of amplitude, spatial frequency, speed or offsets: the nominal ramps to
    /// it; the windows, the sections' modes and the calibration stay. A reversal of the
    /// wave (its windows would run tail to head) is a fresh takeover.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        let now = self.nominal.target().temporal_freq_rad_s;
        if now * params.temporal_freq_rad_s < 0.0 {
            return Err(CannotFollow("a reversal of the wave's direction"));
        }
        self.nominal.follow(t_s, params);
        self.heading.follow(params);
        Ok(())
    }

    /// Gains whose ranges hold the old ones, thresholds, the torque filter and the
    /// steering, in place; the strategy, the sections, which parts comply, the windows'
    /// edges or the calibration are a rebuild.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        super::config::fits_in_place(&self.config, &new.config)?;
        std::mem::swap(&mut self.config, &mut new.config);
        let c = &self.config;
        self.filter.set(c.torque_cutoff_hz, c.torque_deadband_nm);
        self.heading.set_config(c.steering);
        Ok(())
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let Tick { t_s, dt_s: dt } = tick;
        self.t = t_s;
        self.nominal.advance(t_s);
        self.heading
            .set_nominal_offset(self.nominal.params.offset_lat_rad);
        let d = &self.config.dorsal;
        let since = t_s - self.nominal.t0_s;
        self.ramp = if d.ramp_s > 0.0 {
            let x = (since / d.ramp_s).clamp(0.0, 1.0);
            x * x * (3.0 - 2.0 * x)
        } else {
            1.0
        };
        self.filter.update(dt, obs.torque_nm, &mut self.tau_ext);
        self.anchor_windows();
        self.compute_forces();
        self.integrate(dt);
        self.measure_sections();
        self.observe_sections(dt);
        self.calibrate_step(dt);
        self.set_points(set_points_rad);
        self.nominal.add_offsets(&self.layout, set_points_rad);
        let reach = (0..self.layout.len())
            .map(|i| self.joint_wave(i))
            .filter(|w| w.0 == LAT)
            .fold(0.0_f64, |m, w| m.max(w.2.abs()));
        self.heading.step(tick, obs.body, reach);
        self.heading.add_to(&self.layout, set_points_rad);
    }

    fn report(&self, out: &mut ControllerReport) {
        self.fill_report(out);
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            steers_by_heading: self.heading.holds_heading(),
            calibration: Some(self.calibration.state()),
        }
    }

    fn command(&mut self, command: ControllerCommand) -> Result<(), CommandRefused> {
        match command {
            ControllerCommand::Calibrate { duration_s } => self.calibration.start(duration_s),
            ControllerCommand::ClearCalibration => {
                self.calibration.clear();
                Ok(())
            }
            heading @ ControllerCommand::SetHeading { .. } => self.heading.command(heading),
        }
    }
}

#[cfg(test)]
#[path = "controller_tests.rs"]
mod tests;
