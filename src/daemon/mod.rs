//! Wiring of the daemon: configuration, discovery, the loop thread, the socket
//! server and the service manager.

pub mod bus_setup;
pub mod config;
mod config_bus;
mod config_pose;
mod config_record;
mod config_ros2;
pub mod files;
pub mod logging;
pub mod service;
pub mod token;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use anyhow::{Context, Result};

use crate::controller_interface::BuildContext;
use crate::controller_interface::catalog::Catalog;
use crate::controller_interface::registry;
use crate::controllers::REGISTRY;
use crate::estimation::external_pose;
use crate::estimation::world_position::WorldPositionEstimator;
use crate::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable};
use crate::live::LiveOptions;
use crate::record::{LoopRecorder, LoopRecording};
use crate::record::{RecordOptions, RecordTx, Recorder, RecordingInfo};
use crate::rt::control_loop::{ControlLoop, LoopParts};
use crate::rt::controller_slots::Installed;
use crate::rt::observer::CycleObserver;
use crate::rt::pacer::{LockstepPacer, Pacer, RealTimePacer};
use crate::rt::sys;
use crate::rt::telemetry::{self, Snapshot, TelemetryReader};
use crate::safety::failsafe::{Failsafe, FailsafeConfig};
use crate::socket::{self, DaemonInfo, LoopHandle, ServerConfig};
use crate::station::{Station, StationConfig};
use config::{Config, Pacing, StartMode};

/// What the command line chose, over the configuration file.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub emulated: bool,
    pub world: Option<PathBuf>,
    pub socket: Option<PathBuf>,
    pub tcp_port: Option<u16>,
    pub start: Option<StartMode>,
    pub pacing: Option<Pacing>,
    /// `--record FILE.mcap` (overrides record.path).
    pub record: Option<PathBuf>,
    /// `--foxglove`: serve the live view (foxglove.enabled).
    pub foxglove: bool,
    /// `--operate`: drive and tune from Foxglove too (foxglove.operate).
    pub operate: bool,
}

/// Apply the command line to the configuration. `--emulated` starts the gait at once
/// unless `--start` says otherwise: the emulator has nothing to break.
pub fn apply_overrides(cfg: &mut Config, o: &Overrides) {
    if let Some(s) = &o.socket {
        cfg.control.socket = s.clone();
    }
    if let Some(w) = &o.world {
        cfg.emulator.world = w.clone();
    }
    if let Some(p) = o.tcp_port {
        cfg.control.tcp_port = p;
    }
    if let Some(p) = o.pacing {
        cfg.loop_.pacing = p;
    }
    if let Some(r) = &o.record {
        cfg.record.path = r.clone();
    }
    cfg.foxglove.enabled |= o.foxglove;
    cfg.foxglove.operate |= o.operate;
    // Operating needs the server it operates through.
    cfg.foxglove.enabled |= cfg.foxglove.operate;
    cfg.gait.start = match (o.start, o.emulated) {
        (Some(s), _) => s,
        (None, true) => StartMode::Run,
        (None, false) => cfg.gait.start,
    };
}

/// The configured gait parameters, validated as a whole for this body's module length.
fn gait_table(cfg: &Config) -> Result<GaitTable> {
    let path = std::path::Path::new("configuration");
    let table = cfg.gait_table(path)?;
    table
        .validate_for(cfg.body.module_length_m)
        .map_err(|(kind, e)| anyhow::anyhow!("bad configuration: gait {}: {e}", kind.name()))?;
    Ok(table)
}

/// Every gait's configured controller, built for `layout` and recorded in `catalog`.
pub fn build_controllers(
    cfg: &Config,
    layout: &BodyLayout,
    table: &GaitTable,
    catalog: &Catalog,
) -> Result<Vec<(GaitKind, Installed)>> {
    GaitKind::ALL
        .into_iter()
        .map(|gait| {
            let ctx = BuildContext {
                gait,
                layout,
                params: table.get(gait),
            };
            let built = registry::build(REGISTRY, &cfg.controller_selection(gait), &ctx)
                .with_context(|| {
                    format!("bad configuration: [gait.controllers.{}]", gait.name())
                })?;
            let info = catalog.insert(built.info);
            Ok((
                gait,
                Installed {
                    id: info.id,
                    controller: built.controller,
                },
            ))
        })
        .collect()
}

/// Run the daemon until SIGINT/SIGTERM (or a `Shutdown` request) has brought the
/// robot to a safe stop.
pub fn run(cfg: Config, emulated: bool) -> Result<()> {
    // Before any thread starts: they all inherit a CPU set without the loop's CPU (the
    // loop thread pins itself to it), so none of them preempts the loop or delays its
    // wake-up there.
    if let Some(cpu) = cfg.loop_.cpu {
        match sys::avoid_cpu(cpu) {
            Ok(true) => {}
            Ok(false) => tracing::warn!(
                "the daemon's other threads share CPU {cpu} with the loop (it is the only \
                 one they may use, or not one of theirs)"
            ),
            Err(e) => tracing::warn!("keeping the other threads off CPU {cpu} refused ({e})"),
        }
    }
    // Held until the daemon returns.
    let _cpu_latency = cfg.loop_.cpu_latency_limit_s().and_then(|s| {
        let us = (s * 1e6).round() as i32;
        sys::limit_cpu_latency_us(us)
            .inspect_err(|e| {
                tracing::warn!(
                    "limiting the CPUs' wake-up latency to {us} µs refused ({e}); idle CPUs \
                     may take longer to wake for the loop"
                );
            })
            .ok()
    });
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .context("installing the SIGINT/SIGTERM handler")?;
    }
    // Past a file-size limit (`LimitFSIZE=`, `ulimit -f`) a write must fail with EFBIG,
    // which the recorder reports (the file unfinished, the robot driven on), not kill the
    // daemon with SIGXFSZ before its safe stop.
    // SAFETY: only sets the signal's disposition; no handler runs.
    unsafe { libc::signal(libc::SIGXFSZ, libc::SIG_IGN) };

    // The configuration's check refused caps that do not fit below the hard limit.
    match files::raise_file_limit() {
        Ok(n) => tracing::debug!(open_files = n, "file limit"),
        Err(e) => tracing::warn!("raising the open files' soft limit refused ({e})"),
    }
    let needed = cfg.files_needed();
    if let Ok(l) = files::file_limit()
        && l.soft < needed
    {
        anyhow::bail!(
            "the connections the configuration lets in need {needed} open files, more than \
             the {} the process may open (RLIMIT_NOFILE; systemd: LimitNOFILE=)",
            l.soft
        );
    }

    // Everything that can be refused without the robot is checked before discovery.
    let table = gait_table(&cfg)?;
    let period_ns = (1e9 / cfg.loop_.rate_hz).round() as u64;
    let built = match bus_setup::build(&cfg, emulated, period_ns, &stop) {
        Ok(b) => b,
        // A signal during discovery: nothing is driven yet, so stopping is all there is.
        Err(e) if stopped_in_discovery(&e) => {
            tracing::info!("stopped during discovery");
            return Ok(());
        }
        Err(e) => return Err(e),
    };
    let n = built.bus.module_count();
    tracing::info!(modules = n, bus = ?built.kind, names = ?built.names, "group ready");
    service::notify_status(&format!("group of {n} modules found"));

    let layout = BodyLayout::alternating(n, cfg.body.first_joint_plane, cfg.body.module_length_m);
    let catalog = Catalog::default();
    let controllers = build_controllers(&cfg, &layout, &table, &catalog)?;
    let mut estimators = crate::estimation::standard_estimators(&layout);
    let station = operator_station(&cfg)?;
    let recorder = start_recorder(&cfg, &built, &layout, &catalog, station.as_ref())?;
    let selector = GaitSelector::new(
        layout.clone(),
        table,
        cfg.gait.initial,
        cfg.gait.blend_time_s,
        cfg.gait.max_joint_speed_rad_s,
    );
    let failsafe = Failsafe::new(FailsafeConfig {
        feedback_timeout_s: cfg.failsafe.feedback_timeout_s,
        limp_after_s: cfg.failsafe.limp_after_s,
        auto_resume: cfg.failsafe.auto_resume,
        shutdown_hold_s: cfg.failsafe.shutdown_hold_s,
    });
    let pacer: Box<dyn Pacer> = match cfg.loop_.pacing {
        Pacing::Realtime => Box::new(RealTimePacer::with_busy_wait(
            period_ns,
            (cfg.loop_.busy_wait_s * 1e9).round() as u64,
        )),
        Pacing::Lockstep => Box::new(LockstepPacer::new(
            period_ns,
            (cfg.loop_.lockstep_timeout_s * 1e9) as u64,
        )),
    };

    // The pose input (`pose.external`, ROS 2's pose topic): sources write, the loop's
    // last estimator reads.
    let (pose, pose_reader) = external_pose::pose_input(pacer.epoch_monotonic_ns());
    estimators.push(Box::new(WorldPositionEstimator::new(
        pose_reader,
        cfg.pose.fusion(),
    )));
    let (control_ends, loop_ends) =
        crate::rt::channels::loop_channels(cfg.control.channel_capacity);
    let (tel_writer, tel_reader) = telemetry::channel(Snapshot::new(
        n,
        cfg.gait.initial,
        table,
        cfg.gait.blend_time_s,
    ));
    let heartbeat = Arc::new(AtomicU64::new(0));

    let mut server_cfg = server_config(&cfg);
    server_cfg.pose = Some(pose);
    server_cfg.record = recorder.as_ref().map(|(_, r, _)| {
        let probe = r.probe();
        socket::RecordView::new(move || serde_json::json!(probe.status()))
    });
    if cfg.control.tcp_port != 0 {
        if cfg.control.tcp_token_file.as_os_str().is_empty() {
            anyhow::bail!(
                "bad configuration: a TCP port needs control.tcp_token_file (a token file \
                 readable by the operators' group): without it any local user could drive \
                 the robot"
            );
        }
        let path = &cfg.control.tcp_token_file;
        let token = token::read_token(path)
            .with_context(|| format!("control.tcp_token_file {}", path.display()))?;
        server_cfg.tcp_token = Some(token);
    }
    let server = socket::start(
        server_cfg,
        LoopHandle {
            requests: control_ends.requests,
            acks: control_ends.acks,
            telemetry: tel_reader.clone(),
            info: DaemonInfo {
                version: env!("CARGO_PKG_VERSION").to_owned(),
                module_count: n,
                module_names: built.names.clone(),
                loop_rate_hz: cfg.loop_.rate_hz,
                bus: built.kind,
                pacing: match cfg.loop_.pacing {
                    Pacing::Realtime => socket::Pacing::Realtime,
                    Pacing::Lockstep => socket::Pacing::Lockstep,
                },
            },
            layout,
            retired: control_ends.retired,
            catalog: catalog.clone(),
        },
    )
    .context("starting the control socket")?;
    if let Some(ros2) = recorder.as_ref().and_then(|(_, _, r)| r.as_ref()) {
        ros2.bind(server.operator());
    }
    if let Some(station) = &station {
        station.bind(server.operator());
        let auth = if station.config.token.is_some() {
            "token required"
        } else {
            "loopback, no token"
        };
        tracing::info!(
            "operating from Foxglove: services and teleop on {} ({auth})",
            station.config.teleop.topic
        );
    }

    let parts = LoopParts {
        bus: built.bus,
        pacer,
        selector,
        failsafe,
        requests: loop_ends.requests,
        acks: loop_ends.acks,
        telemetry: tel_writer,
        heartbeat: heartbeat.clone(),
        stop: stop.clone(),
        velocity_feedforward: cfg.loop_.velocity_feedforward,
        hold_at_start: cfg.gait.start == StartMode::Hold,
        retired: loop_ends.retired,
        controllers,
        estimators,
        observer: recorder.as_ref().map(|(tx, _, _)| {
            let out = LoopRecording {
                tx: tx.clone(),
                wait_when_full: false,
            };
            Box::new(LoopRecorder::new(out)) as Box<dyn CycleObserver>
        }),
    };
    let rt = cfg.loop_.clone();
    let loop_thread = std::thread::Builder::new()
        .name("snaked-rt".into())
        .spawn(move || {
            apply_realtime_settings(&rt);
            ControlLoop::new(parts).run()
        })
        .context("spawning the loop thread")?;

    supervise(&heartbeat, &tel_reader, &loop_thread, n);

    let report = loop_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the control loop panicked"))?;
    service::notify_stopping();
    server.shutdown();
    if let Some((_, recorder, _)) = recorder {
        finish_recorder(recorder);
    }
    tracing::info!(
        cycles = report.cycles,
        wakeup_latency_p99_us = report.wakeup_latency.p99_us,
        period_error_p99_us = report.period_error.p99_us,
        compute_p99_us = report.compute.p99_us,
        overruns = report.overruns,
        "stopped safely"
    );
    Ok(())
}

fn stopped_in_discovery(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<crate::bus::udp::DiscoveryError>(),
            Some(crate::bus::udp::DiscoveryError::Stopped)
        )
    })
}

/// The recorder and live view the configuration asks for (`None`: neither). Fails
/// before the loop starts if the file cannot be created or the port is taken.
fn start_recorder(
    cfg: &Config,
    built: &bus_setup::BuiltBus,
    layout: &BodyLayout,
    catalog: &Catalog,
    station: Option<&Station>,
) -> Result<Option<(RecordTx, Recorder, Option<crate::ros2::Ros2Handle>)>> {
    let rec = &cfg.record;
    let mcap = rec.mcap_options();
    if mcap.is_none() && !cfg.foxglove.enabled && !cfg.ros2.enabled {
        return Ok(None);
    }
    let opts = RecordOptions {
        mcap,
        live: cfg.foxglove.enabled.then(|| LiveOptions {
            addr: std::net::SocketAddr::new(cfg.foxglove.host, cfg.foxglove.port),
            station: station.cloned(),
            max_connections: Some(cfg.foxglove.max_connections),
            max_connections_per_address: Some(cfg.foxglove.max_connections_per_address),
            handshake_timeout: Some(Duration::from_secs_f64(cfg.foxglove.handshake_timeout_s)),
        }),
        ring_capacity: rec.ring_capacity,
        scene_rate_hz: rec.scene_rate_hz,
    };
    let info = RecordingInfo {
        source: "snaked".into(),
        module_names: built.names.clone(),
        layout: layout.clone(),
        world: built.world.clone(),
        catalog: catalog.clone(),
        metadata: vec![
            ("version".into(), env!("CARGO_PKG_VERSION").into()),
            ("bus".into(), format!("{:?}", built.kind)),
            ("loop_rate_hz".into(), cfg.loop_.rate_hz.to_string()),
        ],
    };
    let (sink, ros2) = match start_ros2(cfg, built, layout)? {
        Some((sink, handle)) => (Some(sink), Some(handle)),
        None => (None, None),
    };
    let (tx, recorder) =
        crate::record::start_with(opts, info, sink).context("starting the recorder")?;
    if let Some(addr) = recorder.live_addr() {
        tracing::info!("live view (Foxglove WebSocket) on ws://{addr}");
    }
    Ok(Some((tx, recorder, ros2)))
}

/// The ROS 2 node `[ros2]` asks for (`None`: off), as the recorder's sink: its thread
/// ends when the recorder finishes and drops the sink.
fn start_ros2(
    cfg: &Config,
    built: &bus_setup::BuiltBus,
    layout: &BodyLayout,
) -> Result<Option<(Box<dyn crate::record::CycleSink>, crate::ros2::Ros2Handle)>> {
    let r = &cfg.ros2;
    if !r.enabled {
        return Ok(None);
    }
    let urdf = crate::record::urdf::urdf(layout, &built.names);
    let (sink, handle) =
        crate::ros2::start(&r.options(cfg.foxglove.teleop()), built.names.clone(), urdf)
            .context("starting the ROS 2 node")?;
    tracing::info!(
        node = %r.node_name,
        namespace = %r.namespace,
        domain = r.domain_id,
        operate = r.operate,
        "ROS 2 node up"
    );
    if r.operate {
        let beyond = crate::ros2::interfaces_beyond_loopback();
        if !beyond.is_empty() {
            tracing::warn!(
                "ROS 2 may drive this robot ([ros2] operate) and DDS discovery reaches \
                 beyond localhost (on {}): DDS has no authentication, so anyone on those \
                 networks in domain {} can drive it",
                beyond.join(", "),
                r.domain_id
            );
        }
    }
    Ok(Some((Box::new(sink), handle)))
}

/// The operator's station the configuration asks for (`[foxglove] operate`), with its
/// token read from `token_file` (as the configuration's check reads it).
fn operator_station(cfg: &Config) -> Result<Option<Station>> {
    let fx = &cfg.foxglove;
    if !(fx.enabled && fx.operate) {
        return Ok(None);
    }
    let token = fx
        .token()
        .with_context(|| format!("foxglove.token_file {}", fx.token_file.display()))?;
    let teleop = fx.teleop();
    teleop
        .check()
        .map_err(|e| anyhow::anyhow!("bad configuration: foxglove: {e}"))?;
    Ok(Some(Station::new(StationConfig { token, teleop })))
}

/// Finishes the file (summary and index) and says what it holds.
fn finish_recorder(recorder: Recorder) {
    match recorder.finish() {
        Ok(s) => tracing::info!(
            path = ?s.path,
            items = s.items,
            messages = s.messages_written,
            dropped = s.dropped,
            bytes = s.bytes,
            capped = ?s.capped,
            "recording finished"
        ),
        Err(e) => tracing::error!("recording: {e}"),
    }
}

fn server_config(cfg: &Config) -> ServerConfig {
    let socket = &cfg.control.socket;
    ServerConfig {
        unix_path: if socket.as_os_str().is_empty() {
            None
        } else if socket.as_os_str() == "auto" {
            Some(crate::socket::paths::daemon_socket())
        } else {
            Some(socket.clone())
        },
        tcp_port: (cfg.control.tcp_port != 0).then_some(cfg.control.tcp_port),
        max_line_bytes: cfg.control.max_line_bytes,
        max_clients: cfg.control.max_clients,
        ack_timeout: Duration::from_secs_f64(cfg.control.ack_timeout_s),
        idle_timeout: (cfg.control.idle_timeout_s > 0.0)
            .then(|| Duration::from_secs_f64(cfg.control.idle_timeout_s)),
        driver_timeout: Duration::from_secs_f64(cfg.control.driver_timeout_s),
        ..ServerConfig::default()
    }
}

/// Each real-time setting is attempted; a refusal is a warning, not a failure.
fn apply_realtime_settings(rt: &config::LoopConfig) {
    let slack_ns = (rt.timer_slack_s * 1e9).round().max(1.0) as u64;
    if let Err(e) = sys::set_timer_slack_ns(slack_ns) {
        tracing::warn!("timer slack refused ({e}); sleeps may end up to 50 µs late");
    }
    if rt.lock_memory
        && let Err(e) = sys::lock_memory()
    {
        tracing::warn!("mlockall refused ({e}); carrying on without locked memory");
    }
    if let Some(cpu) = rt.cpu
        && let Err(e) = sys::pin_to_cpu(cpu)
    {
        tracing::warn!("pinning the loop to CPU {cpu} refused ({e}); carrying on unpinned");
    }
    if rt.sched_fifo_priority > 0
        && let Err(e) = sys::set_fifo_priority(rt.sched_fifo_priority)
    {
        tracing::warn!(
            "SCHED_FIFO priority {} refused ({e}); carrying on with the default scheduler",
            rt.sched_fifo_priority
        );
    }
}

/// The main thread while the loop runs: READY once the loop turns, watchdog pings
/// while it keeps turning, and a log line for every change of mode or gait (the loop
/// itself never logs).
fn supervise(
    heartbeat: &Arc<AtomicU64>,
    telemetry: &TelemetryReader,
    loop_thread: &std::thread::JoinHandle<crate::rt::stats::StatsReport>,
    n: usize,
) {
    let mut ready = false;
    let mut last = None;
    let mut watchdog = service::Watchdog::from_env(heartbeat.clone());
    while !loop_thread.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
        if !ready && heartbeat.load(Ordering::Acquire) > 0 {
            ready = true;
            service::notify_ready(&format!("running {n} modules"));
            tracing::info!(watchdog = watchdog.enabled(), "loop running; READY");
        }
        if ready && !watchdog.poll() {
            tracing::error!("control loop stalled; withholding watchdog pings");
        }
        let snap = telemetry.latest();
        let now = (snap.mode, snap.reason, snap.gait);
        if last != Some(now) {
            tracing::info!(mode = ?snap.mode, reason = ?snap.reason, gait = snap.gait.name(), t_s = snap.t_s, "state");
            last = Some(now);
        }
    }
}
