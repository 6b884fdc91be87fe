//! One trial: a controller drives the physics plant in lockstep, 1 ms per step, from the
//! layout's start until the front half of the body has crossed the board or the time
//! limit. Recorded at a fixed rate: the body centre, the controller's signals.

use super::LabError;
use super::board::Board;
use super::controllers::LabController;
use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use crate::emu::world::scenario::MODULE_LENGTH_M;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Plane};
use crate::protocol::Command;
use crate::shape::Measured;

/// How a trial runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialConfig {
    pub modules: usize,
    /// Time limit, s (the thesis: 120).
    pub limit_s: f64,
    /// Plant and controller step, s.
    pub dt_s: f64,
    /// Recording rate of the centre path and the signals, Hz.
    pub sample_hz: f64,
    /// The set-points blend from the measured start pose (straight) into the
    /// controller's over this long, s, so no joint set-point steps at t = 0.
    pub blend_s: f64,
}

impl Default for TrialConfig {
    fn default() -> Self {
        Self {
            modules: 18,
            limit_s: 120.0,
            dt_s: 1e-3,
            sample_hz: 20.0,
            blend_s: 1.0,
        }
    }
}

impl TrialConfig {
    /// Plant steps between two samples.
    pub fn steps_per_sample(&self) -> usize {
        (1.0 / (self.sample_hz * self.dt_s)).round().max(1.0) as usize
    }

    /// Time between two samples, s.
    pub fn sample_dt_s(&self) -> f64 {
        self.steps_per_sample() as f64 * self.dt_s
    }
}

/// What one trial recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialRecord {
    /// Time between samples, s; sample `k` is at `k · sample_dt_s`.
    pub sample_dt_s: f64,
    /// Body centre (mean of the links) in the ground plane, m.
    pub centre_m: Vec<[f64; 2]>,
    /// Link positions at the start and at the end (head first), m.
    pub start_links_m: Vec<[f64; 2]>,
    pub end_links_m: Vec<[f64; 2]>,
    /// The controller's signals (`JointController::for_each_signal`), one series each,
    /// sampled with the centre.
    pub signal_names: Vec<String>,
    pub signals: Vec<Vec<f64>>,
    /// Simulated time at the end, s.
    pub seconds: f64,
    /// The front half crossed the board before the limit.
    pub success: bool,
    /// The controller's nominal temporal frequency, rad/s.
    pub temporal_freq_rad_s: f64,
}

/// The body layout and nominal parameters every slithering controller gets.
pub fn slithering_setup(modules: usize) -> (BodyLayout, GaitParams) {
    (
        BodyLayout::alternating(modules, Plane::Lateral, MODULE_LENGTH_M),
        GaitParams::default_for(GaitKind::Slithering),
    )
}

/// Runs `controller` in `world` until the front half crosses `board` or the time limit.
/// Deterministic given `noise_seed` (the plant's sensor noise).
pub fn run_trial(
    controller: &LabController,
    world: &WorldSpec,
    board: &Board,
    noise_seed: u64,
    config: &TrialConfig,
) -> Result<TrialRecord, LabError> {
    let n = config.modules;
    let (layout, params) = slithering_setup(n);
    let mut ctrl = controller.build(&layout, &params)?;
    let physics = PhysicsConfig {
        modules: n,
        seed: noise_seed,
        ..PhysicsConfig::default()
    };
    let mut plant = PhysicsPlant::new(world, physics).map_err(|source| LabError::Physics {
        trial: format!("{} (seed {noise_seed})", controller.label),
        source,
    })?;

    let steps = (config.limit_s / config.dt_s).round() as usize;
    let per_sample = config.steps_per_sample();
    let samples = steps / per_sample + 1;
    let mut rec = TrialRecord {
        sample_dt_s: config.sample_dt_s(),
        centre_m: Vec::with_capacity(samples),
        start_links_m: links(&plant),
        end_links_m: Vec::new(),
        signal_names: Vec::new(),
        signals: Vec::new(),
        seconds: 0.0,
        success: false,
        temporal_freq_rad_s: ctrl.temporal_freq_rad_s(),
    };
    ctrl.for_each_signal(&mut |name, _| {
        rec.signal_names.push(name.to_owned());
        rec.signals.push(Vec::with_capacity(samples));
    });

    let mut position_rad = vec![0.0; n];
    let mut torque_nm = vec![0.0; n];
    let mut set_points_rad = vec![0.0; n];
    let mut commands = vec![Command::LIMP; n];
    read_feedback(&plant, &mut position_rad, &mut torque_nm);
    let start_rad = position_rad.clone();
    record(&plant, ctrl.as_ref(), &mut rec);

    for k in 1..=steps {
        let t_s = plant.time_s();
        read_feedback(&plant, &mut position_rad, &mut torque_nm);
        let measured = Measured {
            position_rad: &position_rad,
            torque_nm: &torque_nm,
        };
        ctrl.step(t_s, &measured, &mut set_points_rad);
        let w = blend_weight(t_s, config.blend_s);
        for ((c, &sp), &s0) in commands.iter_mut().zip(&set_points_rad).zip(&start_rad) {
            *c = Command::position(s0 + w * (sp - s0));
        }
        plant.step(config.dt_s, &commands);
        if k % per_sample == 0 {
            record(&plant, ctrl.as_ref(), &mut rec);
            if board.crossed(front_half_centre(&plant)) {
                rec.success = true;
                break;
            }
        }
    }
    rec.seconds = plant.time_s();
    rec.end_links_m = links(&plant);
    Ok(rec)
}

fn read_feedback(plant: &PhysicsPlant, position_rad: &mut [f64], torque_nm: &mut [f64]) {
    for (i, (p, t)) in position_rad
        .iter_mut()
        .zip(torque_nm.iter_mut())
        .enumerate()
    {
        let f = plant.feedback(i);
        *p = f64::from(f.position_rad);
        *t = f64::from(f.torque_nm);
    }
}

fn record(plant: &PhysicsPlant, ctrl: &dyn crate::shape::JointController, rec: &mut TrialRecord) {
    let c = plant.centre_of_mass_m();
    rec.centre_m.push([c[0], c[1]]);
    let mut k = 0;
    ctrl.for_each_signal(&mut |_, v| {
        if let Some(series) = rec.signals.get_mut(k) {
            series.push(v);
        }
        k += 1;
    });
    // A signal the controller skipped this time is a gap, so the series stay aligned.
    let samples = rec.centre_m.len();
    for series in &mut rec.signals {
        series.resize(samples, f64::NAN);
    }
}

/// Ground-plane positions of the links, head first, m.
fn links(plant: &PhysicsPlant) -> Vec<[f64; 2]> {
    (0..plant.link_count())
        .map(|k| {
            let p = plant.link_pose(k).position_m;
            [p[0], p[1]]
        })
        .collect()
}

/// Mean ground-plane position of the front half of the links (`0 .. links/2`), m.
pub fn front_half_centre(plant: &PhysicsPlant) -> [f64; 2] {
    let half = (plant.link_count() / 2).max(1);
    let mut c = [0.0, 0.0];
    for k in 0..half {
        let p = plant.link_pose(k).position_m;
        c = [c[0] + p[0], c[1] + p[1]];
    }
    [c[0] / half as f64, c[1] / half as f64]
}

/// 0 → 1 smoothly (cubic smoothstep) over `blend_s`; 1 when `blend_s` is 0.
pub fn blend_weight(t_s: f64, blend_s: f64) -> f64 {
    if blend_s <= 0.0 {
        return 1.0;
    }
    let x = (t_s / blend_s).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::scenario::Region;

    #[test]
    fn blend_is_smooth_and_ends_at_one() {
        assert_eq!(blend_weight(0.0, 1.0), 0.0);
        assert_eq!(blend_weight(0.5, 1.0), 0.5);
        assert_eq!(blend_weight(1.0, 1.0), 1.0);
        assert_eq!(blend_weight(7.0, 1.0), 1.0);
        assert_eq!(blend_weight(0.0, 0.0), 1.0);
        assert!(blend_weight(0.01, 1.0) < 1e-3, "starts with zero slope");
    }

    #[test]
    fn sampling_cadence() {
        let c = TrialConfig::default();
        assert_eq!(c.steps_per_sample(), 50);
        assert!((c.sample_dt_s() - 0.05).abs() < 1e-12);
    }

    #[test]
    fn a_short_open_loop_trial_records_and_moves_the_joints() {
        let world = WorldSpec::default();
        let board = Board::new(
            Region {
                x_m: [-5.0, 5.0],
                y_m: [-5.0, 5.0],
            },
            std::f64::consts::PI,
        );
        let config = TrialConfig {
            limit_s: 0.5,
            ..TrialConfig::default()
        };
        let open_loop = LabController::named("open_loop").unwrap();
        let rec = run_trial(&open_loop, &world, &board, 7, &config).unwrap();
        assert!(!rec.success);
        assert!((rec.seconds - 0.5).abs() < 1e-9);
        assert_eq!(rec.centre_m.len(), 11, "t = 0 and every 50 ms");
        assert_eq!(rec.start_links_m.len(), 19);
        assert_ne!(rec.start_links_m, rec.end_links_m, "the body moved");
        assert_eq!(rec.temporal_freq_rad_s, 1.0);
        assert_eq!(rec.signal_names.len(), rec.signals.len());
        let again = run_trial(&open_loop, &world, &board, 7, &config).unwrap();
        assert_eq!(rec, again, "deterministic");
    }

    #[test]
    fn a_trial_ends_when_the_front_half_crosses() {
        // A board whose far edge is just ahead of the straight body's front half: the
        // front half starts beyond the x_max edge (entry x_min), so the first sample ends it.
        let world = WorldSpec::default();
        let board = Board::new(
            Region {
                x_m: [-3.0, -0.5],
                y_m: [-1.0, 1.0],
            },
            std::f64::consts::PI,
        );
        let config = TrialConfig {
            limit_s: 2.0,
            ..TrialConfig::default()
        };
        let open_loop = LabController::named("open_loop").unwrap();
        let rec = run_trial(&open_loop, &world, &board, 1, &config).unwrap();
        assert!(rec.success);
        assert!((rec.seconds - 0.05).abs() < 1e-9, "{}", rec.seconds);
    }
}
