//! Shape-based compliance for any serpenoid gait (SPEC §3, central): each plane's wave
//! amplitude is scaled by a shape parameter `k_p` (nominal 1) that follows the
//! admittance `M·k̈ + B·k̇ + K·(k − 1) = s·F_p`, with the shape force
//! `F_p = Σ_{i ∈ p} ∂θ_i/∂k_p · τ_ext,i = Σ (θ_i − φ_p)·τ_ext,i`. Compliant (`s = +1`), a
//! body pressed along its bend opens its wave; anti-compliant (`s = −1`, the thesis's
//! sidewinding choice) it pushes back. One parameter per plane, no windows: the
//! windowed controllers of each gait build on the same blocks.

use serde::{Deserialize, Serialize};

use crate::controller_interface::config::{ConfigError, check_torque_filter};
use crate::controller_interface::nominal::Nominal;
use crate::controller_interface::report::{ControllerReport, ReportSpec, SignalSpec};
use crate::controller_interface::{
    BuildContext, CannotFollow, Controller, ControllerKind, Handover, NominalMismatch, Observation,
    Tick, same_kind,
};
use crate::gait::{BodyLayout, GaitKind, GaitParams, JOINT_LIMIT_RAD, Plane, Serpenoid};
use crate::module::MODULE_MAX_SPEED_RAD_S;
use crate::shape::admittance::{AdmittanceGains, AdmittanceSign, ParamState};
use crate::shape::torque::TorqueFilter;

/// One plane's amplitude scale.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneConfig {
    /// Off: the plane keeps its nominal amplitude.
    pub enabled: bool,
    /// Admittance of the scale `k` (nominal 1; `min`/`max` bound `k`).
    pub gains: AdmittanceGains,
}

/// The controller's configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerpenoidAdmittanceConfig {
    pub lateral: PlaneConfig,
    pub dorsal: PlaneConfig,
    /// `compliant` or `anti_compliant`.
    pub sign: AdmittanceSign,
    /// Low-pass cutoff of the joint torques, Hz.
    pub torque_cutoff_hz: f64,
    /// Torques below this (after filtering) are ignored, N·m.
    pub torque_deadband_nm: f64,
}

/// Most a scale may grow or shrink the nominal amplitude.
const SCALE_RANGE: (f64, f64) = (0.0, 2.0);

impl SerpenoidAdmittanceConfig {
    fn with_sign(sign: AdmittanceSign) -> Self {
        let plane = PlaneConfig {
            enabled: true,
            gains: AdmittanceGains {
                mass: 1.0,
                damping: 6.0,
                stiffness: 8.0,
                min: 0.5,
                max: 1.4,
                bias_force: 0.0,
                max_rate: f64::INFINITY,
            },
        };
        Self {
            lateral: plane,
            dorsal: plane,
            sign,
            torque_cutoff_hz: 5.0,
            torque_deadband_nm: 0.3,
        }
    }

    fn check(&self) -> Result<(), ConfigError> {
        let (lo, hi) = SCALE_RANGE;
        for (name, p) in [("lateral", &self.lateral), ("dorsal", &self.dorsal)] {
            p.gains
                .check(lo, hi, 0.0)
                .map_err(|e| e.under(&format!("{name}.gains")))?;
            if p.enabled && !(p.gains.min..=p.gains.max).contains(&1.0) {
                return Err(ConfigError::invalid(
                    format!("{name}.gains"),
                    "the range of the scale must contain its nominal value 1",
                ));
            }
        }
        check_torque_filter(self.torque_cutoff_hz, self.torque_deadband_nm)
    }

    fn plane(&self, p: Plane) -> &PlaneConfig {
        match p {
            Plane::Lateral => &self.lateral,
            Plane::Dorsal => &self.dorsal,
        }
    }
}

/// The registry's entry.
pub struct SerpenoidAdmittanceKind;

impl ControllerKind for SerpenoidAdmittanceKind {
    type Config = SerpenoidAdmittanceConfig;
    const NAME: &'static str = "serpenoid_admittance";
    const SUMMARY: &'static str =
        "each plane's amplitude follows the torques (central shape-based compliance)";
    const GAITS: &'static [GaitKind] = &[
        GaitKind::LinearProgression,
        GaitKind::Slithering,
        GaitKind::Sidewinding,
        GaitKind::Rolling,
        GaitKind::ConicalSidewinding,
    ];
    const PRESETS: &'static [(&'static str, &'static str)] = &[
        ("compliant", "the waves give way to what pushes them"),
        (
            "anti_compliant",
            "the waves push back against what pushes them",
        ),
    ];

    fn preset(name: &str) -> Option<Self::Config> {
        match name {
            "compliant" => Some(SerpenoidAdmittanceConfig::with_sign(
                AdmittanceSign::Compliant,
            )),
            "anti_compliant" => Some(SerpenoidAdmittanceConfig::with_sign(
                AdmittanceSign::AntiCompliant,
            )),
            _ => None,
        }
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(_config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        let s = SignalSpec::new;
        ReportSpec {
            signals: vec![
                s("scale_lateral", ""),
                s("scale_dorsal", ""),
                s("force_lateral", "N·m·rad"),
                s("force_dorsal", "N·m·rad"),
                s("phase_rad", "rad"),
            ],
            fields: Vec::new(),
        }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(SerpenoidAdmittance::new(
            *config, ctx.gait, ctx.layout, ctx.params,
        ))
    }
}

/// The controller (see the module docs). Allocates at construction only.
pub struct SerpenoidAdmittance {
    config: SerpenoidAdmittanceConfig,
    kind: GaitKind,
    layout: BodyLayout,
    wave: Serpenoid,
    /// Amplitude scale per plane (lateral, dorsal): deviation from 1 and its rate.
    scale: [ParamState; 2],
    force: [f64; 2],
    filter: TorqueFilter,
    tau_ext: Vec<f64>,
    nominal: Nominal,
    phase: f64,
}

fn index(p: Plane) -> usize {
    match p {
        Plane::Lateral => 0,
        Plane::Dorsal => 1,
    }
}

impl SerpenoidAdmittance {
    pub fn new(
        config: SerpenoidAdmittanceConfig,
        kind: GaitKind,
        layout: &BodyLayout,
        params: &GaitParams,
    ) -> Self {
        let n = layout.len();
        Self {
            config,
            kind,
            layout: layout.clone(),
            wave: Serpenoid::for_layout(kind, params, layout),
            scale: [ParamState::default(); 2],
            force: [0.0; 2],
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            tau_ext: vec![0.0; n],
            nominal: Nominal::new(params),
            phase: 0.0,
        }
    }

    /// The amplitude scale of `plane` now.
    pub fn scale(&self, plane: Plane) -> f64 {
        self.scale[index(plane)].value(1.0)
    }
}

impl Controller for SerpenoidAdmittance {
    /// The largest scale must keep every joint in range and under the joints' speed.
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        let wave = Serpenoid::for_layout(self.kind, params, &self.layout);
        for plane in [Plane::Lateral, Plane::Dorsal] {
            let pc = self.config.plane(plane);
            let w = wave.wave(plane);
            let k = if pc.enabled { pc.gains.max } else { 1.0 };
            let reach = w.offset_rad.abs() + k * w.amplitude_rad.abs() * wave.max_taper_factor();
            let speed = k
                * w.amplitude_rad.abs()
                * wave.max_taper_factor()
                * wave.temporal_freq_rad_s.abs();
            let field = match plane {
                Plane::Lateral => "amplitude_lat_rad",
                Plane::Dorsal => "amplitude_dor_rad",
            };
            if reach > JOINT_LIMIT_RAD || speed > MODULE_MAX_SPEED_RAD_S {
                let by_reach = (JOINT_LIMIT_RAD - w.offset_rad.abs()) / k;
                let by_speed = MODULE_MAX_SPEED_RAD_S / (k * wave.temporal_freq_rad_s.abs());
                return Err(NominalMismatch {
                    field,
                    value: w.amplitude_rad,
                    min: 0.0,
                    max: by_reach.min(by_speed) / wave.max_taper_factor(),
                });
            }
        }
        Ok(())
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.wave = Serpenoid::for_layout(self.kind, h.params, &self.layout);
        self.scale = [ParamState::default(); 2];
        self.force = [0.0; 2];
        self.filter.reset();
        self.nominal = Nominal::engaged(h);
        self.phase = h.phase_rad;
    }

    /// Any change the checks accept: the wave ramps to it, the scales stay.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        self.nominal.follow(t_s, params);
        Ok(())
    }

    /// Gains, ranges that hold the scales now, the sign and the filter in place;
    /// switching a plane's compliance on or off is a rebuild.
    fn reconfigure(&mut self, new: &mut dyn Controller) -> Result<(), CannotFollow> {
        let new = same_kind::<Self>(new)?;
        for plane in [Plane::Lateral, Plane::Dorsal] {
            let (a, b) = (self.config.plane(plane), new.config.plane(plane));
            if a.enabled != b.enabled {
                return Err(CannotFollow("switching a plane's compliance on or off"));
            }
            if b.enabled && !(b.gains.min..=b.gains.max).contains(&self.scale(plane)) {
                return Err(CannotFollow("a scale now lies outside its new range"));
            }
        }
        std::mem::swap(&mut self.config, &mut new.config);
        let c = &self.config;
        self.filter.set(c.torque_cutoff_hz, c.torque_deadband_nm);
        Ok(())
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let Tick { t_s, dt_s: dt } = tick;
        if self.nominal.ramping(t_s) || self.nominal.params != *self.nominal.target() {
            self.nominal.advance(t_s);
            self.wave = Serpenoid::for_layout(self.kind, &self.nominal.params, &self.layout);
        }
        self.phase = self.nominal.phase_at(t_s);
        self.filter.update(dt, obs.torque_nm, &mut self.tau_ext);
        // The nominal wave: its joints' deviation from the plane's offset is ∂θ/∂k.
        self.wave.evaluate(&self.layout, self.phase, set_points_rad);
        self.force = [0.0; 2];
        for ((&theta, &plane), &tau) in set_points_rad
            .iter()
            .zip(&self.layout.planes)
            .zip(&self.tau_ext)
        {
            self.force[index(plane)] += (theta - self.wave.wave(plane).offset_rad) * tau;
        }
        for plane in [Plane::Lateral, Plane::Dorsal] {
            let pc = self.config.plane(plane);
            if pc.enabled {
                let i = index(plane);
                self.scale[i].step(&pc.gains, self.config.sign, self.force[i], 1.0, dt);
            }
        }
        for (x, &plane) in set_points_rad.iter_mut().zip(&self.layout.planes) {
            let offset = self.wave.wave(plane).offset_rad;
            *x = offset + self.scale(plane) * (*x - offset);
        }
    }

    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        let values = [
            self.scale(Plane::Lateral),
            self.scale(Plane::Dorsal),
            self.force[0],
            self.force[1],
            self.phase,
        ];
        out.signals[..values.len()].copy_from_slice(&values);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller_interface::testing::{engage_at, run_with_torques};
    use crate::controllers::open_loop::OpenLoop;

    const N: usize = 18;

    fn setup(gait: GaitKind) -> (BodyLayout, GaitParams) {
        (
            BodyLayout::alternating(N, Plane::Lateral, 0.064),
            GaitParams::default_for(gait),
        )
    }

    fn preset(name: &str) -> SerpenoidAdmittanceConfig {
        SerpenoidAdmittanceKind::preset(name).expect("a preset")
    }

    #[test]
    fn without_torque_it_is_the_open_loop_gait() {
        for gait in SerpenoidAdmittanceKind::GAITS {
            let (layout, params) = setup(*gait);
            let mut open = OpenLoop::new(*gait, &layout, &params);
            let mut c = SerpenoidAdmittance::new(preset("compliant"), *gait, &layout, &params);
            engage_at(&mut open, &layout, &params, 0.0);
            engage_at(&mut c, &layout, &params, 0.0);
            let a = run_with_torques(&mut open, 3.0, |_| [0.0; N]);
            let b = run_with_torques(&mut c, 3.0, |_| [0.0; N]);
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-12, "{gait:?}: {x} vs {y}");
            }
        }
    }

    /// SPEC §3's sign test on a sidewinding body: pushed along its bend everywhere,
    /// compliant waves open, anti-compliant ones close.
    #[test]
    fn a_push_along_the_bend_opens_compliant_waves_and_closes_anti_compliant_ones() {
        let (layout, params) = setup(GaitKind::Sidewinding);
        // Reported torque against the bend: the environment bends each joint further.
        let push = |sp: &[f64]| {
            let mut tau = [0.0; N];
            for (t, &x) in tau.iter_mut().zip(sp) {
                *t = -2.0 * x.signum() * f64::from(u8::from(x.abs() > 0.05));
            }
            tau
        };
        for (name, wider) in [("compliant", true), ("anti_compliant", false)] {
            let mut c =
                SerpenoidAdmittance::new(preset(name), GaitKind::Sidewinding, &layout, &params);
            engage_at(&mut c, &layout, &params, 0.0);
            run_with_torques(&mut c, 3.0, push);
            for plane in [Plane::Lateral, Plane::Dorsal] {
                let k = c.scale(plane);
                assert_eq!(k > 1.05, wider, "{name} {plane:?}: {k}");
                assert_eq!(k < 0.95, !wider, "{name} {plane:?}: {k}");
            }
        }
    }

    #[test]
    fn bounds_and_reach_are_checked() {
        let mut cfg = preset("compliant");
        cfg.lateral.gains.max = 3.0;
        assert!(
            cfg.check()
                .unwrap_err()
                .to_string()
                .contains("lateral.gains.max")
        );
        let mut cfg = preset("compliant");
        cfg.dorsal.gains.min = 1.1;
        assert!(
            cfg.check()
                .unwrap_err()
                .to_string()
                .contains("dorsal.gains")
        );
        // A sidewinding amplitude that 1.4× would push past the joints' range.
        let (layout, mut params) = setup(GaitKind::Sidewinding);
        let c =
            SerpenoidAdmittance::new(preset("compliant"), GaitKind::Sidewinding, &layout, &params);
        assert!(c.accepts(&params).is_ok());
        params.amplitude_lat_rad = 1.3;
        assert_eq!(c.accepts(&params).unwrap_err().field, "amplitude_lat_rad");
    }
}
