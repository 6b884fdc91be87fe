//! `snake-emu`: every module of a snake as its own UDP endpoint, with a joint-space
//! model (default) or, with `--world`, the rigid-body physics plant behind them. See
//! `docs/emulator.md`.

use std::net::IpAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Context;
use clap::Parser;
use snaked::emu::Plant;
use snaked::emu::faults::{FaultConfig, Silence};
use snaked::emu::model_file::ModelFile;
use snaked::emu::module::ModuleConfig;
use snaked::emu::plant::JointSpacePlant;
use snaked::emu::server::{Mode, Server, ServerConfig};
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::scenario::WorldScenario;
use tracing::{info, warn};

/// UDP emulator of a modular series-elastic snake robot (protocol v2).
#[derive(Debug, Parser)]
#[command(name = "snake-emu", version)]
struct Args {
    /// Number of modules.
    #[arg(long, default_value_t = 18)]
    modules: usize,
    /// Address every module binds.
    #[arg(long, default_value = "127.0.0.1")]
    bind: IpAddr,
    /// Module i listens on base-port + i (0: the OS picks each port; they are logged).
    #[arg(long, default_value_t = 7000)]
    base_port: u16,
    /// Serve every module from one endpoint on base-port (units 0..n), with the frames
    /// of a cycle bundled into one datagram each way, like a tether hub.
    #[arg(long)]
    gateway: bool,
    /// The robot's network key (64 hex digits, not readable by every user); without
    /// it the network is open (docs/protocol.md §4).
    #[arg(long, value_name = "FILE")]
    network_key_file: Option<PathBuf>,
    /// realtime: 1 kHz physics on the wall clock; lockstep: one step per command round.
    #[arg(long, value_enum, default_value_t = Mode::Realtime)]
    mode: Mode,
    /// Lockstep: step anyway after this long without a complete command round, s.
    #[arg(long, default_value_t = 1.0)]
    lockstep_timeout: f64,
    /// Module family reported in announcements.
    #[arg(long, default_value = "SEA")]
    family: String,
    /// Loss of feedback sent and commands received, percent.
    #[arg(long, default_value_t = 0.0)]
    loss: f64,
    /// Extra feedback latency, ms (real-time mode only).
    #[arg(long, default_value_t = 0.0)]
    delay_ms: f64,
    /// Silence module K (0-based) from T s, for D s or for good: K@T[+D]. Repeatable.
    #[arg(long, value_name = "K@T[+D]")]
    silence: Vec<Silence>,
    /// Model file (TOML): servo and noise parameters, the first joint's plane, and for
    /// the joint-space plant scripted torques and obstacles (`--scenario` is its old name).
    #[arg(long, value_name = "FILE.toml", alias = "scenario")]
    model: Option<PathBuf>,
    /// Write the ground truth (one CSV row per physics step) to this file.
    #[arg(long, value_name = "FILE.csv")]
    record: Option<PathBuf>,
    /// Use the rigid-body physics plant in this world scenario (docs/scenarios.md, e.g.
    /// scenarios/peg-board-40.toml). The model file's first plane, servo and noise
    /// parameters still apply; its scripted torques and obstacles do not.
    #[arg(long, value_name = "FILE.toml")]
    world: Option<PathBuf>,
    /// Which start of the world scenario's `[start.random]` to use (obstacles stay).
    #[arg(long, default_value_t = 0)]
    world_trial: u64,
    /// Physics plant: write every link's pose and the contacts per step to this CSV.
    #[arg(long, value_name = "FILE.csv")]
    record_poses: Option<PathBuf>,
    /// Seed of the sensor noise and the faults.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stop after this much simulated time, s.
    #[arg(long)]
    duration: Option<f64>,
}

fn main() -> anyhow::Result<()> {
    snaked::daemon::logging::init("info");
    let args = Args::parse();

    let model = match &args.model {
        Some(path) => ModelFile::load(path)?,
        None => ModelFile::default(),
    };
    let plant: Box<dyn Plant> = match &args.world {
        Some(path) => {
            let spec = WorldScenario::load(path)?.generate_trial(args.modules, args.world_trial)?;
            let config = PhysicsConfig {
                modules: args.modules,
                first_plane: model.first_plane,
                servo: model.servo,
                noise: model.noise,
                seed: args.seed,
                temperature_c: model.temperature_c,
                voltage_v: model.voltage_v,
                ..PhysicsConfig::default()
            };
            Box::new(PhysicsPlant::new(&spec, config).context("invalid physics plant")?)
        }
        None => Box::new(
            JointSpacePlant::new(model.plant_config(args.modules, args.seed))
                .context("invalid plant configuration")?,
        ),
    };
    if args.record_poses.is_some() && args.world.is_none() {
        warn!("--record-poses without --world: the joint-space plant has no bodies to record");
    }
    if args.mode == Mode::Lockstep && args.delay_ms > 0.0 {
        warn!("--delay-ms has no effect in lockstep mode");
    }
    let network_key = match &args.network_key_file {
        Some(path) => snaked::protocol::Key::load(path)
            .with_context(|| format!("--network-key-file {}", path.display()))?,
        None => snaked::protocol::Key::OPEN,
    };
    let config = ServerConfig {
        bind_ip: args.bind,
        base_port: args.base_port,
        gateway: args.gateway,
        mode: args.mode,
        lockstep_timeout_s: args.lockstep_timeout,
        family: args.family.clone(),
        module: ModuleConfig {
            network_key,
            ..ModuleConfig::default()
        },
        faults: FaultConfig {
            loss_pct: args.loss,
            delay_s: args.delay_ms * 1e-3,
            silences: args.silence.clone(),
            // Decorrelated from the noise seed.
            seed: args.seed ^ 0x5EED_FA17,
            ..FaultConfig::default()
        },
        record: args.record.clone(),
        record_poses: args.record_poses.clone(),
        duration_s: args.duration,
        ..ServerConfig::default()
    };
    let mut server = Server::new(config, plant).context("cannot start the emulator")?;
    let addrs = server.local_addrs()?;
    info!(
        modules = args.modules,
        first = %addrs[0],
        last = %addrs[addrs.len() - 1],
        mode = ?args.mode,
        gateway = args.gateway,
        keyed = !network_key.is_open(),
        "snake-emu serving"
    );

    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .context("cannot install the SIGINT/SIGTERM handler")?;

    let counters = server.run(&stop)?;
    info!(
        sim_time_s = server.time_s(),
        counters = %serde_json::to_string(&counters)?,
        "snake-emu stopped"
    );
    if let Some(path) = &args.record {
        info!(path = %path.display(), "ground truth written");
    }
    Ok(())
}
