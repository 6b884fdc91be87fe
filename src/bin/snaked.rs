//! snaked: the control daemon. `snaked --emulated` runs it against an in-process
//! emulated snake; otherwise it discovers the modules on the network.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use snaked::daemon::{self, Overrides, config::Config, config::Pacing, config::StartMode};
use snaked::record;

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
    /// Also drive and tune the robot from Foxglove: services, the Teleop and Parameters
    /// panels (foxglove.operate; implies --foxglove; off loopback it needs a token file).
    #[arg(long)]
    operate: bool,
    /// Look up HEBI modules on hebi.interfaces for hebi.lookup_timeout_s, print what
    /// answers (family, name, MAC) and exit: the names for hebi.names.
    #[arg(long)]
    list_modules: bool,
    /// Validate the configuration, print it, and exit.
    #[arg(long)]
    check_config: bool,
    /// Make a finished file of a recording that a crash, a power loss or a full disk left
    /// unfinished (every complete chunk, the metadata), write it to OUT.mcap (default:
    /// NAME.recovered.mcap beside it; never overwritten), and exit.
    #[arg(long, num_args = 1..=2, value_names = ["FILE.mcap", "OUT.mcap"])]
    recover: Option<Vec<PathBuf>>,
    /// Print the robot's model as a URDF for this many modules (the configuration's
    /// body: module length, first joint's plane; module names as discovery gives them)
    /// and exit. The live view serves the same as an asset.
    #[arg(long, value_name = "MODULES")]
    urdf: Option<usize>,
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
    if let Some(paths) = &args.recover {
        return recover(&paths[0], paths.get(1));
    }
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
        operate: args.operate,
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
    if args.list_modules {
        return match daemon::bus_setup::list_hebi_modules(&cfg.hebi) {
            Ok(text) => {
                print!("{text}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("snaked: {e:#}");
                ExitCode::FAILURE
            }
        };
    }
    if let Some(n) = args.urdf {
        if !(1..=64).contains(&n) {
            eprintln!("snaked: --urdf takes 1 to 64 modules, not {n}");
            return ExitCode::from(2);
        }
        let layout = snaked::gait::BodyLayout::alternating(
            n,
            cfg.body.first_joint_plane,
            cfg.body.module_length_m,
        );
        let names: Vec<String> = (1..=n).map(|k| format!("module-{k:02}")).collect();
        print!("{}", snaked::record::urdf::urdf(&layout, &names));
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

/// `--recover FILE [OUT]`: what the file held and what was written; exit 1 on failure.
fn recover(input: &Path, output: Option<&PathBuf>) -> ExitCode {
    let output = output
        .cloned()
        .unwrap_or_else(|| record::recovered_path(input));
    match record::recover(input, &output) {
        Ok(r) if r.already_finished => {
            println!(
                "{}: finished (it ends with its footer): nothing to recover",
                input.display()
            );
            ExitCode::SUCCESS
        }
        Ok(r) => {
            let mut said = format!(
                "{}: not finished: {} complete chunks, {} messages over {:.3} s",
                input.display(),
                r.chunks,
                r.messages,
                r.span_s()
            );
            if r.lost_bytes > 0 {
                let why = r
                    .stopped
                    .as_deref()
                    .unwrap_or("a summary section cut short");
                said += &format!("; the {} bytes after them dropped ({why})", r.lost_bytes);
            }
            println!("{said}");
            let topics: Vec<String> = r
                .per_topic
                .iter()
                .map(|(t, n)| format!("{t} {n}"))
                .collect();
            println!(
                "wrote {}: finished (summary and index); {}",
                output.display(),
                topics.join(", ")
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("snaked: {e}");
            ExitCode::FAILURE
        }
    }
}
