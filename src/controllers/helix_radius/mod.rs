//! Radius compliance for the rolling helix (SPEC §6, thesis §4.2): the helix parameter
//! `R = ρ·R_0` (ρ nominal 1), with the spatial frequency and the amplitude tied to it
//! (`shape::helix_shape`), following `M·ρ̈ + B·ρ̇ + K·(ρ − 1) = s·F_ρ + τ_D`,
//! `F_ρ = Jᵀ·τ_ext`. The virtual squeeze `τ_D` tightens the coil until the pole pushes
//! back hard enough to hold the body by friction; compliant (`s = +1`), a pole that
//! grows pushes the coil open. One file a concern:
//! - [`config`]: the configuration and presets (`fixed` is the open-loop helix);
//! - `windows`: one ρ per half turn (`windowed`) and the adaptive set point;
//! - `getting_on`: from the ground onto the pole, taking over at the switch;
//! - `slip`: what a lost grip or a fall does.
//!
//! docs/compliance.md, "Rolling helix".

use crate::controller_interface::config::ConfigError;
use crate::controller_interface::nominal::Nominal;
use crate::controller_interface::report::{ControllerReport, FieldSpec, ReportSpec, SignalSpec};
use crate::controller_interface::{
    BuildContext, CannotFollow, Controller, ControllerKind, Handover, NominalMismatch, Observation,
    Tick,
};
use crate::gait::{BodyLayout, GaitKind, GaitParams, JOINT_LIMIT_RAD, Plane, Serpenoid};
use crate::module::MODULE_MAX_SPEED_RAD_S;
use crate::shape::ShapeFunction;
use crate::shape::admittance::ParamState;
use crate::shape::helix_shape::HelixShape;
use crate::shape::torque::TorqueFilter;
use crate::shape::window::{Window, steepness_for_width};

mod config;
mod getting_on;
mod slip;
mod windows;
pub use config::{AdaptiveConfig, HelixRadiusConfig};
use getting_on::GettingOn;
pub use getting_on::{GettingOnConfig, PoleSide, Stage};
pub use slip::SlipConfig;
use slip::SlipGuard;
use windows::{MAX_HALF_TURNS, RadiusWindows, adapt};

/// The registry's entry.
pub struct HelixRadiusKind;

impl ControllerKind for HelixRadiusKind {
    type Config = HelixRadiusConfig;
    const NAME: &'static str = "helix_radius";
    const SUMMARY: &'static str =
        "the rolling helix's radius follows the torques, squeezed onto the pole (SPEC §6)";
    const GAITS: &'static [GaitKind] = &[GaitKind::RollingHelix];
    const PRESETS: &'static [(&'static str, &'static str)] = &[
        (
            "central",
            "one radius for the body, compliant, with a virtual squeeze",
        ),
        (
            "central_adaptive",
            "central, its set point following the grip (the pole's diameter)",
        ),
        ("windowed", "one radius per half turn of the coil"),
        (
            "windowed_adaptive",
            "one radius and adaptive set point per half turn (the full controller)",
        ),
        (
            "fixed",
            "the open-loop helix: the nominal coil, radius fixed (no compliance, no squeeze)",
        ),
    ];

    fn preset(name: &str) -> Option<Self::Config> {
        match name {
            "fixed" => Some(HelixRadiusConfig::fixed()),
            "central" => Some(HelixRadiusConfig::central()),
            "central_adaptive" => Some(HelixRadiusConfig::central_adaptive()),
            "windowed" => Some(HelixRadiusConfig::windowed()),
            "windowed_adaptive" => Some(HelixRadiusConfig::windowed_adaptive()),
            _ => None,
        }
    }

    fn check(config: &Self::Config, _ctx: &BuildContext<'_>) -> Result<(), ConfigError> {
        config.check()
    }

    fn report_spec(config: &Self::Config, _ctx: &BuildContext<'_>) -> ReportSpec {
        let s = SignalSpec::new;
        let fields = if config.windowed {
            vec![FieldSpec {
                name: "radius".into(),
                centralization: "windowed".into(),
                enabled: true,
                columns: vec![
                    s("radius_scale", ""),
                    s("set_point", ""),
                    s("shape_force", "N·m"),
                    s("grip_nm", "N·m"),
                ],
            }]
        } else {
            Vec::new()
        };
        ReportSpec {
            signals: vec![
                s("radius_scale", ""),
                s("helix_param", "rad/BL"),
                s("amplitude_rad", "rad"),
                s("shape_force", "N·m"),
                s("squeeze", "N·m"),
                s("phase_rad", "rad"),
                s("radius_set_point", ""),
                s("grip_nm", "N·m"),
                s("windows", "count"),
                s("radius_scale_min", ""),
                s("radius_scale_max", ""),
                s("getting_on", "stage"),
                s("getting_on_retries", "count"),
                s("slipping", "bool"),
                s("slips", "count"),
            ],
            fields,
        }
    }

    fn build(config: &Self::Config, ctx: &BuildContext<'_>) -> Box<dyn Controller> {
        Box::new(HelixRadius::new(*config, ctx.layout, ctx.params))
    }
}

/// The nominal helix's amplitude and spatial frequency (rad per body length).
fn nominal_wave(layout: &BodyLayout, params: &GaitParams) -> (f64, f64, f64) {
    let wave = Serpenoid::for_layout(GaitKind::RollingHelix, params, layout);
    let w = wave.wave(Plane::Dorsal);
    (
        w.amplitude_rad,
        w.spatial_freq_rad,
        wave.temporal_freq_rad_s,
    )
}

/// The controller (see the module docs). Allocates at construction only.
pub struct HelixRadius {
    config: HelixRadiusConfig,
    layout: BodyLayout,
    params: GaitParams,
    shape: HelixShape,
    /// R_0, rad per body length, and ωT, rad/s.
    r0: f64,
    temporal_freq: f64,
    /// The roll's speed over roll time (the loop's less the holds, from the roll's
    /// start): steady, or ramping to a followed change of speed.
    speed: Nominal,
    rho: ParamState,
    /// The half turns' state (windowed).
    windows: RadiusWindows,
    /// ρ's set point (1 unless adaptive) and the grip, the mean |τ_ext|, N·m.
    set_point: f64,
    grip: f64,
    force: f64,
    filter: TorqueFilter,
    tau_ext: Vec<f64>,
    jacobian: Vec<f64>,
    phase0: f64,
    t0: f64,
    phase: f64,
    getting_on: GettingOn,
    /// Taken over at the switch: the getting on decides the phase.
    own_way: bool,
    slip: SlipGuard,
    /// Time the roll held while slipping, s (the phase stands still meanwhile).
    held_s: f64,
}

impl HelixRadius {
    pub fn new(config: HelixRadiusConfig, layout: &BodyLayout, params: &GaitParams) -> Self {
        let n = layout.len();
        let (a0, r0, wt) = nominal_wave(layout, params);
        Self {
            config,
            layout: layout.clone(),
            params: *params,
            shape: HelixShape::with_capacity(
                layout,
                MAX_HALF_TURNS,
                // Edges about half a module wide (SPEC §4).
                steepness_for_width(0.5 / n as f64),
                HelixShape::tie(a0, r0),
            ),
            r0,
            temporal_freq: wt,
            speed: Nominal::at_phase(params, 0.0, 0.0),
            rho: ParamState::default(),
            windows: RadiusWindows::new(&layout.s, layout.body_length_m() / layout.module_length_m),
            set_point: 1.0,
            grip: 0.0,
            force: 0.0,
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            tau_ext: vec![0.0; n],
            jacobian: vec![0.0; n],
            phase0: 0.0,
            t0: 0.0,
            phase: 0.0,
            getting_on: GettingOn::new(config.getting_on, layout),
            own_way: false,
            slip: SlipGuard::default(),
            held_s: 0.0,
        }
    }

    /// ρ = R/R_0 now (the mean over the half turns when windowed).
    pub fn radius_scale(&self) -> f64 {
        if self.config.windowed {
            self.windows.summary().0
        } else {
            self.rho.value(self.set_point)
        }
    }

    /// The half turns on the body (1 when central).
    pub fn window_count(&self) -> usize {
        if self.config.windowed {
            self.windows.len()
        } else {
            1
        }
    }
}

impl HelixRadius {
    /// One ρ for the body: its force, grip, set point and admittance, then the shape.
    fn step_central(&mut self, config: &HelixRadiusConfig, dt: f64, set_points_rad: &mut [f64]) {
        let r = [self.r0 * self.radius_scale()];
        self.shape.jacobian(&r, &mut self.jacobian);
        // ∂h/∂ρ = R_0·∂h/∂R.
        self.force = self.r0
            * self
                .jacobian
                .iter()
                .zip(&self.tau_ext)
                .map(|(j, t)| j * t)
                .sum::<f64>();
        self.grip = self.tau_ext.iter().map(|t| t.abs()).sum::<f64>() / self.tau_ext.len() as f64;
        let g = &config.gains;
        // The set point moves, ρ's deviation from it is kept: ρ moves with it.
        self.set_point = adapt(
            &config.adaptive,
            self.set_point,
            self.grip,
            g.min,
            g.max,
            dt,
        );
        self.rho
            .step(g, config.sign, self.force, self.set_point, dt);
        self.shape
            .value(&[self.r0 * self.radius_scale()], set_points_rad);
    }
}

impl Controller for HelixRadius {
    /// The tightest coil (ρ at its bound) must keep every joint in range and under the
    /// joints' speed: its amplitude is ρ·A_0.
    fn accepts(&self, params: &GaitParams) -> Result<(), NominalMismatch> {
        let (a0, r0, wt) = nominal_wave(&self.layout, params);
        // R ties ωS to A: a helix without both (no pitch, no curvature) has no R.
        if !(a0 > 0.0 && r0 > 0.0 && a0.is_finite() && r0.is_finite()) {
            return Err(NominalMismatch {
                field: "helix_pitch_m",
                value: params.helix_pitch_m,
                min: 0.005,
                max: 0.5,
            });
        }
        let rho = self.config.gains.max;
        let offset = params.offset_lat_rad.abs().max(params.offset_dor_rad.abs());
        let reach = offset + rho * a0;
        let speed = rho * a0 * wt.abs();
        let over = |a0: f64| {
            let by_reach = rho * a0 / (JOINT_LIMIT_RAD - offset).max(1e-9);
            let by_speed = rho * a0 * wt.abs() / MODULE_MAX_SPEED_RAD_S;
            by_reach.max(by_speed)
        };
        if reach > JOINT_LIMIT_RAD || speed > MODULE_MAX_SPEED_RAD_S {
            // The smallest nominal radius (the pitch scaled with it) the bound leaves
            // room for: A is nearly ∝ 1/radius, so a few fixed-point steps find it.
            let mut p = *params;
            for _ in 0..8 {
                let (a, _, _) = nominal_wave(&self.layout, &p);
                let scale = over(a);
                p.helix_radius_m *= scale;
                p.helix_pitch_m *= scale;
            }
            return Err(NominalMismatch {
                field: "helix_radius_m",
                value: params.helix_radius_m,
                min: p.helix_radius_m * (1.0 + 1e-9),
                max: f64::INFINITY,
            });
        }
        Ok(())
    }

    fn engage(&mut self, h: &Handover<'_>) {
        self.params = *h.params;
        let (a0, r0, wt) = nominal_wave(&self.layout, h.params);
        self.shape.set_tie(HelixShape::tie(a0, r0));
        self.shape.set_windows([Window::EVERYWHERE]);
        self.windows.reset();
        self.r0 = r0;
        self.temporal_freq = wt;
        self.speed = Nominal::at_phase(h.params, 0.0, 0.0);
        self.rho = ParamState::default();
        self.set_point = 1.0;
        self.grip = 0.0;
        self.force = 0.0;
        self.filter.reset();
        self.phase0 = h.phase_rad;
        self.t0 = h.t_s;
        self.phase = h.phase_rad;
        let stage = self.getting_on.engage(h.t_s, h.set_points_rad, h.params);
        self.own_way = stage != Stage::Off;
        self.slip = SlipGuard::default();
        self.held_s = 0.0;
    }

    /// A change of speed alone (same sense) once climbing or without getting on: the
    /// roll ramps to it (`Nominal::follow` over the roll's time), the coil and what it
    /// learnt stay. A change of the helix (radius, pitch, offsets), a reversal, or any
    /// change while getting on the pole: a fresh takeover.
    fn follow(&mut self, t_s: f64, params: &GaitParams) -> Result<(), CannotFollow> {
        let mut same = *params;
        same.temporal_freq_rad_s = self.params.temporal_freq_rad_s;
        if same != self.params {
            return Err(CannotFollow(
                "the helix's radius, pitch and offsets set its coil",
            ));
        }
        if params.temporal_freq_rad_s * self.params.temporal_freq_rad_s < 0.0 {
            return Err(CannotFollow("a reversal of the roll"));
        }
        if self.own_way && self.getting_on.stage() != Stage::Climb {
            return Err(CannotFollow("getting on the pole"));
        }
        let roll_s = (t_s - self.t0 - self.held_s).max(0.0);
        self.speed.follow(roll_s, params);
        self.params = *params;
        Ok(())
    }

    fn takes_over_at_switch(&self) -> bool {
        self.config.getting_on.enabled
    }

    fn step(&mut self, tick: Tick, obs: &Observation<'_>, set_points_rad: &mut [f64]) {
        let Tick { t_s, dt_s: dt } = tick;
        self.filter.update(dt, obs.torque_nm, &mut self.tau_ext);
        let grip = self.tau_ext.iter().map(|t| t.abs()).sum::<f64>() / self.tau_ext.len() as f64;
        let mut direction = 1.0;
        if self.own_way {
            self.getting_on.update(t_s, obs.position_rad, obs.imu, grip);
            self.phase0 = self.getting_on.coil_phase();
            self.t0 = self.getting_on.roll_start_s();
            direction = self.getting_on.direction();
        }
        // Slipping: hold the roll and squeeze harder (once climbing).
        let mut config = self.config;
        let climbing = !self.own_way || self.getting_on.stage() == Stage::Climb;
        if climbing && self.slip.update(&config.slip, dt, grip, obs.imu) {
            self.held_s += dt;
            config.gains.bias_force *= config.slip.squeeze_gain;
        }
        // ψ₀ + ∫ωT over the roll's time (ωT·τ while steady).
        let roll_s = (t_s - self.t0 - self.held_s).max(0.0);
        self.phase = self.phase0 + direction * self.speed.phase_at(roll_s);
        self.shape.set_phase(self.phase);
        if !self.getting_on.coil_active() {
            // Held or lapping: the coil waits at its nominal (again after a miss).
            self.rho = ParamState::default();
            self.set_point = 1.0;
            self.windows.reset();
            self.getting_on.mix(t_s, set_points_rad);
            return;
        }
        if self.config.windowed {
            self.windows
                .step(&mut self.shape, &config, self.r0, &self.tau_ext, dt);
            self.shape.value(self.windows.values(), set_points_rad);
        } else {
            self.step_central(&config, dt, set_points_rad);
        }
        for (x, &plane) in set_points_rad.iter_mut().zip(&self.layout.planes) {
            *x += match plane {
                Plane::Lateral => self.params.offset_lat_rad,
                Plane::Dorsal => self.params.offset_dor_rad,
            };
        }
        self.getting_on.mix(t_s, set_points_rad);
    }

    fn report(&self, out: &mut ControllerReport) {
        out.clear();
        let rho = self.radius_scale();
        let r = self.r0 * rho;
        let (lo, hi) = if self.config.windowed {
            let (_, lo, hi) = self.windows.summary();
            (lo, hi)
        } else {
            (rho, rho)
        };
        let (force, set_point, grip) = if self.config.windowed {
            self.windows.means()
        } else {
            (self.force, self.set_point, self.grip)
        };
        let values = [
            rho,
            r,
            r / self.shape.k(),
            force,
            self.config.gains.bias_force,
            self.phase,
            set_point,
            grip,
            self.window_count() as f64,
            lo,
            hi,
            self.getting_on.stage().code(),
            f64::from(self.getting_on.attempts()),
            f64::from(u8::from(self.slip.slipping())),
            f64::from(self.slip.count()),
        ];
        out.signals[..values.len()].copy_from_slice(&values);
        if self.config.windowed {
            self.windows.field(&mut out.fields[0]);
        }
    }
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
