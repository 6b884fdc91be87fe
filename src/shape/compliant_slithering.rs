//! Compliant slithering (SPEC §5): the slithering shape whose amplitude, spatial
//! frequency and temporal phase follow shape-space admittance driven by the joints'
//! torques, each central, windowed (travelling half-wave windows) or per joint.

use super::admittance::ParamState;
use super::controller::{JointController, Measured};
use super::function::ShapeFunction;
use super::report::ComplianceReport;
use super::slithering_config::{Centralization, SlitheringCompliance};
use super::slithering_shape::{Param, SlitheringShape};
use super::torque::TorqueFilter;
use super::window::{Window, steepness_for_width};
use super::window_manager::{WindowEvents, WindowManager};
use crate::gait::{BodyLayout, GaitParams};

/// Most travelling windows on the body (ωS ≤ 4π gives at most 5).
const MAX_WINDOWS: usize = 16;

/// The controller. Construction allocates; [`JointController::step`] does not.
pub struct CompliantSlithering {
    name: &'static str,
    config: SlitheringCompliance,
    /// Nominal A, ωS, and ωT (the phase's nominal is `ωT·t`).
    amplitude0: f64,
    spatial_freq0: f64,
    temporal_freq: f64,
    shape: SlitheringShape,
    manager: WindowManager<[ParamState; 3]>,
    /// States of the fields that are not windowed (1 when central, one per lateral
    /// joint when per joint), by parameter.
    fixed: [Vec<ParamState>; 3],
    per_joint_windows: Vec<Window>,
    filter: TorqueFilter,
    reported: Vec<f64>,
    tau_ext: Vec<f64>,
    sigma: Vec<f64>,
    forces: Vec<f64>,
    last_t: Option<f64>,
    t: f64,
    last_events: WindowEvents,
}

impl CompliantSlithering {
    pub fn new(
        name: &'static str,
        layout: &BodyLayout,
        params: &GaitParams,
        config: SlitheringCompliance,
    ) -> Result<Self, String> {
        config.validate()?;
        let n = layout.len();
        let width = config.edge_width_modules / (n as f64 + 1.0);
        let cap = MAX_WINDOWS.max(n);
        let shape = SlitheringShape::new(layout, steepness_for_width(width), cap);
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
        let fixed = [Param::Amplitude, Param::SpatialFreq, Param::Phase].map(|p| {
            let count = match config.param(p).centralization {
                Centralization::Central => 1,
                Centralization::Windowed => 0,
                Centralization::PerJoint => lat.len(),
            };
            vec![ParamState::default(); count]
        });
        let m = 3 * cap;
        let mut c = Self {
            name,
            config,
            amplitude0: params.amplitude_lat_rad,
            spatial_freq0: params.spatial_freq_rad,
            temporal_freq: params.temporal_freq_rad_s,
            manager: WindowManager::new(n + 9, MAX_WINDOWS),
            shape,
            fixed,
            per_joint_windows,
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            reported: vec![0.0; n],
            tau_ext: vec![0.0; n],
            sigma: Vec::with_capacity(m),
            forces: Vec::with_capacity(m),
            last_t: None,
            t: 0.0,
            last_events: WindowEvents::default(),
        };
        c.start_nominal();
        Ok(c)
    }

    /// The nominal shape at t = 0, so everything can be read before the first step.
    /// Allocates nothing (capacities are set at construction).
    fn start_nominal(&mut self) {
        let ws0 = self.spatial_freq0;
        self.manager.update(|s| ws0 * s, [ParamState::default(); 3]);
        self.assemble();
    }

    pub fn config(&self) -> &SlitheringCompliance {
        &self.config
    }

    /// Nominal value of `p` at the current time.
    fn nominal(&self, p: Param) -> f64 {
        match p {
            Param::Amplitude => self.amplitude0,
            Param::SpatialFreq => self.spatial_freq0,
            Param::Phase => self.temporal_freq * self.t,
        }
    }

    fn windowed(&self, p: Param) -> bool {
        self.config.param(p).centralization == Centralization::Windowed
    }

    /// Writes every field's windows into the shape and σ from the states.
    fn assemble(&mut self) {
        for p in Param::ALL {
            match self.config.param(p).centralization {
                Centralization::Central => self.shape.set_windows(p, [Window::EVERYWHERE]),
                Centralization::PerJoint => self
                    .shape
                    .set_windows(p, self.per_joint_windows.iter().copied()),
                Centralization::Windowed => self
                    .shape
                    .set_windows(p, self.manager.windows().map(|w| w.window)),
            }
        }
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

    /// Shape forces with the SPEC's window-local Jacobian: a window collects torques only
    /// from the joints it covers (for the spatial frequency the exact column would also
    /// reach every joint behind the window, whose phase it shifts).
    fn compute_forces(&mut self) {
        let m = self.shape.steepness();
        self.forces.clear();
        self.forces.resize(self.sigma.len(), 0.0);
        let offsets = Param::ALL.map(|p| self.shape.offset(p));
        for (i, s) in self.shape.lateral_joints() {
            let tau = self.tau_ext[i];
            if tau == 0.0 {
                continue;
            }
            let a = self.shape.field_at(&self.sigma, Param::Amplitude, s);
            let (sin, cos) = self.shape.phase_at(&self.sigma, s).sin_cos();
            for (j, w) in self.shape.windows(Param::Amplitude).iter().enumerate() {
                self.forces[offsets[0] + j] += w.weight(s, m) * sin * tau;
            }
            for (j, w) in self.shape.windows(Param::SpatialFreq).iter().enumerate() {
                self.forces[offsets[1] + j] += w.weight(s, m) * a * cos * w.integral(s, m) * tau;
            }
            for (j, w) in self.shape.windows(Param::Phase).iter().enumerate() {
                self.forces[offsets[2] + j] -= a * cos * w.weight(s, m) * tau;
            }
        }
    }

    fn integrate(&mut self, dt: f64) {
        let compliance = self.config.compliance;
        for p in Param::ALL {
            let pc = *self.config.param(p);
            if !pc.enabled {
                continue;
            }
            let (nominal, at) = (self.nominal(p), self.shape.offset(p));
            let forces = &self.forces[at..];
            if self.windowed(p) {
                for (w, &f) in self.manager.payloads_mut().zip(forces) {
                    w[p.index()].step(&pc.gains, compliance, f, nominal, dt);
                }
            } else {
                for (st, &f) in self.fixed[p.index()].iter_mut().zip(forces) {
                    st.step(&pc.gains, compliance, f, nominal, dt);
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
        let lat = self.shape.lateral_count().max(1) as f64;
        self.shape
            .lateral_s()
            .map(|s| self.value_at(p, s))
            .sum::<f64>()
            / lat
    }

    /// `p`'s value at normalised arc length `s`.
    pub fn value_at(&self, p: Param, s: f64) -> f64 {
        self.shape.field_at(&self.sigma, p, s)
    }
}

impl JointController for CompliantSlithering {
    fn name(&self) -> &'static str {
        self.name
    }

    fn step(&mut self, t_s: f64, measured: &Measured<'_>, set_points_rad: &mut [f64]) {
        let dt = self.last_t.map_or(0.0, |last| (t_s - last).max(0.0));
        self.last_t = Some(t_s);
        self.t = t_s;
        for (r, &m) in self.reported.iter_mut().zip(measured.torque_nm) {
            *r = m;
        }
        self.filter.update(dt, &self.reported, &mut self.tau_ext);
        if Param::ALL.iter().any(|&p| self.windowed(p)) {
            // Anchor the windows to the wave as it stands (last step's fields).
            let shape = &self.shape;
            let sigma = &self.sigma;
            let ready = sigma.len() == shape.param_count();
            let (ws0, omega0) = (self.spatial_freq0, self.temporal_freq * t_s);
            self.last_events = self.manager.update(
                |s| {
                    if ready {
                        shape.phase_at(sigma, s)
                    } else {
                        ws0 * s - omega0
                    }
                },
                [ParamState::default(); 3],
            );
        }
        self.assemble();
        self.compute_forces();
        self.integrate(dt);
        self.assemble();
        self.shape.value(&self.sigma, set_points_rad);
    }

    fn temporal_freq_rad_s(&self) -> f64 {
        self.temporal_freq
    }

    fn for_each_signal(&self, f: &mut dyn FnMut(&str, f64)) {
        let mean = |p: Param| self.lateral_mean(p);
        f("amplitude_mean_rad", mean(Param::Amplitude));
        f("spatial_freq_mean_rad", mean(Param::SpatialFreq));
        f(
            "phase_lag_rad",
            mean(Param::Phase) - self.temporal_freq * self.t,
        );
        f("windows", self.manager.len() as f64);
        let peak = |p: Param| self.field(p).2.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        f("force_amplitude_peak", peak(Param::Amplitude));
        f("force_spatial_freq_peak", peak(Param::SpatialFreq));
        f("force_phase_peak", peak(Param::Phase));
    }

    fn reset(&mut self) {
        self.manager.clear();
        for states in &mut self.fixed {
            states.fill(ParamState::default());
        }
        self.filter.reset();
        self.sigma.clear();
        self.forces.clear();
        self.last_t = None;
        self.t = 0.0;
        self.last_events = WindowEvents::default();
        self.start_nominal();
    }

    fn compliance_report(&self, out: &mut ComplianceReport) {
        out.clear();
        if self.sigma.len() != self.shape.param_count() {
            return; // Not stepped since construction or reset.
        }
        let nominal_phase = self.temporal_freq * self.t;
        for p in Param::ALL {
            let (windows, values, forces) = self.field(p);
            let pc = self.config.param(p);
            let offset = if p == Param::Phase {
                nominal_phase
            } else {
                0.0
            };
            out.fields[p.index()].fill(
                pc.enabled,
                pc.centralization,
                windows,
                values,
                forces,
                offset,
            );
        }
        let mean = |p: Param| self.lateral_mean(p);
        out.amplitude_mean_rad = mean(Param::Amplitude);
        out.spatial_freq_mean_rad = mean(Param::SpatialFreq);
        out.phase_lag_rad = mean(Param::Phase) - nominal_phase;
        out.travelling_windows = self.manager.len();
        out.events = self.last_events;
        out.available = true;
    }
}

#[cfg(test)]
#[path = "compliant_slithering_tests.rs"]
mod tests;
