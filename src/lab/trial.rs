//! One trial through the daemon's own loop: the physics plant behind a `SimBus`, the
//! real `ControlLoop` with the lockstep pacer, the gait selector, its blend and the
//! controller's takeover, the set-point guard and the failsafe, exactly as `snaked`
//! runs them, 1 ms per cycle, from the layout's start until the front half of the body
//! has crossed the board or the time limit. Recorded at a fixed rate: the body centre
//! and the controller's signals.

use super::aim::Aim;
use super::aim::PendingHeading;
use super::pose_source::{SimSource, SourceConfig, fused_input, position_error};
use super::trial_navigator::TrialNavigator;
pub use super::truth::{centre, front_half_centre, front_half_of};
use super::truth::{ground, links};
use crate::estimation::external_pose::PoseInput;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64};

use super::LabError;
use super::compared::LabController;
use super::experiment::Goal;
use super::strain::{Strain, StrainLimits};
use crate::controller_interface::catalog::Catalog;
use crate::controller_interface::report::MAX_COLUMNS;
use crate::emu::Plant;
use crate::emu::servo::PositionLoop;
use crate::emu::sim_bus::{SimBus, SimBusConfig};
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use crate::gait::{
    BodyLayout, DEFAULT_BLEND_TIME_S, GaitKind, GaitParams, GaitSelector, GaitTable, Plane,
};
use crate::module::{MODULE_LENGTH_M, MODULE_MAX_SPEED_RAD_S};
use crate::record::{LoopRecorder, LoopRecording};
use crate::record::{McapOptions, RecordOptions, Recorder, RecordingInfo};
use crate::rt::control_loop::{ControlLoop, Flow, LoopParts};
use crate::rt::controller_slots::Installed;
use crate::rt::observer::CycleObserver;
use crate::rt::pacer::LockstepPacer;
use crate::rt::telemetry::{self, Snapshot};
use crate::safety::failsafe::{Failsafe, FailsafeConfig};

/// How a trial runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialConfig {
    pub modules: usize,
    /// Time limit, s (the thesis: 120).
    pub limit_s: f64,
    /// Loop period, s.
    pub dt_s: f64,
    /// Recording rate of the centre path and the signals, Hz.
    pub sample_hz: f64,
    /// The selector's blend from the measured start pose into the gait, s (the
    /// daemon's default); the controller takes over when it ends.
    pub blend_time_s: f64,
    /// The emulated servos' position loop.
    pub servo_loop: PositionLoop,
    /// Every gait's nominal parameters (the daemon's defaults unless the experiment
    /// was given `--nominal`): what the selector runs and the controllers are built on.
    pub gaits: GaitTable,
    /// Start in this gait and select the controller's after this many seconds, as an
    /// operator's `gait.set` would (the pole: rolling on the ground, then the helix);
    /// `None`: the controller's gait from the start.
    pub lead_in: Option<(GaitKind, f64)>,
    /// Aim the controller at a direction of travel (`controller.heading` at the takeover,
    /// as an operator would); `None`: its own heading.
    pub aim: Option<Aim>,
    /// A simulated outside position source (`lab::pose_source`) fused into the pose
    /// estimate; `None`: the body's own sensors only.
    pub pose_source: Option<SourceConfig>,
}

impl Default for TrialConfig {
    fn default() -> Self {
        Self {
            modules: 18,
            limit_s: 120.0,
            dt_s: 1e-3,
            sample_hz: 20.0,
            blend_time_s: DEFAULT_BLEND_TIME_S,
            servo_loop: PositionLoop::default(),
            gaits: GaitTable::default(),
            lead_in: None,
            aim: None,
            pose_source: None,
        }
    }
}

impl TrialConfig {
    /// The physics plant's configuration for a trial with sensor-noise seed `seed`.
    pub fn physics(&self, seed: u64) -> PhysicsConfig {
        let mut physics = PhysicsConfig {
            modules: self.modules,
            seed,
            ..PhysicsConfig::default()
        };
        physics.servo.position_loop = self.servo_loop;
        physics
    }

    /// Loop cycles between two samples.
    pub fn steps_per_sample(&self) -> usize {
        (1.0 / (self.sample_hz * self.dt_s)).round().max(1.0) as usize
    }

    /// The lead-in, if it lasts two loop cycles or more (shorter: the controller's
    /// gait from the start). A gait request before the loop's second cycle is not
    /// taken (measured: a switch at the first cycle never happened).
    pub fn lead_in(&self) -> Option<(GaitKind, f64)> {
        self.lead_in.filter(|&(_, s)| s >= 2.0 * self.dt_s)
    }

    /// Time between two samples, s.
    pub fn sample_dt_s(&self) -> f64 {
        self.steps_per_sample() as f64 * self.dt_s
    }
}

/// What one trial recorded.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrialRecord {
    /// Time between samples, s; sample `k` is at `k · sample_dt_s`.
    pub sample_dt_s: f64,
    /// Body centre (mean of the links) in the ground plane, m.
    pub centre_m: Vec<[f64; 2]>,
    /// Link positions at the start and at the end (head first), m.
    pub start_links_m: Vec<[f64; 2]>,
    /// Every link's position at every sample, head first, flattened: sample `k`'s
    /// links are [`TrialRecord::links_at`]`(k)`, m.
    pub links_m: Vec<[f64; 2]>,
    pub end_links_m: Vec<[f64; 2]>,
    /// The controller's signals (names from its report), one series each, sampled
    /// with the centre; NaN while the selector drives (before the takeover).
    pub signal_names: Vec<String>,
    pub signals: Vec<Vec<f64>>,
    /// Simulated time at the end, s.
    pub seconds: f64,
    /// The goal ended the trial before the limit (on a peg board: the front half left
    /// it, by any edge but the entry; the experiment's metrics say which).
    pub success: bool,
    /// The gait's nominal temporal frequency, rad/s.
    pub temporal_freq_rad_s: f64,
    /// Cycles in which the loop did not run the gait (failsafe hold or limp).
    pub cycles_not_running: u64,
    /// Contact onsets between non-adjacent links during the trial (`Plant::self_contacts`).
    pub self_contacts: u64,
    /// Every link's height at every sample, laid out as `links_m`, m.
    pub heights_m: Vec<f64>,
    /// The report's first window field at every sample (empty when it has none): each
    /// window's centre in normalised arc length and its columns.
    pub windows: Vec<Vec<[f64; 1 + MAX_COLUMNS]>>,
    /// What the trial asked of the actuators, every cycle (guard, joint speed, torque).
    pub strain: Strain,
    /// The loop's stuck detector at every sample (`ControlLoop::progress`).
    #[serde(default)]
    pub stuck_reported: Vec<bool>,
    /// Changes of gait or controller the navigator made (0 without one).
    #[serde(default)]
    pub gait_switches: u32,
    /// The loop's body estimate at every sample: contact odometry x, y (m) and heading
    /// (rad), in the estimate's world; NaN while it is not valid.
    #[serde(default)]
    pub estimate: Vec<[f64; 3]>,
    /// Per sample, how far the fused position (the chassis in the source's world) is
    /// from the truth (the links' centroid), m; NaN while it is not valid; empty
    /// without a source.
    #[serde(default)]
    pub position_error_m: Vec<f64>,
}

impl TrialRecord {
    /// The links (head first) at sample `k`; empty past the end.
    pub fn links_at(&self, k: usize) -> &[[f64; 2]] {
        let n = self.start_links_m.len();
        self.links_m.get(k * n..(k + 1) * n).unwrap_or(&[])
    }

    /// The links' heights (head first) at sample `k`; empty past the end.
    pub fn heights_at(&self, k: usize) -> &[f64] {
        let n = self.start_links_m.len();
        self.heights_m.get(k * n..(k + 1) * n).unwrap_or(&[])
    }

    /// The centre's height (mean of the links') at sample `k`, m.
    pub fn centre_height(&self, k: usize) -> f64 {
        let h = self.heights_at(k);
        h.iter().sum::<f64>() / h.len().max(1) as f64
    }
}

/// The daemon's gait table with `gait`'s nominal parameters patched by `json`, a
/// partial parameter set as the socket's `params.set` takes it (e.g.
/// `{"amplitude_lat_rad":1.1}`), checked as the daemon checks it.
pub fn nominal_gaits(gait: GaitKind, json: Option<&str>) -> Result<GaitTable, LabError> {
    let mut table = GaitTable::default();
    if let Some(json) = json {
        patch_nominal_json(&mut table, gait, json)?;
    }
    Ok(table)
}

/// `table` with `gait`'s nominal parameters patched by `json` (as `--nominal` gives it).
pub fn patch_nominal_json(
    table: &mut GaitTable,
    gait: GaitKind,
    json: &str,
) -> Result<(), LabError> {
    let what = format!("--nominal {json:?}");
    let patch: crate::gait::ParamPatch =
        serde_json::from_str(json).map_err(|e| LabError::BadValue(format!("{what}: {e}")))?;
    patch_nominal(table, gait, &patch, &what)
}

/// `table` with `gait`'s nominal parameters patched by `patch`, checked as the daemon
/// checks `params.set`; `what` names where the patch came from in the message.
pub fn patch_nominal(
    table: &mut GaitTable,
    gait: GaitKind,
    patch: &crate::gait::ParamPatch,
    what: &str,
) -> Result<(), LabError> {
    let params = table
        .get(gait)
        .patched(gait, patch)
        .map_err(|e| LabError::BadValue(format!("{what}: {e}")))?;
    *table.get_mut(gait) = params;
    Ok(())
}

/// The body layout and nominal parameters every slithering controller gets.
pub fn slithering_setup(modules: usize) -> (BodyLayout, GaitParams) {
    (
        BodyLayout::alternating(modules, Plane::Lateral, MODULE_LENGTH_M),
        GaitParams::default_for(GaitKind::Slithering),
    )
}

/// Where a trial is recorded, and with what.
pub struct TrialRecording<'a> {
    /// The MCAP file to write (must not exist).
    pub path: std::path::PathBuf,
    pub world: &'a WorldSpec,
    /// Labels written into the file's metadata (experiment, layout, start, seed).
    pub metadata: Vec<(String, String)>,
}

/// The loop of one trial, its signal names, its recorder and the sender of its
/// request channel (an operator's requests later in the trial).
pub(crate) type TrialLoop = (
    ControlLoop,
    Vec<String>,
    Option<Recorder>,
    crossbeam_channel::Sender<crate::rt::messages::Envelope>,
    Option<PoseInput>,
);

/// The loop of one trial: `controller` installed for its gait, the selector starting
/// on that gait (or the lead-in's), over `plant`, with `requests` waiting for its first
/// cycle (as if an operator had sent them); recorded when `recording` says where (the
/// recorder is returned, to be finished at the trial's end).
pub(crate) fn trial_loop(
    controller: &LabController,
    plant: PhysicsPlant,
    config: &TrialConfig,
    recording: Option<TrialRecording<'_>>,
    requests: &[crate::rt::messages::LoopRequest],
) -> Result<TrialLoop, LabError> {
    let n = config.modules;
    let gait = controller.gait;
    let layout = BodyLayout::alternating(n, Plane::Lateral, MODULE_LENGTH_M);
    let mut estimators = crate::estimation::standard_estimators(&layout);
    let pose = config.pose_source.map(|s| fused_input(&s, &mut estimators));
    let table = config.gaits;
    let built = controller.build(&layout, table.get(gait))?;
    let names = built
        .info
        .report
        .signals
        .iter()
        .map(|s| s.name.clone())
        .collect();
    let (record, recorder) = match recording {
        None => (None, None),
        Some(r) => {
            let catalog = Catalog::default();
            catalog.insert(built.info.clone());
            let info = RecordingInfo {
                source: "snake-lab".into(),
                module_names: (0..n).map(|i| format!("M{i:02}")).collect(),
                layout: layout.clone(),
                world: Some(r.world.clone()),
                catalog,
                metadata: r.metadata,
            };
            let opts = RecordOptions {
                mcap: Some(McapOptions::new(&r.path)),
                ..RecordOptions::default()
            };
            let (tx, recorder) =
                crate::record::start(opts, info).map_err(|source| LabError::Record {
                    path: r.path.clone(),
                    source,
                })?;
            // Offline: the loop waits for the writer rather than drop a record.
            let out = LoopRecording {
                tx,
                wait_when_full: true,
            };
            let observer: Box<dyn CycleObserver> = Box::new(LoopRecorder::new(out));
            (Some(observer), Some(recorder))
        }
    };
    let period_ns = (config.dt_s * 1e9).round() as u64;
    let bus = SimBus::new(
        Box::new(plant),
        SimBusConfig {
            period_s: config.dt_s,
            ..SimBusConfig::default()
        },
    );
    // The lab's loop answers no socket: its channels only need to exist, and carry the
    // requests given (their answers are not read).
    let (control_ends, loop_ends) = crate::rt::channels::loop_channels(requests.len() + 8);
    let req_tx = control_ends.requests;
    for (ticket, r) in requests.iter().enumerate() {
        let _ = req_tx.try_send(crate::rt::messages::Envelope::new(ticket as u64, *r));
    }
    let (writer, _reader) = telemetry::channel(Snapshot::new(n, gait, table, config.blend_time_s));
    let parts = LoopParts {
        bus: Box::new(bus),
        pacer: Box::new(LockstepPacer::new(period_ns, 1_000_000_000)),
        selector: GaitSelector::new(
            layout,
            table,
            config.lead_in().map_or(gait, |(g, _)| g),
            config.blend_time_s,
            MODULE_MAX_SPEED_RAD_S,
        ),
        failsafe: Failsafe::new(FailsafeConfig::default()),
        requests: loop_ends.requests,
        acks: loop_ends.acks,
        telemetry: writer,
        heartbeat: Arc::new(AtomicU64::new(0)),
        stop: Arc::new(AtomicBool::new(false)),
        velocity_feedforward: true,
        hold_at_start: false,
        retired: loop_ends.retired,
        controllers: vec![(
            gait,
            Installed {
                id: built.info.id,
                controller: built.controller,
            },
        )],
        estimators,
        observer: record,
    };
    Ok((ControlLoop::new(parts), names, recorder, req_tx, pose))
}

/// Runs `controller` in `world` until `goal` is reached or the time limit.
/// Deterministic given `noise_seed` (the plant's sensor noise).
pub fn run_trial(
    controller: &LabController,
    world: &WorldSpec,
    goal: &dyn Goal,
    noise_seed: u64,
    config: &TrialConfig,
    recording: Option<TrialRecording<'_>>,
) -> Result<TrialRecord, LabError> {
    let physics = config.physics(noise_seed);
    let plant = PhysicsPlant::new(world, physics).map_err(|source| LabError::Physics {
        trial: format!("{} (seed {noise_seed})", controller.label),
        source,
    })?;
    let temporal_freq_rad_s = config.gaits.get(controller.gait).temporal_freq_rad_s;
    let start_links_m = links(&plant);
    let n_links = start_links_m.len();
    let record_path = recording
        .as_ref()
        .map(|r| r.path.clone())
        .unwrap_or_default();
    let (mut lp, mut signal_names, recorder, requests, pose) =
        trial_loop(controller, plant, config, recording, &[])?;
    let mut source = config
        .pose_source
        .zip(pose)
        .map(|(s, input)| (SimSource::new(s, noise_seed), input));
    let mut nav = match controller.navigator {
        Some(mut cfg) => {
            // Aimed as the single controllers are.
            if let Some(a) = config.aim {
                cfg.sidewind_drift_rad = a.sidewind_drift_rad;
            }
            let travel = config
                .aim
                .map_or(0.0, |a| a.travel_in_estimate(world.start.yaw_rad));
            let layout = BodyLayout::alternating(config.modules, Plane::Lateral, MODULE_LENGTH_M);
            let first = crate::navigation::navigator::Choice::Sidewind;
            // The controllers' signals change with its choices: only its choice is kept,
            // and with a source the position's error and the cross-track error.
            signal_names = vec![super::trial_navigator::CHOICE_SIGNAL.into()];
            if source.is_some() {
                signal_names.extend(super::trial_navigator::POSITION_SIGNALS.map(String::from));
            }
            // By position to the aim's goal when the trial has a source.
            let goal_m = config
                .aim
                .and_then(|a| a.goal_m)
                .filter(|_| source.is_some());
            Some(TrialNavigator::new(
                cfg,
                travel,
                goal_m,
                layout,
                config.gaits,
                first,
            ))
        }
        None => None,
    };
    let switch_step = config
        .lead_in()
        .map(|(_, s)| ((s / config.dt_s).round() as usize).max(2));

    let heading = config
        .aim
        .filter(|_| nav.is_none())
        .and_then(|a| a.nominal_heading(controller.gait, world.start.yaw_rad));
    let mut aim = PendingHeading::new(controller.gait, heading);
    let steps = (config.limit_s / config.dt_s).round() as usize;
    let per_sample = config.steps_per_sample();
    let samples = steps / per_sample + 1;
    let mut rec = TrialRecord {
        sample_dt_s: config.sample_dt_s(),
        centre_m: Vec::with_capacity(samples),
        links_m: Vec::with_capacity(samples * start_links_m.len()),
        start_links_m,
        end_links_m: Vec::new(),
        signals: vec![Vec::with_capacity(samples); signal_names.len()],
        signal_names,
        seconds: 0.0,
        success: false,
        temporal_freq_rad_s,
        cycles_not_running: 0,
        self_contacts: 0,
        heights_m: Vec::with_capacity(samples * n_links),
        windows: Vec::new(),
        strain: Strain::default(),
        stuck_reported: Vec::with_capacity(samples),
        gait_switches: 0,
        estimate: Vec::with_capacity(samples),
        position_error_m: Vec::new(),
    };
    record(&lp, &mut rec, nav.as_ref());
    if source.is_some() {
        record_position(&lp, &mut rec);
    }
    for k in 1..=steps {
        if Some(k) == switch_step {
            let request = crate::rt::messages::LoopRequest::SetGait {
                gait: controller.gait,
            };
            let _ = requests.try_send(crate::rt::messages::Envelope::new(1 << 32, request));
        }
        aim.send_when_engaged(&lp, &requests, 2 << 32);
        let guarded = lp.guard_counters().slew_limited_cycles;
        if let Some((s, input)) = source.as_mut() {
            s.step(k as f64 * config.dt_s, plant_of(&lp), input);
        }
        if lp.step() == Flow::Finished {
            break;
        }
        if lp.mode() != crate::safety::failsafe::Mode::Running {
            rec.cycles_not_running += 1;
        }
        add_strain(&lp, guarded, &mut rec.strain);
        if k % per_sample == 0 {
            if let Some(n) = nav.as_mut().filter(|n| !n.arrived()) {
                n.step(k as f64 * config.dt_s, &lp, &requests)?;
            }
            record(&lp, &mut rec, nav.as_ref());
            if source.is_some() {
                record_position(&lp, &mut rec);
            }
            if goal.reached(plant_of(&lp)) {
                rec.success = true;
                break;
            }
        }
    }
    let plant = plant_of(&lp);
    rec.seconds = plant.time_s();
    rec.end_links_m = links(plant);
    rec.self_contacts = plant.self_contacts();
    rec.gait_switches = nav.as_ref().map_or(0, TrialNavigator::switches);
    drop(lp); // The loop's end of the ring first: the file then holds everything.
    if let Some(r) = recorder {
        r.finish().map_err(|source| LabError::Record {
            path: record_path,
            source,
        })?;
    }
    Ok(rec)
}

/// One cycle's strain: whether the guard limited it (its count moved past
/// `guarded_before`) and the modules' reported speeds and torques.
fn add_strain(lp: &ControlLoop, guarded_before: u64, strain: &mut Strain) {
    let plant = plant_of(lp);
    let limited = lp.guard_counters().slew_limited_cycles > guarded_before;
    let joints = (0..plant.module_count()).map(|i| {
        let f = plant.feedback(i);
        (f64::from(f.velocity_rad_s), f64::from(f.torque_nm))
    });
    strain.add_cycle(&StrainLimits::SEA, limited, joints);
}

pub(crate) fn plant_of(lp: &ControlLoop) -> &dyn Plant {
    SimBus::of(lp.bus())
        .expect("a trial runs over a SimBus")
        .plant()
}

/// With a position source: how far the fused position is from the truth this sample
/// (the centre [`record`] has just recorded).
fn record_position(lp: &ControlLoop, rec: &mut TrialRecord) {
    let truth = rec.centre_m.last().copied().unwrap_or_default();
    rec.position_error_m
        .push(position_error(&lp.body().world, truth));
}

fn record(lp: &ControlLoop, rec: &mut TrialRecord, nav: Option<&TrialNavigator>) {
    let plant = plant_of(lp);
    rec.centre_m.push(centre(plant));
    rec.links_m
        .extend((0..plant.link_count()).map(|k| ground(plant.link_pose(k).position_m)));
    rec.heights_m
        .extend((0..plant.link_count()).map(|k| plant.link_pose(k).position_m[2]));
    rec.stuck_reported.push(lp.progress().stuck);
    let b = lp.body();
    rec.estimate.push(if b.valid {
        [b.odometry_m[0], b.odometry_m[1], b.heading_rad]
    } else {
        [f64::NAN; 3]
    });
    if nav.is_some() {
        // As the loop reports it (the runner tells the loop at each decision).
        let n = lp.navigator();
        let error_mm = 1e3 * position_error(&b.world, centre(plant));
        let values = [n.choice_code(), error_mm, n.cross_track_m];
        for (series, v) in rec.signals.iter_mut().zip(values) {
            series.push(v);
        }
        return;
    }
    let report = lp.controllers().report();
    for (k, series) in rec.signals.iter_mut().enumerate() {
        series.push(report.map_or(f64::NAN, |(_, r)| r.signals[k]));
    }
    if let Some((_, r)) = report
        && r.fields.first().is_some_and(|f| !f.is_empty())
    {
        let f = &r.fields[0];
        if rec.windows.len() + 1 < rec.centre_m.len() {
            rec.windows.resize(rec.centre_m.len() - 1, Vec::new());
        }
        rec.windows.push(
            (0..f.len())
                .map(|w| {
                    let mut row = [0.0; 1 + MAX_COLUMNS];
                    row[0] = 0.5 * (f.a[w].clamp(0.0, 1.0) + f.b[w].clamp(0.0, 1.0));
                    for (c, col) in f.columns.iter().enumerate() {
                        row[1 + c] = col[w];
                    }
                    row
                })
                .collect(),
        );
    }
}

#[cfg(test)]
#[path = "trial_tests.rs"]
pub(crate) mod tests;
