//! The baseline the thesis compares against (SPEC §5): a distributed-feedback central
//! pattern generator. One phase oscillator per lateral joint, coupled to its neighbours
//! so the wave keeps its shape, each with local torque feedback on its own amplitude
//! and frequency. Output `θ_i = r_i·sin(ωS·s_i − ϑ_i)`; with no torque it is the
//! open-loop serpenoid.

use crate::controller_interface::config::{ConfigError, check_range, check_torque_filter};
use crate::controller_interface::nominal::{Nominal, lateral_room, within};
use crate::controller_interface::report::ControllerReport;
use crate::controller_interface::{
    CannotFollow, Controller, Handover, NominalMismatch, Observation, Tick, same_kind,
};
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};
use crate::shape::torque::TorqueFilter;

impl CpgGains {
    /// Every bound (field names as in the configuration).
    pub fn check(&self) -> Result<(), ConfigError> {
        check_range("coupling_per_s", self.coupling_per_s, 0.0, 100.0)?;
        check_range("frequency_feedback", self.frequency_feedback, 0.0, 10.0)?;
        check_range("amplitude_feedback", self.amplitude_feedback, 0.0, 10.0)?;
        check_range(
            "amplitude_time_constant_s",
            self.amplitude_time_constant_s,
            0.01,
            100.0,
        )?;
        check_range(
            "amplitude_min_rad",
            self.amplitude_min_rad,
            0.0,
            JOINT_LIMIT_RAD,
        )?;
        check_range(
            "amplitude_max_rad",
            self.amplitude_max_rad,
            self.amplitude_min_rad,
            JOINT_LIMIT_RAD,
        )?;
        check_torque_filter(self.torque_cutoff_hz, self.torque_deadband_nm)?;
        Ok(())
    }
}

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
    /// Nominal A, ωS, ωT, offsets, and the takeover's phase.
    nominal: Nominal,
    osc: Vec<Oscillator>,
    rates: Vec<f64>,
    layout: BodyLayout,
    filter: TorqueFilter,
    tau_ext: Vec<f64>,
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
            nominal: Nominal::new(params),
            rates: vec![0.0; osc.len()],
            osc,
            layout: layout.clone(),
            filter: TorqueFilter::new(n, gains.torque_cutoff_hz, gains.torque_deadband_nm),
            tau_ext: vec![0.0; n],
            t: 0.0,
        }
    }

    fn reset(&mut self) {
        for o in &mut self.osc {
            o.phase = self.nominal.phase0_rad;
            o.amplitude = self.nominal.params.amplitude_lat_rad;
        }
        self.rates.fill(0.0);
        self.filter.reset();
        self.t = self.nominal.t0_s;
    }
}

impl Controller for Cpg {
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        let (min, max) = (self.gains.amplitude_min_rad, self.gains.amplitude_max_rad);
        within("amplitude_lat_rad", params.amplitude_lat_rad, min, max)?;
        lateral_room(params, max)
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.nominal = Nominal::engaged(h);
        self.reset();
    }

    /// Any change the checks accept: the oscillators' drive (ωT, ωS, the amplitude they
    /// relax to, the offsets) ramps to it; their phases and amplitudes stay.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        self.nominal.follow(t_s, params);
        Ok(())
    }

    /// Gains whose amplitude range holds the oscillators' amplitudes now, in place.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        let (lo, hi) = (new.gains.amplitude_min_rad, new.gains.amplitude_max_rad);
        if !self.osc.iter().all(|o| (lo..=hi).contains(&o.amplitude)) {
            return Err(CannotFollow(
                "an oscillator's amplitude lies outside the new range",
            ));
        }
        std::mem::swap(&mut self.gains, &mut new.gains);
        let g = &self.gains;
        self.filter.set(g.torque_cutoff_hz, g.torque_deadband_nm);
        Ok(())
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let Tick { t_s, dt_s: dt } = tick;
        self.t = t_s;
        self.nominal.advance(t_s);
        self.filter.update(dt, obs.torque_nm, &mut self.tau_ext);
        let g = self.gains;
        let (spatial_freq, temporal_freq, amplitude0) = (
            self.nominal.params.spatial_freq_rad,
            self.nominal.params.temporal_freq_rad_s,
            self.nominal.params.amplitude_lat_rad,
        );
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
            let (sin, cos) = (spatial_freq * o.s - o.phase).sin_cos();
            // Local shape forces: ∂θ/∂ϑ = −r·cos, ∂θ/∂r = sin.
            let phase_force = -o.amplitude * cos * tau;
            self.rates[k] =
                temporal_freq + g.coupling_per_s * coupling + g.frequency_feedback * phase_force;
            let amp_rate = (amplitude0 - o.amplitude) / g.amplitude_time_constant_s
                + g.amplitude_feedback * sin * tau;
            let o = &mut self.osc[k];
            o.amplitude =
                (o.amplitude + amp_rate * dt).clamp(g.amplitude_min_rad, g.amplitude_max_rad);
        }
        set_points_rad.fill(0.0);
        for (o, &rate) in self.osc.iter_mut().zip(&self.rates) {
            o.phase += rate * dt;
            set_points_rad[o.joint] = o.amplitude * (spatial_freq * o.s - o.phase).sin();
        }
        self.nominal.add_offsets(&self.layout, set_points_rad);
    }

    /// Means only: the CPG has no windows.
    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        let n = self.osc.len().max(1) as f64;
        let nominal = self.nominal.phase_at(self.t);
        let (lo, hi) = self
            .osc
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), o| {
                (lo.min(o.phase), hi.max(o.phase))
            });
        out.signals[0] = self.osc.iter().map(|o| o.amplitude).sum::<f64>() / n;
        out.signals[1] = self.osc.iter().map(|o| o.phase - nominal).sum::<f64>() / n;
        out.signals[2] = hi - lo;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller_interface::TickClock;
    use crate::controller_interface::testing::{ObservationBuf, engage_at};
    use crate::controllers::open_loop::OpenLoop;
    use crate::gait::GaitKind;
    use crate::module::MODULE_LENGTH_M;

    #[test]
    fn without_torque_it_is_the_open_loop_gait_and_a_local_push_stays_local() {
        let layout = BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M);
        let params = GaitParams::default_for(GaitKind::Slithering);
        let mut cpg = Cpg::new(&layout, &params, CpgGains::default());
        let mut open = OpenLoop::new(GaitKind::Slithering, &layout, &params);
        let (mut a, mut b) = (vec![0.0; 18], vec![0.0; 18]);
        let zero = [0.0; 18];
        let buf = ObservationBuf::new(18);
        let (mut clock, mut open_clock) = (TickClock::default(), TickClock::default());
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            cpg.step(clock.tick(t), &buf.observe(&zero, &zero), &mut a);
            open.step(open_clock.tick(t), &buf.observe(&zero, &zero), &mut b);
        }
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
        }
        // Push joint 0 along its bend: only the head oscillator's amplitude grows.
        let mut tau = [0.0; 18];
        for k in 3000..4000 {
            let t = k as f64 * 1e-3;
            tau[0] = -3.0 * a[0].signum();
            cpg.step(clock.tick(t), &buf.observe(&zero, &tau), &mut a);
        }
        assert!(
            cpg.osc[0].amplitude > params.amplitude_lat_rad + 0.05,
            "{}",
            cpg.osc[0].amplitude
        );
        assert!((cpg.osc[8].amplitude - params.amplitude_lat_rad).abs() < 0.01);
        let mut report = ControllerReport::EMPTY;
        cpg.report(&mut report);
        assert!(report.signals[0] > params.amplitude_lat_rad);
        // Engaged again: the next steps are a new CPG's, engaged at the same time.
        engage_at(&mut cpg, &layout, &params, 10.0);
        let mut fresh = Cpg::new(&layout, &params, CpgGains::default());
        engage_at(&mut fresh, &layout, &params, 10.0);
        let mut fresh_clock = TickClock::default();
        clock.restart();
        for k in 0..500 {
            let t = 10.0 + k as f64 * 1e-3;
            cpg.step(clock.tick(t), &buf.observe(&zero, &zero), &mut a);
            fresh.step(fresh_clock.tick(t), &buf.observe(&zero, &zero), &mut b);
        }
        assert_eq!(a, b);
    }

    #[test]
    fn gains_out_of_range_are_named() {
        let g = CpgGains {
            coupling_per_s: 1e9,
            ..CpgGains::default()
        };
        assert!(
            g.check()
                .unwrap_err()
                .to_string()
                .contains("coupling_per_s")
        );
        let g = CpgGains {
            amplitude_max_rad: 0.05,
            ..CpgGains::default()
        };
        assert!(
            g.check()
                .unwrap_err()
                .to_string()
                .contains("amplitude_max_rad")
        );
        assert!(CpgGains::default().check().is_ok());
    }
}
