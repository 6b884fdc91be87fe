//! Shared by the socket tests: a fake loop behind the real server, and a client.

use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use serde_json::Value;
use snaked::controller_interface::catalog::Catalog;
use snaked::gait::{BodyLayout, GaitKind, GaitParams, GaitTable, Plane};
use snaked::rt::channels::loop_channels;
use snaked::rt::control_loop::ControlLoop;
use snaked::rt::harness::Harness as LoopHarness;
use snaked::rt::messages::{Ack, LoopRequest, Rejection};
use snaked::rt::telemetry::{self, Snapshot};
use snaked::safety::failsafe::{Mode, Reason};
use snaked::socket::client::{Client, Endpoint};
use snaked::socket::{BusKind, DaemonInfo, LoopHandle, Pacing, RunningServer, ServerConfig};

/// What the fake loop answers to a request.
pub type Policy = Arc<dyn Fn(&LoopRequest) -> Option<Result<(), Rejection>> + Send + Sync>;

/// Ack everything with Ok.
pub fn accept_all() -> Policy {
    Arc::new(|_| Some(Ok(())))
}

/// How the fake loop is built.
pub struct LoopSpec {
    pub channel_capacity: usize,
    /// Whether it reads its request channel at all.
    pub drains: bool,
    /// `None` from the policy: never ack that request.
    pub policy: Policy,
    pub joints: usize,
}

impl Default for LoopSpec {
    fn default() -> Self {
        Self {
            channel_capacity: 16,
            drains: true,
            policy: accept_all(),
            joints: 8,
        }
    }
}

/// A hand-built gait table whose every gait passes validation.
pub fn table() -> GaitTable {
    let mut gaits = [GaitParams::default(); 6];
    gaits[GaitKind::Slithering.index()] = GaitParams {
        amplitude_lat_rad: 0.7,
        spatial_freq_rad: 3.0 * PI,
        temporal_freq_rad_s: 1.5,
        ..GaitParams::default()
    };
    gaits[GaitKind::Sidewinding.index()] = GaitParams {
        amplitude_lat_rad: 0.5,
        amplitude_dor_rad: 0.3,
        spatial_freq_rad: 3.0 * PI,
        temporal_freq_rad_s: 1.5,
        phase_shift_rad: 3.0 * PI / 4.0,
        ..GaitParams::default()
    };
    gaits[GaitKind::Rolling.index()] = GaitParams {
        amplitude_lat_rad: 0.3,
        amplitude_dor_rad: 0.3,
        temporal_freq_rad_s: 1.0,
        phase_shift_rad: PI / 2.0,
        ..GaitParams::default()
    };
    GaitTable { gaits }
}

/// A thread standing in for the 1 kHz loop: applies requests to its snapshot,
/// acks them per the policy, publishes telemetry every millisecond.
pub struct FakeLoop {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// Every request the loop received, in order.
    pub seen: Arc<Mutex<Vec<LoopRequest>>>,
    /// The slithering controller attached to each request that carried one
    /// ("open_loop" or the built controller's name), in order.
    pub controllers: Arc<Mutex<Vec<String>>>,
}

impl FakeLoop {
    pub fn seen(&self) -> Vec<LoopRequest> {
        self.seen.lock().unwrap().clone()
    }

    pub fn controllers(&self) -> Vec<String> {
        self.controllers.lock().unwrap().clone()
    }
}

impl Drop for FakeLoop {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

fn apply(s: &mut Snapshot, r: &LoopRequest) {
    match *r {
        LoopRequest::SetGait { gait: g } => {
            s.gait = g;
            s.blend_progress = 0.0;
            s.mode = Mode::Running;
        }
        LoopRequest::SetParams { gait: g, patch } => {
            if let Ok(p) = s.params.get(g).patched(g, &patch) {
                *s.params.get_mut(g) = p;
            }
        }
        LoopRequest::SetBlendTime { blend_time_s: t } => s.blend_time_s = t,
        LoopRequest::Hold => s.mode = Mode::Hold,
        LoopRequest::Limp | LoopRequest::Shutdown => s.mode = Mode::Limp,
        LoopRequest::EStop => s.mode = Mode::EStop,
        LoopRequest::Arm => s.mode = Mode::Running,
        LoopRequest::SetController { .. } | LoopRequest::ControllerCommand { .. } => {}
        LoopRequest::Navigation { state } => s.navigator = state,
        LoopRequest::StopGait { .. } => s.motion = snaked::rt::gait_clock::Motion::Stopped,
        LoopRequest::ResumeGait { .. } => s.motion = snaked::rt::gait_clock::Motion::Running,
    }
    s.reason = Reason::Operator;
}

pub fn fake_loop(spec: LoopSpec) -> (FakeLoop, LoopHandle) {
    let (control_ends, loop_ends) = loop_channels(spec.channel_capacity);
    let (req_rx, ack_tx) = (loop_ends.requests, loop_ends.acks);
    let initial = Snapshot::new(spec.joints, GaitKind::Slithering, table(), 2.0);
    let (mut writer, reader) = telemetry::channel(initial.clone());
    let stop = Arc::new(AtomicBool::new(false));
    let seen = Arc::new(Mutex::new(Vec::new()));
    let controllers = Arc::new(Mutex::new(Vec::new()));
    let catalog = Catalog::default();
    let thread = {
        let (stop, seen, controllers) = (stop.clone(), seen.clone(), controllers.clone());
        let catalog = catalog.clone();
        std::thread::spawn(move || {
            let mut state = initial;
            // The receiver lives here even when not draining, so sends see "full".
            while !stop.load(Ordering::Relaxed) {
                if spec.drains {
                    while let Ok(env) = req_rx.try_recv() {
                        seen.lock().unwrap().push(env.request);
                        if let Some(c) = &env.controller {
                            let info = catalog.get(c.id).expect("built controllers are named");
                            let name = format!("{}/{}", info.controller, info.preset);
                            controllers.lock().unwrap().push(name);
                        }
                        if let Some(result) = (spec.policy)(&env.request) {
                            if result.is_ok() {
                                apply(&mut state, &env.request);
                                let gait = match env.request {
                                    LoopRequest::SetController { gait: g }
                                    | LoopRequest::SetParams { gait: g, patch: _ } => Some(g),
                                    _ => None,
                                };
                                if let (Some(c), Some(g)) = (&env.controller, gait) {
                                    state.controller.installed[g.index()] = c.id;
                                    if g == state.gait {
                                        state.controller.active_id = c.id;
                                    }
                                }
                                state.requests_applied += 1;
                            } else {
                                state.requests_refused += 1;
                            }
                            let _ = ack_tx.send(Ack {
                                ticket: env.ticket,
                                result: result.map(|()| None),
                            });
                        }
                    }
                }
                state.cycle += 1;
                state.t_s += 0.001;
                state.stats.cycles = state.cycle;
                state
                    .stats
                    .wakeup_latency
                    .record(2_000 + state.cycle % 50 * 100);
                state
                    .stats
                    .period_error
                    .record(2_000 + state.cycle % 50 * 100);
                state.bus.feedback_received += state.joints.len() as u64;
                state.blend_progress = (state.blend_progress + 0.01).min(1.0);
                for (i, j) in state.joints.iter_mut().enumerate() {
                    j.position_rad = 0.1 * i as f64;
                    j.setpoint_rad = 0.1 * i as f64 + 0.01;
                    j.torque_nm = 0.5;
                    j.feedback_age_s = 0.001;
                }
                let s = &state;
                writer.write(|out| out.clone_from(s));
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    let info = DaemonInfo {
        version: "test".into(),
        module_count: spec.joints,
        module_names: (0..spec.joints).map(|i| format!("SA{i:03}")).collect(),
        loop_rate_hz: 1000.0,
        bus: BusKind::Emulated,
        pacing: Pacing::Realtime,
    };
    let handle = LoopHandle {
        requests: control_ends.requests,
        acks: control_ends.acks,
        telemetry: reader,
        info,
        layout: BodyLayout::alternating(spec.joints, Plane::Lateral, 0.064),
        retired: control_ends.retired,
        catalog,
    };
    let fake = FakeLoop {
        stop,
        thread: Some(thread),
        seen,
        controllers,
    };
    (fake, handle)
}

/// A server on a Unix socket in a temporary directory, with a fake loop.
pub struct Harness {
    pub server: Option<RunningServer>,
    pub path: PathBuf,
    pub fake: FakeLoop,
    pub dir: tempfile::TempDir,
}

impl Harness {
    pub fn new(spec: LoopSpec, tweak: impl FnOnce(&mut ServerConfig)) -> Self {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snaked.sock");
        let mut cfg = ServerConfig {
            unix_path: Some(path.clone()),
            ..ServerConfig::default()
        };
        tweak(&mut cfg);
        let (fake, handle) = fake_loop(spec);
        let server = snaked::socket::start(cfg, handle).expect("server starts");
        Self {
            server: Some(server),
            path,
            fake,
            dir,
        }
    }

    pub fn default_server() -> Self {
        Self::new(LoopSpec::default(), |_| {})
    }

    pub fn client(&self) -> Client {
        Client::connect(
            &Endpoint::Unix(self.path.clone()),
            Some(Duration::from_secs(10)),
        )
        .expect("connects")
    }
}

/// Send a raw line and return the next answer (skipping stream messages).
pub fn raw(c: &mut Client, line: &str) -> Value {
    c.send_line(line).unwrap();
    loop {
        let m = c.next_message().unwrap();
        if m.get("id").is_some() {
            return m;
        }
    }
}

/// The error code of an answer (panics when it is a result).
/// `method` with `params` (an object), answered as it came (result or error).
pub fn call(c: &mut Client, method: &str, params: Value) -> Value {
    let line = serde_json::json!({"id": 1, "method": method, "params": params}).to_string();
    raw(c, &line)
}

pub fn error_code(answer: &Value) -> i64 {
    answer["error"]["code"]
        .as_i64()
        .unwrap_or_else(|| panic!("expected an error, got {answer}"))
}

pub fn error_message(answer: &Value) -> String {
    answer["error"]["message"]
        .as_str()
        .unwrap_or_default()
        .to_owned()
}

/// A real loop (`snaked::rt::harness`) behind the real server, stepped on its own
/// thread; stops both when dropped.
pub struct RealLoop {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    pub server: Option<RunningServer>,
    pub path: PathBuf,
    _dir: tempfile::TempDir,
}

impl Drop for RealLoop {
    fn drop(&mut self) {
        if let Some(s) = self.server.take() {
            s.shutdown();
        }
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

/// Serves `h`'s loop on a socket in a temporary directory; `pace` runs on the loop's
/// thread until the loop is dropped (e.g. a few steps, then a sleep).
pub fn serve_real_loop(
    h: LoopHarness,
    mut pace: impl FnMut(&mut ControlLoop) + Send + 'static,
) -> RealLoop {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("snaked.sock");
    let handle = LoopHandle {
        requests: h.requests.clone(),
        acks: h.acks.clone(),
        telemetry: h.telemetry.clone(),
        info: DaemonInfo {
            version: "test".into(),
            module_count: h.layout.len(),
            loop_rate_hz: 1000.0,
            bus: BusKind::Emulated,
            pacing: Pacing::Lockstep,
            ..DaemonInfo::default()
        },
        layout: h.layout.clone(),
        retired: h.retired.clone(),
        catalog: h.catalog.clone(),
    };
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        ..ServerConfig::default()
    };
    let server = snaked::socket::start(cfg, handle).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let mut control = h.control;
    let thread = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                pace(&mut control);
            }
        })
    };
    RealLoop {
        stop,
        thread: Some(thread),
        server: Some(server),
        path,
        _dir: dir,
    }
}
