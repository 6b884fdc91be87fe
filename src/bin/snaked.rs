//! snaked: the control daemon. `snaked --emulated` runs it against an in-process
//! emulated snake; otherwise it discovers the modules on the network.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use snaked::daemon::{self, Overrides, config::Config, config::Pacing, config::StartMode};

#[derive(Parser, Debug)]
#[command(version, about = "Real-time control daemon for modular snake robots")]
struct Args {
    /// Configuration file (TOML). Without it, the documented defaults apply.
    #[arg(short, long, value_name = "PATH")]
    config: Option<PathBuf>,
    /// Drive an in-process emulated snake instead of modules on the network.
    #[arg(long)]
    emulated: bool,
    /// With --emulated: a world scenario for the rigid-body physics plant (overrides
    /// emulator.world), e.g. scenarios/flat.toml.
    #[arg(long, value_name = "FILE.toml", requires = "emulated")]
    world: Option<PathBuf>,
    /// Control socket path (overrides control.socket).
    #[arg(long, value_name = "PATH")]
    socket: Option<PathBuf>,
    /// Also listen on this TCP port of 127.0.0.1 (overrides control.tcp_port).
    #[arg(long, value_name = "PORT")]
    tcp_port: Option<u16>,
    /// What to do once feedback is healthy (overrides gait.start; --emulated defaults to run).
    #[arg(long, value_enum)]
    start: Option<StartArg>,
    /// Loop pacing (overrides loop.pacing).
    #[arg(long, value_enum)]
    pacing: Option<PacingArg>,
    /// Record every cycle to this MCAP file (overrides record.path; `{time}` becomes
    /// the start time). It must not exist yet.
    #[arg(long, value_name = "FILE.mcap")]
    record: Option<PathBuf>,
    /// Serve the live view over the Foxglove WebSocket protocol (foxglove.enabled;
    /// ws://127.0.0.1:8765 unless configured).
    #[arg(long)]
    foxglove: bool,
    /// Validate the configuration, print it, and exit.
    #[arg(long)]
    check_config: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum StartArg {
    Run,
    Hold,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PacingArg {
    Realtime,
    Lockstep,
}

fn main() -> ExitCode {
    daemon::logging::init("info");
    let args = Args::parse();
    let mut cfg = match &args.config {
        Some(path) => match Config::load(path) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("snaked: bad configuration: {e}");
                return ExitCode::from(2);
            }
        },
        None => Config::default(),
    };
    let overrides = Overrides {
        emulated: args.emulated,
        world: args.world.clone(),
        socket: args.socket.clone(),
        tcp_port: args.tcp_port,
        start: args.start.map(|s| match s {
            StartArg::Run => StartMode::Run,
            StartArg::Hold => StartMode::Hold,
        }),
        pacing: args.pacing.map(|p| match p {
            PacingArg::Realtime => Pacing::Realtime,
            PacingArg::Lockstep => Pacing::Lockstep,
        }),
        record: args.record.clone(),
        foxglove: args.foxglove,
    };
    daemon::apply_overrides(&mut cfg, &overrides);
    // The command line may change what the file said (a TCP port, a world): check the
    // result, so that --check-config refuses what the daemon would.
    let label = args.config.as_deref().unwrap_or(Path::new("the defaults"));
    if let Err(e) = cfg.validate(label) {
        eprintln!("snaked: bad configuration (with the command line's overrides): {e}");
        return ExitCode::from(2);
    }
    if args.check_config {
        println!("{cfg:#?}");
        return ExitCode::SUCCESS;
    }
    match daemon::run(cfg, args.emulated) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("{e:#}");
            eprintln!("snaked: {e:#}");
            ExitCode::FAILURE
        }
    }
}
