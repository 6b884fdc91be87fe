//! Getting on the pole (issue 12, point 3): the body lies on the ground beside the pole
//! when the rolling helix is commanded. A blend into the coil would coil it on the
//! ground and roll it away (`examples/pole_windup.rs`), so the controller takes over at
//! the switch and laps the pole's foot instead (`examples/pole_lasso.rs`):
//!
//! 1. **Straighten** (`straighten_s`), then **measure** (`measure_s`): the body lies
//!    straight (whatever the rolling gait left, an arc lapping the wrong way among
//!    it), the middle module's accelerometer averaged: which way is up in that
//!    link's frame, so which way the pole is.
//! 2. **Lap** (`lap_s`): blend into a flat-pitched helix of the nominal radius plus
//!    `lap_clearance_m`, its phase chosen so the body's middle bends towards the pole
//!    (`side` of the body, looking towards the head): both halves lap its foot.
//! 3. **Open** (`open_s`): blend from the lap into the controller's own coil (nominal
//!    pitch, the squeeze tightening it), still not rolling, its middle bent the same way.
//! 4. **Climb**: the controller rolls the coil at ωT, upwards for ωT > 0: which way
//!    of rolling climbs depends on which end of the body is up (the lap leaves the
//!    head at the bottom or the top), read from the joint angles and the head
//!    module's accelerometer when the climb starts.
//!
//! A body already coiled when the controller takes over (after a hold, or new
//! parameters) is not lapped: the controller blends from where it is into its coil at
//! the phase nearest the pose (over `open_s`) and rolls on.
//! Allocates at construction only.

use std::f64::consts::TAU;

use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::controller_interface::Imu;
use crate::controller_interface::config::{ConfigError, check_range};
use crate::gait::kinematics::link_poses;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Serpenoid};

/// Which side of the body the pole is on, looking along the body towards the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoleSide {
    #[default]
    Left,
    Right,
}

/// How the controller gets on the pole (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GettingOnConfig {
    /// Take over at the switch and lap the pole when the body is not coiled; off: take
    /// over after the selector's blend, as other controllers do.
    pub enabled: bool,
    pub side: PoleSide,
    pub straighten_s: f64,
    pub measure_s: f64,
    pub lap_s: f64,
    pub open_s: f64,
    /// The lap's pitch parameter, m (flat: the coil lies round the pole's foot).
    pub lap_pitch_m: f64,
    /// The lap's radius over the nominal helix radius, m (room to close round the pole).
    pub lap_clearance_m: f64,
    /// The grip (mean |τ_ext| over the joints) at the end of the opening that says the
    /// coil closed on the pole, N·m; below it the lap missed and is tried again.
    pub found_nm: f64,
    /// Laps tried again after a miss, each 2 cm wider.
    pub retries: u32,
}

impl Default for GettingOnConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            side: PoleSide::Left,
            straighten_s: 1.0,
            measure_s: 0.3,
            lap_s: 2.0,
            open_s: 3.0,
            lap_pitch_m: 0.008,
            lap_clearance_m: 0.04,
            found_nm: 0.8,
            retries: 2,
        }
    }
}

impl GettingOnConfig {
    pub fn check(&self) -> Result<(), ConfigError> {
        let k = |e: ConfigError| e.under("getting_on");
        check_range("straighten_s", self.straighten_s, 0.1, 10.0).map_err(k)?;
        check_range("measure_s", self.measure_s, 0.01, 5.0).map_err(k)?;
        check_range("lap_s", self.lap_s, 0.2, 30.0).map_err(k)?;
        check_range("open_s", self.open_s, 0.2, 30.0).map_err(k)?;
        check_range("lap_pitch_m", self.lap_pitch_m, 0.001, 0.05).map_err(k)?;
        check_range("lap_clearance_m", self.lap_clearance_m, 0.0, 0.1).map_err(k)?;
        check_range(
            "found_nm",
            self.found_nm,
            0.0,
            crate::module::MODULE_MAX_TORQUE_NM,
        )
        .map_err(k)?;
        check_range("retries", f64::from(self.retries), 0.0, 5.0).map_err(k)
    }
}

/// Where the getting on is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Not taken over at a switch (or disabled): the controller's coil from the start.
    Off,
    Straighten,
    Measure,
    Lap,
    Open,
    /// Blending from a coiled handover into the coil, rolling.
    Resume,
    Climb,
}

impl Stage {
    /// The stage as a signal value: 0 climbing (or off), 1 straighten or measure,
    /// 2 lap, 3 open, 4 resume.
    pub fn code(self) -> f64 {
        match self {
            Self::Off | Self::Climb => 0.0,
            Self::Straighten | Self::Measure => 1.0,
            Self::Lap => 2.0,
            Self::Open => 3.0,
            Self::Resume => 4.0,
        }
    }
}

/// Phases tried when aiming the lap (and when matching a coiled pose).
const PHASES: usize = 72;

/// The getting-on sequence's state and scratch space.
pub struct GettingOn {
    config: GettingOnConfig,
    layout: BodyLayout,
    stage: Stage,
    t0: f64,
    from: Vec<f64>,
    lap: Vec<f64>,
    scratch: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    up_sum: Vector3<f64>,
    lap_wave: Serpenoid,
    coil_wave: Serpenoid,
    /// The coil's phase chosen to match the lap (or the pose), rad.
    coil_phase: f64,
    lap_phase: f64,
    /// +1: the head is above the tail (the phase advancing at ωT > 0 climbs); −1 below.
    direction: f64,
    /// Laps tried again so far.
    attempts: u32,
    params: GaitParams,
    /// The last set-points mixed (where a retry starts from).
    last: Vec<f64>,
}

fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

impl GettingOn {
    pub fn new(config: GettingOnConfig, layout: &BodyLayout) -> Self {
        let n = layout.len();
        Self {
            config,
            layout: layout.clone(),
            stage: Stage::Off,
            t0: 0.0,
            from: vec![0.0; n],
            lap: vec![0.0; n],
            scratch: vec![0.0; n],
            poses: vec![Isometry3::identity(); n + 1],
            up_sum: Vector3::zeros(),
            lap_wave: Serpenoid::default(),
            coil_wave: Serpenoid::default(),
            coil_phase: 0.0,
            lap_phase: 0.0,
            direction: 1.0,
            attempts: 0,
            params: GaitParams::default_for(GaitKind::RollingHelix),
            last: vec![0.0; n],
        }
    }

    pub fn stage(&self) -> Stage {
        self.stage
    }

    /// Starts from a takeover at `t_s` with the handed-over set-points; `params` the
    /// nominal helix. Returns the stage it starts in.
    pub fn engage(&mut self, t_s: f64, from: &[f64], params: &GaitParams) -> Stage {
        self.t0 = t_s;
        self.from.copy_from_slice(from);
        self.up_sum = Vector3::zeros();
        self.coil_wave = Serpenoid::for_layout(GaitKind::RollingHelix, params, &self.layout);
        self.params = *params;
        self.attempts = 0;
        self.set_lap();
        let coil_amplitude = self.coil_wave.dorsal.amplitude_rad.abs();
        self.stage = if !self.config.enabled {
            Stage::Off
        } else if rms(from) > 0.5 * coil_amplitude {
            self.coil_phase = self.nearest_phase(from);
            Stage::Resume
        } else {
            Stage::Straighten
        };
        self.stage
    }

    /// Laps tried again so far.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// The lap of this attempt: 2 cm wider each retry.
    fn set_lap(&mut self) {
        let p = &self.params;
        let lap = GaitParams {
            helix_radius_m: p.helix_radius_m
                + self.config.lap_clearance_m
                + 0.02 * f64::from(self.attempts),
            helix_pitch_m: self.config.lap_pitch_m * p.helix_pitch_m.signum(),
            ..*p
        };
        self.lap_wave = Serpenoid::for_layout(GaitKind::RollingHelix, &lap, &self.layout);
    }

    /// Seconds from the takeover to the end of the measuring.
    fn measured_s(&self) -> f64 {
        self.config.straighten_s + self.config.measure_s
    }

    /// The coil's phase and the time it starts rolling from, once known (after the
    /// measure stage or at a resume).
    pub fn coil_phase(&self) -> f64 {
        self.coil_phase
    }

    /// When the coil starts rolling, s (loop time).
    pub fn roll_start_s(&self) -> f64 {
        let c = &self.config;
        match self.stage {
            Stage::Resume => self.t0,
            _ => self.t0 + self.measured_s() + c.lap_s + c.open_s,
        }
    }

    /// The sense of rolling that climbs: +1 with the head above the tail, −1 below.
    pub fn direction(&self) -> f64 {
        self.direction
    }

    /// Advances the stage at `t_s` with the measured joint angles and IMUs and the grip
    /// (mean |τ_ext| over the joints, N·m).
    pub fn update(&mut self, t_s: f64, position_rad: &[f64], imu: &[Imu], grip_nm: f64) {
        let c = self.config;
        let e = t_s - self.t0;
        let measured = self.measured_s();
        // Module i's IMU sits on link i + 1: the middle link's is module m − 1's.
        let m = self.layout.len() / 2;
        let middle_accel_m_s2 = imu.get(m - 1).map_or([0.0, 0.0, 9.81], |i| i.accel_m_s2);
        let before = self.stage;
        match self.stage {
            Stage::Straighten if e >= c.straighten_s => self.stage = Stage::Measure,
            Stage::Measure => {
                self.up_sum += Vector3::from(middle_accel_m_s2);
                if e >= measured {
                    self.aim();
                    self.stage = Stage::Lap;
                }
            }
            Stage::Lap if e >= measured + c.lap_s => self.stage = Stage::Open,
            Stage::Open if e >= measured + c.lap_s + c.open_s => {
                if grip_nm < c.found_nm && self.attempts < c.retries {
                    // Missed the pole: straighten from here and lap again, wider.
                    self.attempts += 1;
                    self.set_lap();
                    self.t0 = t_s;
                    self.from.copy_from_slice(&self.last);
                    self.up_sum = Vector3::zeros();
                    self.stage = Stage::Straighten;
                } else {
                    self.stage = Stage::Climb;
                }
            }
            Stage::Resume if e >= c.open_s => self.stage = Stage::Climb,
            _ => {}
        }
        let climbing = matches!(self.stage, Stage::Climb | Stage::Resume);
        if climbing && (before != self.stage || e == 0.0) {
            self.direction = self.head_up(position_rad, imu);
        }
    }

    /// +1 if the head is above the tail, from the joint angles (the tail in the head's
    /// frame) and module 0's accelerometer (up, on link 1); −1 if below.
    fn head_up(&mut self, position_rad: &[f64], imu: &[Imu]) -> f64 {
        let n = self.layout.len();
        let Some(first) = imu.first() else {
            return 1.0;
        };
        if position_rad.len() < n || !position_rad.iter().all(|x| x.is_finite()) {
            return 1.0;
        }
        link_poses(
            Isometry3::identity(),
            &self.layout,
            &position_rad[..n],
            &mut self.poses,
        );
        let up = self.poses[1].rotation * Vector3::from(first.accel_m_s2);
        let tail = self.poses[n].translation.vector;
        if tail.dot(&up) <= 0.0 { 1.0 } else { -1.0 }
    }

    /// Whether the coil's own dynamics (the squeeze, the adaptation) run yet: not
    /// while the body is held or lapped.
    pub fn coil_active(&self) -> bool {
        !matches!(self.stage, Stage::Straighten | Stage::Measure | Stage::Lap)
    }

    /// Mixes the controller's coil `coil` (written at the coil's phase) into what the
    /// stage commands, in place.
    pub fn mix(&mut self, t_s: f64, coil: &mut [f64]) {
        let c = &self.config;
        let e = t_s - self.t0;
        let blend = |a: &[f64], b: &mut [f64], w: f64| {
            for (b, a) in b.iter_mut().zip(a) {
                *b = (1.0 - w) * a + w * *b;
            }
        };
        let measured = self.measured_s();
        match self.stage {
            Stage::Off | Stage::Climb => {}
            Stage::Straighten => {
                let w = smooth(e / c.straighten_s);
                for (o, f) in coil.iter_mut().zip(&self.from) {
                    *o = (1.0 - w) * f;
                }
            }
            Stage::Measure => coil.fill(0.0),
            Stage::Lap => {
                let w = smooth((e - measured) / c.lap_s);
                for (o, l) in coil.iter_mut().zip(&self.lap) {
                    *o = w * l;
                }
            }
            Stage::Open => blend(&self.lap, coil, smooth((e - measured - c.lap_s) / c.open_s)),
            Stage::Resume => blend(&self.from, coil, smooth(e / c.open_s)),
        }
        self.last.copy_from_slice(coil);
    }

    /// Picks the lap's phase (and the coil's) so the middle bends towards the pole.
    fn aim(&mut self) {
        let up = self.up_sum.try_normalize(1e-9).unwrap_or(Vector3::z());
        // Left of the body in the middle link's frame (x towards the head): up × x.
        let left = Vector3::new(0.0, up.z, -up.y);
        let toward = match self.config.side {
            PoleSide::Left => left,
            PoleSide::Right => -left,
        };
        let target = toward.z.atan2(toward.y);
        let lap_wave = self.lap_wave;
        let coil_wave = self.coil_wave;
        self.lap_phase = self.phase_bending(&lap_wave, target);
        self.coil_phase = self.phase_bending(&coil_wave, target);
        let (layout, lap) = (&self.layout, &mut self.lap);
        lap_wave.evaluate(layout, self.lap_phase, lap);
    }

    /// The phase at which `wave` bends the middle link towards `target` (an angle in
    /// that link's y–z plane, from y).
    fn phase_bending(&mut self, wave: &Serpenoid, target: f64) -> f64 {
        let m = self.layout.len() / 2;
        let (mut best, mut best_err) = (0.0, f64::INFINITY);
        for k in 0..PHASES {
            let psi = k as f64 * TAU / PHASES as f64;
            wave.evaluate(&self.layout, psi, &mut self.scratch);
            link_poses(
                Isometry3::identity(),
                &self.layout,
                &self.scratch,
                &mut self.poses,
            );
            // The middle link's neighbours in its own frame: their sum points into the bend.
            let inv = self.poses[m].inverse();
            let at = |p: &Isometry3<f64>| inv * Point3::from(p.translation.vector);
            let c = at(&self.poses[m - 1]).coords + at(&self.poses[m + 1]).coords;
            let d = c.z.atan2(c.y) - target;
            let err = d.sin().abs() + (1.0 - d.cos());
            if err < best_err {
                (best, best_err) = (psi, err);
            }
        }
        best
    }

    /// The coil's phase whose shape is nearest `pose` (least squares).
    fn nearest_phase(&mut self, pose: &[f64]) -> f64 {
        let (mut best, mut best_err) = (0.0, f64::INFINITY);
        for k in 0..PHASES {
            let psi = k as f64 * TAU / PHASES as f64;
            self.coil_wave
                .evaluate(&self.layout, psi, &mut self.scratch);
            let err: f64 = self
                .scratch
                .iter()
                .zip(pose)
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            if err < best_err {
                (best, best_err) = (psi, err);
            }
        }
        best
    }
}

#[cfg(test)]
#[path = "getting_on_tests.rs"]
mod tests;
