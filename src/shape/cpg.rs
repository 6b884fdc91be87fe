//! The baseline the thesis compares against (SPEC §5): a distributed-feedback central
//! pattern generator. One phase oscillator per lateral joint, coupled to its neighbours
//! so the wave keeps its shape, each with local torque feedback on its own amplitude
//! and frequency. Output `θ_i = r_i·sin(ωS·s_i − ϑ_i)`; with no torque it is the
//! open-loop serpenoid.

use super::controller::{JointController, Measured};
use super::report::ComplianceReport;
use super::torque::TorqueFilter;
use crate::gait::{BodyLayout, GaitParams, Plane};

/// Gains of the CPG.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CpgGains {
    /// Neighbour phase coupling, 1/s.
    pub coupling_per_s: f64,
    /// Phase-rate feedback from the local phase force, rad/s per N·m.
    pub frequency_feedback: f64,
    /// Amplitude feedback from the local amplitude force, rad/s per N·m.
    pub amplitude_feedback: f64,
    /// Time constant of the amplitude's return to nominal, s.
    pub amplitude_time_constant_s: f64,
    pub amplitude_min_rad: f64,
    pub amplitude_max_rad: f64,
    pub torque_cutoff_hz: f64,
    pub torque_deadband_nm: f64,
}

impl Default for CpgGains {
    fn default() -> Self {
        Self {
            coupling_per_s: 4.0,
            frequency_feedback: 0.3,
            amplitude_feedback: 0.3,
            amplitude_time_constant_s: 0.7,
            amplitude_min_rad: 0.1,
            amplitude_max_rad: 1.2,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
        }
    }
}

struct Oscillator {
    joint: usize,
    s: f64,
    phase: f64,
    amplitude: f64,
}

/// The CPG controller. Allocates at construction only.
pub struct Cpg {
    gains: CpgGains,
    amplitude0: f64,
    spatial_freq: f64,
    temporal_freq: f64,
    osc: Vec<Oscillator>,
    rates: Vec<f64>,
    filter: TorqueFilter,
    tau_ext: Vec<f64>,
    last_t: Option<f64>,
    t: f64,
}

impl Cpg {
    pub fn new(layout: &BodyLayout, params: &GaitParams, gains: CpgGains) -> Self {
        let osc: Vec<Oscillator> = layout
            .planes
            .iter()
            .zip(&layout.s)
            .enumerate()
            .filter(|(_, (p, _))| **p == Plane::Lateral)
            .map(|(joint, (_, &s))| Oscillator {
                joint,
                s,
                phase: 0.0,
                amplitude: params.amplitude_lat_rad,
            })
            .collect();
        let n = layout.len();
        Self {
            gains,
            amplitude0: params.amplitude_lat_rad,
            spatial_freq: params.spatial_freq_rad,
            temporal_freq: params.temporal_freq_rad_s,
            rates: vec![0.0; osc.len()],
            osc,
            filter: TorqueFilter::new(n, gains.torque_cutoff_hz, gains.torque_deadband_nm),
            tau_ext: vec![0.0; n],
            last_t: None,
            t: 0.0,
        }
    }
}

impl JointController for Cpg {
    fn name(&self) -> &'static str {
        "cpg"
    }

    fn step(&mut self, t_s: f64, measured: &Measured<'_>, set_points_rad: &mut [f64]) {
        let dt = self.last_t.map_or(0.0, |last| (t_s - last).max(0.0));
        if self.last_t.is_none() {
            for o in &mut self.osc {
                o.phase = self.temporal_freq * t_s;
            }
        }
        self.last_t = Some(t_s);
        self.t = t_s;
        self.filter
            .update(dt, measured.torque_nm, &mut self.tau_ext);
        let g = self.gains;
        let count = self.osc.len();
        for k in 0..count {
            let o = &self.osc[k];
            let mut coupling = 0.0;
            for nb in [k.wrapping_sub(1), k + 1] {
                if let Some(n) = self.osc.get(nb) {
                    coupling += (n.phase - o.phase).sin();
                }
            }
            let tau = self.tau_ext[o.joint];
            let (sin, cos) = (self.spatial_freq * o.s - o.phase).sin_cos();
            // Local shape forces: ∂θ/∂ϑ = −r·cos, ∂θ/∂r = sin.
            let phase_force = -o.amplitude * cos * tau;
            self.rates[k] = self.temporal_freq
                + g.coupling_per_s * coupling
                + g.frequency_feedback * phase_force;
            let amp_rate = (self.amplitude0 - o.amplitude) / g.amplitude_time_constant_s
                + g.amplitude_feedback * sin * tau;
            let o = &mut self.osc[k];
            o.amplitude =
                (o.amplitude + amp_rate * dt).clamp(g.amplitude_min_rad, g.amplitude_max_rad);
        }
        set_points_rad.fill(0.0);
        for (o, &rate) in self.osc.iter_mut().zip(&self.rates) {
            o.phase += rate * dt;
            set_points_rad[o.joint] = o.amplitude * (self.spatial_freq * o.s - o.phase).sin();
        }
    }

    fn temporal_freq_rad_s(&self) -> f64 {
        self.temporal_freq
    }

    fn for_each_signal(&self, f: &mut dyn FnMut(&str, f64)) {
        let n = self.osc.len().max(1) as f64;
        f(
            "amplitude_mean_rad",
            self.osc.iter().map(|o| o.amplitude).sum::<f64>() / n,
        );
        let nominal = self.temporal_freq * self.t;
        f(
            "phase_lag_rad",
            self.osc.iter().map(|o| nominal - o.phase).sum::<f64>() / -n,
        );
        let spread = self
            .osc
            .iter()
            .map(|o| o.phase)
            .fold(f64::NEG_INFINITY, f64::max)
            - self
                .osc
                .iter()
                .map(|o| o.phase)
                .fold(f64::INFINITY, f64::min);
        f("phase_spread_rad", spread);
    }

    fn reset(&mut self) {
        for o in &mut self.osc {
            o.phase = 0.0;
            o.amplitude = self.amplitude0;
        }
        self.rates.fill(0.0);
        self.filter.reset();
        self.last_t = None;
        self.t = 0.0;
    }

    /// Means only: the CPG has no windows.
    fn compliance_report(&self, out: &mut ComplianceReport) {
        out.clear();
        if self.last_t.is_none() {
            return;
        }
        let n = self.osc.len().max(1) as f64;
        let nominal = self.temporal_freq * self.t;
        out.amplitude_mean_rad = self.osc.iter().map(|o| o.amplitude).sum::<f64>() / n;
        out.spatial_freq_mean_rad = self.spatial_freq;
        out.phase_lag_rad = self.osc.iter().map(|o| o.phase - nominal).sum::<f64>() / n;
        out.available = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::servo::MODULE_LENGTH_M;
    use crate::gait::GaitKind;
    use crate::shape::controller::OpenLoopSlithering;

    #[test]
    fn without_torque_it_is_the_open_loop_gait_and_a_local_push_stays_local() {
        let layout = BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M);
        let params = GaitParams::default_for(GaitKind::Slithering);
        let mut cpg = Cpg::new(&layout, &params, CpgGains::default());
        let mut open = OpenLoopSlithering::new(layout.clone(), &params);
        let (mut a, mut b) = (vec![0.0; 18], vec![0.0; 18]);
        let zero = [0.0; 18];
        let m = Measured {
            position_rad: &zero,
            torque_nm: &zero,
        };
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            cpg.step(t, &m, &mut a);
            open.step(t, &m, &mut b);
        }
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
        }
        // Push joint 0 along its bend: only the head oscillator's amplitude grows.
        let mut tau = [0.0; 18];
        for k in 3000..4000 {
            let t = k as f64 * 1e-3;
            tau[0] = -3.0 * a[0].signum();
            cpg.step(
                t,
                &Measured {
                    position_rad: &zero,
                    torque_nm: &tau,
                },
                &mut a,
            );
        }
        assert!(
            cpg.osc[0].amplitude > params.amplitude_lat_rad + 0.05,
            "{}",
            cpg.osc[0].amplitude
        );
        assert!((cpg.osc[8].amplitude - params.amplitude_lat_rad).abs() < 0.01);
        let mut report = ComplianceReport::default();
        cpg.compliance_report(&mut report);
        assert!(report.available && report.amplitude_mean_rad > params.amplitude_lat_rad);
        // Reset: the next steps are a new CPG's.
        cpg.reset();
        let mut fresh = Cpg::new(&layout, &params, CpgGains::default());
        for k in 0..500 {
            let t = 10.0 + k as f64 * 1e-3;
            cpg.step(t, &m, &mut a);
            fresh.step(t, &m, &mut b);
        }
        assert_eq!(a, b);
    }
}
