//! `snake-lab`: controller comparisons in simulation. `snake-lab pegboard` runs the
//! peg-board experiment of SPEC §5 and writes `results.csv`, `summary.md` and PNG plots.
//! See `docs/lab.md`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use snaked::lab::displacement::Terrain;

#[path = "snake_lab/displacement.rs"]
mod displacement;
#[path = "snake_lab/pole.rs"]
mod pole;
#[path = "snake_lab/sidewinding.rs"]
mod sidewinding;
use snaked::emu::servo::PositionLoop;
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::GaitKind;
use snaked::lab::PEGBOARD_CONTROLLERS;
use snaked::lab::board::{Layout, PEG_BOARD_TOML};
use snaked::lab::controllers::LabController;
use snaked::lab::pegboard;
use snaked::lab::report::SummaryContext;
use snaked::lab::runner::{Experiment, RunOptions, run};
use snaked::lab::trial::TrialConfig;
use snaked::lab::{LabError, write_report};

/// Controller comparisons for the snake robot in simulation (docs/lab.md).
#[derive(Debug, Parser)]
#[command(name = "snake-lab", version)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// List the peg-board experiment's controllers, in report order.
    List,
    /// The slithering peg-board experiment (SPEC §5).
    Pegboard(Pegboard),
    /// Directional compliance on the reference's planar peg array (SPEC §8).
    PegArray(displacement::Args),
    /// Directional compliance in 3-D over the reference's rock pile (SPEC §8).
    RockPile(displacement::Args),
    /// Anti-compliant sidewinding through an irregular peg array (SPEC §7).
    Sidewinding(sidewinding::Args),
    /// The rolling helix with radius compliance up poles whose diameter changes (SPEC §6).
    Pole(pole::Args),
}

#[derive(Debug, clap::Args)]
struct Pegboard {
    /// Controllers to compare, comma-separated (default: all, see `snake-lab list`).
    #[arg(long, value_delimiter = ',')]
    controllers: Vec<String>,
    /// A controller with its own configuration, LABEL=JSON (repeatable), compared after
    /// the named ones. JSON is a selection as `controller.set` takes it
    /// ({"controller", "preset", "config"}), over the full controller a_ws_omega unless
    /// it names another; other keys override the configuration (docs/lab.md), e.g.
    /// 'stiff={"amplitude":{"gains":{"stiffness":8}}}'.
    #[arg(long = "variant", value_name = "LABEL=JSON")]
    variants: Vec<String>,
    /// Seeded random layouts of the board: seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 20)]
    layouts: usize,
    /// Random starts per layout.
    #[arg(long, default_value_t = 3)]
    starts: usize,
    /// Master seed of the first seeded layout.
    #[arg(long, default_value_t = 1000)]
    seed_base: u64,
    /// World scenario the seeded layouts come from (default: the built-in
    /// scenarios/peg-board-40-inside.toml, starts among the pegs as in the thesis;
    /// scenarios/peg-board-40.toml starts at the board's edge).
    #[arg(long, value_name = "FILE")]
    board: Option<PathBuf>,
    /// An explicit layout: a world scenario file, run as is (repeatable).
    #[arg(long = "scenario", value_name = "FILE")]
    scenarios: Vec<PathBuf>,
    /// Time limit of a trial, simulated s.
    #[arg(long, default_value_t = 120.0)]
    seconds: f64,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    threads: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "lab-out/pegboard")]
    out: PathBuf,
    /// Record every trial as MCAP into this directory (created if missing):
    /// CONTROLLER-LAYOUT-sSTART.mcap, replayable in Foxglove (docs/recording.md).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// No progress bar, no list of written files.
    #[arg(long)]
    quiet: bool,
    /// Run controllers that calibrate (directional compliance) uncalibrated, instead
    /// of calibrating them on open ground first.
    #[arg(long)]
    no_calibrate: bool,
    /// The emulated servos' position loop: `profiled` (the default) or `speed-clamped`
    /// (the loop before 2026-12-02, unstable when links are held in the air; the earlier
    /// lab results were measured with it: docs/emulator.md, "The servo loop").
    #[arg(long, value_enum, default_value = "profiled")]
    servo_loop: PositionLoop,
    #[command(flatten)]
    nominal: crate::NominalArg,
}

/// `--nominal`, shared by every experiment.
#[derive(Debug, clap::Args)]
pub(crate) struct NominalArg {
    /// The experiment's gait's nominal parameters, a partial set as the socket's
    /// `params.set` takes it, checked as the daemon checks it (default: the daemon's,
    /// docs/gaits.md), e.g. '{"amplitude_lat_rad":1.1,"spatial_freq_rad":6.28}'.
    #[arg(long = "nominal", value_name = "JSON")]
    json: Option<String>,
}

impl NominalArg {
    /// The gait table the trials run on.
    pub(crate) fn gaits(&self, gait: GaitKind) -> Result<snaked::gait::GaitTable, LabError> {
        snaked::lab::trial::nominal_gaits(gait, self.json.as_deref())
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.cmd {
        Cmd::List => {
            for name in PEGBOARD_CONTROLLERS {
                println!("{name}");
            }
            Ok(())
        }
        Cmd::Pegboard(args) => pegboard(args),
        Cmd::PegArray(args) => displacement::run(Terrain::PegArray, args),
        Cmd::RockPile(args) => displacement::run(Terrain::RockPile, args),
        Cmd::Sidewinding(args) => sidewinding::run(args),
        Cmd::Pole(args) => pole::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprint!("snake-lab: {e}");
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                eprint!(": {s}");
                source = s.source();
            }
            eprintln!();
            ExitCode::from(if e.is_bad_input() { 2 } else { 1 })
        }
    }
}

fn pegboard(args: Pegboard) -> Result<(), LabError> {
    let threads = threads(args.threads)?;
    let base = match &args.board {
        Some(path) => WorldScenario::load(path)?,
        None => WorldScenario::parse(PEG_BOARD_TOML)?,
    };
    let mut layouts: Vec<Layout> = (0..args.layouts as u64)
        .map(|k| Layout::seeded(&base, args.seed_base.wrapping_add(k)))
        .collect();
    for path in &args.scenarios {
        layouts.push(Layout::from_file(path)?);
    }
    let names: Vec<String> = if args.controllers.is_empty() {
        PEGBOARD_CONTROLLERS.iter().map(|s| s.to_string()).collect()
    } else {
        args.controllers
            .iter()
            .map(|s| s.trim().to_owned())
            .collect()
    };
    let mut controllers = names
        .iter()
        .map(|n| LabController::named(GaitKind::Slithering, n))
        .collect::<Result<Vec<_>, _>>()?;
    for spec in &args.variants {
        controllers.push(LabController::variant(GaitKind::Slithering, spec)?);
    }
    let trial = TrialConfig {
        limit_s: args.seconds,
        servo_loop: args.servo_loop,
        gaits: args.nominal.gaits(GaitKind::Slithering)?,
        ..TrialConfig::default()
    };
    let calibrations = if args.no_calibrate {
        Vec::new()
    } else {
        calibrate_all(&mut controllers, &layouts, &trial, args.quiet)?
    };
    let exp = Experiment {
        controllers,
        layouts,
        starts: args.starts,
        repeats: 1,
        trial,
        record_dir: args.record.clone(),
    };
    let results = run_experiment(&pegboard::Pegboard, &exp, threads, args.quiet)?;
    let ctx = context(&exp, calibrations);
    let written = write_report(&args.out, &results, &ctx)?;
    finish(&written, &args.out, args.quiet);
    Ok(())
}

/// Runs every trial of `exp` (creating its recording directory first).
pub(crate) fn run_experiment<E: snaked::lab::experiment::ExperimentModule>(
    module: &E,
    exp: &Experiment,
    threads: usize,
    quiet: bool,
) -> Result<Vec<snaked::lab::runner::TrialResult<E>>, LabError> {
    if let Some(dir) = &exp.record_dir {
        std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let opts = RunOptions {
        threads,
        progress: !quiet,
    };
    run(module, exp, opts)
}

/// What the summary says of how `exp` was run.
pub(crate) fn context(exp: &Experiment, calibrations: Vec<(String, String)>) -> SummaryContext {
    SummaryContext {
        command: command_line(),
        layouts: exp.layouts.iter().map(|l| l.name.clone()).collect(),
        starts: exp.starts,
        repeats: exp.repeats,
        limit_s: exp.trial.limit_s,
        plots: Vec::new(),
        calibrations,
    }
}

/// Lists the files written (unless quiet) and prints the summary.
pub(crate) fn finish(written: &[PathBuf], out: &std::path::Path, quiet: bool) {
    if !quiet {
        for p in written {
            eprintln!("wrote {}", p.display());
        }
    }
    print!(
        "{}",
        std::fs::read_to_string(out.join("summary.md")).unwrap_or_default()
    );
}

/// The compared controllers of `module`: the names given (its own list when none),
/// then each `LABEL=JSON` variant over `variant_base` unless it names another.
pub(crate) fn module_controllers<E: snaked::lab::experiment::ExperimentModule>(
    module: &E,
    given: &[String],
    variants: &[String],
    variant_base: &str,
) -> Result<Vec<LabController>, LabError> {
    let gait = module.gait();
    let mut controllers = if given.is_empty() {
        module
            .controllers()
            .iter()
            .map(|n| LabController::named(gait, n))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        given
            .iter()
            .map(|n| LabController::named(gait, n.trim()))
            .collect::<Result<Vec<_>, _>>()?
    };
    for spec in variants {
        controllers.push(LabController::variant_on(gait, spec, variant_base)?);
    }
    Ok(controllers)
}

/// `--threads`, or the available parallelism.
fn threads(given: Option<usize>) -> Result<usize, LabError> {
    match given {
        Some(0) => Err(LabError::BadValue("--threads must be at least 1".into())),
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, usize::from)),
    }
}

/// Calibrates every controller that calibrates on the first layout's open ground and
/// replaces it by its calibrated self; returns what each measured.
fn calibrate_all(
    controllers: &mut [LabController],
    layouts: &[Layout],
    trial: &TrialConfig,
    quiet: bool,
) -> Result<Vec<(String, String)>, LabError> {
    let Some(first) = layouts.first() else {
        return Ok(Vec::new());
    };
    let ground = first.scenario.generate_trial(trial.modules, 0)?;
    let mut out = Vec::new();
    for c in controllers.iter_mut() {
        if let Some(done) = snaked::lab::calibration::calibrate(c, &ground, trial)? {
            if !quiet {
                eprintln!(
                    "calibrated {} on open ground over {:.1} s: {}",
                    c.label, done.seconds, done.offsets
                );
            }
            out.push((c.label.clone(), done.offsets.to_string()));
            *c = done.controller;
        }
    }
    Ok(out)
}

/// The command line as typed, each argument shell-quoted where needed.
pub(crate) fn command_line() -> String {
    std::iter::once("snake-lab".to_owned())
        .chain(std::env::args().skip(1).map(|a| {
            if !a.is_empty()
                && a.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./,=:+@".contains(c))
            {
                a
            } else {
                format!("'{}'", a.replace('\'', r"'\''"))
            }
        }))
        .collect::<Vec<_>>()
        .join(" ")
}
