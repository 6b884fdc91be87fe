//! A simulated outside position source for the lab's trials (issue 48): fixes of the
//! body from the emulator's ground truth, as a lab's motion capture or a field team's
//! total station would give them, into the trial loop's pose input
//! (`estimation::external_pose`) in loop time (the trial's time is simulated). Its
//! rate, noise, latency, dropouts (single fixes and bursts of occlusion) and the marker
//! are set by [`SourceConfig`]; deterministic for a seed.
//!
//! The source tracks the virtual chassis (the links' centroid; its yaw from the links'
//! main axis, toward the head, as the estimator defines it) or a marker on the head
//! link at an offset, in the emulator's world.

use std::collections::VecDeque;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use crate::controller_interface::Estimator;
use crate::emu::Plant;
use crate::estimation::chassis::{Chassis, chassis};
use crate::estimation::external_pose::{ExternalFix, PoseInput, pose_input};
use crate::estimation::world_position::{
    FusionConfig, Tracked, WorldPosition, WorldPositionEstimator,
};

/// How the simulated source behaves.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SourceConfig {
    pub rate_hz: f64,
    /// Each axis' noise, standard deviation, m.
    pub noise_m: f64,
    /// From measurement to arrival, s.
    pub latency_s: f64,
    /// Chance that a single fix is lost.
    pub dropout: f64,
    /// Occlusions: how many start a second, and how long each lasts, s.
    pub occlusions_per_s: f64,
    pub occlusion_s: f64,
    pub tracked: Tracked,
    /// The head marker in the head link's frame, m (`Head` only).
    pub marker_offset_m: [f64; 2],
}

impl SourceConfig {
    /// A lab's motion capture: 100 Hz, 2 mm, 15 ms.
    pub const LAB: SourceConfig = SourceConfig {
        rate_hz: 100.0,
        noise_m: 0.002,
        latency_s: 0.015,
        dropout: 0.0,
        occlusions_per_s: 0.0,
        occlusion_s: 0.0,
        tracked: Tracked::Chassis,
        marker_offset_m: [0.0, 0.0],
    };

    /// Degraded: 10 Hz, 2 cm, 100 ms, occluded 10 % of the time (1 s occlusions).
    pub const DEGRADED: SourceConfig = SourceConfig {
        rate_hz: 10.0,
        noise_m: 0.02,
        latency_s: 0.1,
        dropout: 0.0,
        occlusions_per_s: 0.1,
        occlusion_s: 1.0,
        tracked: Tracked::Chassis,
        marker_offset_m: [0.0, 0.0],
    };

    /// Refused: rates, noise, latency or chances out of range.
    pub fn check(&self) -> Result<(), String> {
        let within = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(format!(
                    "pose source {name} must be in [{lo}, {hi}], not {v}"
                ))
            }
        };
        within("rate_hz", self.rate_hz, 0.1, 1000.0)?;
        within("noise_m", self.noise_m, 0.0, 1.0)?;
        within("latency_s", self.latency_s, 0.0, 1.5)?;
        within("dropout", self.dropout, 0.0, 1.0)?;
        within("occlusions_per_s", self.occlusions_per_s, 0.0, 10.0)?;
        within("occlusion_s", self.occlusion_s, 0.0, 60.0)?;
        Ok(())
    }
}

impl Default for SourceConfig {
    fn default() -> Self {
        Self::LAB
    }
}

/// The truth the source measures: the tracked point and the tracked body's yaw.
pub fn truth(
    plant: &dyn Plant,
    tracked: Tracked,
    offset: [f64; 2],
    previous: Option<&Chassis>,
) -> ([f64; 2], f64, Chassis) {
    let n = plant.link_count();
    let mut points = [Vector3::zeros(); crate::record::cycle::RECORD_MAX_LINKS];
    for (k, p) in points.iter_mut().enumerate().take(n) {
        *p = Vector3::from(plant.link_pose(k).position_m);
    }
    let c = chassis(&points[..n], previous);
    let (point, yaw) = match tracked {
        Tracked::Chassis => ([c.origin.x, c.origin.y], c.heading_rad()),
        Tracked::Head => {
            let head = plant.link_pose(0);
            let [w, x, y, z] = head.quat_wxyz;
            let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
            let (s, co) = yaw.sin_cos();
            let p = head.position_m;
            (
                [
                    p[0] + co * offset[0] - s * offset[1],
                    p[1] + s * offset[0] + co * offset[1],
                ],
                yaw,
            )
        }
    };
    (point, yaw, c)
}

/// A trial's pose input, its fixes fused as the daemon fuses a real source's: the
/// fusion appended to `estimators`, set for what `source` tracks.
pub fn fused_input(source: &SourceConfig, estimators: &mut Vec<Box<dyn Estimator>>) -> PoseInput {
    let (input, reader) = pose_input(None);
    let fusion = FusionConfig {
        tracked: source.tracked,
        marker_offset_m: source.marker_offset_m,
        default_sd_m: source.noise_m.max(1e-4),
        ..FusionConfig::default()
    };
    estimators.push(Box::new(WorldPositionEstimator::new(reader, fusion)));
    input
}

/// How far the fused position is from the true centre `truth_m` (NaN: not valid), m.
pub fn position_error(world: &WorldPosition, truth_m: [f64; 2]) -> f64 {
    if world.valid() {
        (world.position_m[0] - truth_m[0]).hypot(world.position_m[1] - truth_m[1])
    } else {
        f64::NAN
    }
}

/// The source during one trial.
pub struct SimSource {
    config: SourceConfig,
    rng: Pcg64,
    next_s: f64,
    occluded_until_s: f64,
    /// Fixes measured, waiting for their arrival: (arrival, measured, fix).
    pending: VecDeque<(f64, f64, ExternalFix)>,
    last_chassis: Option<Chassis>,
    /// Fixes measured, and lost to dropouts and occlusions.
    pub measured: u64,
    pub lost: u64,
}

impl SimSource {
    pub fn new(config: SourceConfig, seed: u64) -> Self {
        Self {
            config,
            rng: Pcg64::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15),
            next_s: 0.0,
            occluded_until_s: f64::NEG_INFINITY,
            pending: VecDeque::new(),
            last_chassis: None,
            measured: 0,
            lost: 0,
        }
    }

    fn gaussian(&mut self) -> f64 {
        // Box-Muller.
        let u1: f64 = self.rng.random::<f64>().max(1e-300);
        let u2: f64 = self.rng.random();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// At loop time `t_s`: measures when due (unless lost) and hands over every fix
    /// whose latency has passed.
    pub fn step(&mut self, t_s: f64, plant: &dyn Plant, input: &PoseInput) {
        let c = self.config;
        if t_s >= self.next_s {
            self.next_s += 1.0 / c.rate_hz;
            if self.next_s < t_s {
                self.next_s = t_s + 1.0 / c.rate_hz;
            }
            self.measure(t_s, plant);
        }
        while let Some(&(arrival, measured, _)) = self.pending.front() {
            if arrival > t_s {
                break;
            }
            let (_, _, fix) = self.pending.pop_front().expect("a pending fix");
            // A refused fix (the trial's start) is the estimator's to count.
            let _ = input.write_loop_time(measured, &fix, 0);
        }
    }

    fn measure(&mut self, t_s: f64, plant: &dyn Plant) {
        let c = self.config;
        let (point, yaw, chassis) = truth(
            plant,
            c.tracked,
            c.marker_offset_m,
            self.last_chassis.as_ref(),
        );
        self.last_chassis = Some(chassis);
        self.measured += 1;
        // Occlusions start at random (a Poisson process) and last `occlusion_s`.
        let dt = 1.0 / c.rate_hz;
        if c.occlusions_per_s > 0.0 && self.rng.random_bool((c.occlusions_per_s * dt).min(1.0)) {
            self.occluded_until_s = self.occluded_until_s.max(t_s + c.occlusion_s);
        }
        let lost =
            t_s < self.occluded_until_s || (c.dropout > 0.0 && self.rng.random_bool(c.dropout));
        let noise = [self.gaussian() * c.noise_m, self.gaussian() * c.noise_m];
        if lost {
            self.lost += 1;
            return;
        }
        let fix = ExternalFix {
            stamp_unix_ns: 0,
            position_m: [point[0] + noise[0], point[1] + noise[1], 0.0],
            orientation_wxyz: Some([(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()]),
            position_sd_m: (c.noise_m > 0.0).then_some(c.noise_m),
            source: "lab".into(),
        };
        self.pending.push_back((t_s + c.latency_s, t_s, fix));
    }
}

#[cfg(test)]
#[path = "pose_source_tests.rs"]
mod tests;
