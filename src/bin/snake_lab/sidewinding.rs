//! `snake-lab sidewinding`: the thesis's sidewinding experiment (SPEC §7, docs/lab.md).

use std::path::PathBuf;

use snaked::emu::servo::PositionLoop;
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::GaitKind;
use snaked::lab::LabError;
use snaked::lab::board::Layout;
use snaked::lab::runner::Experiment;
use snaked::lab::sidewinding::{self, SIDEWINDING_PEGS_TOML, SidewindingPegs};
use snaked::lab::trial::TrialConfig;

/// Options. The defaults are the thesis's protocol: one array, 7 starts, 3 trials per
/// start; `--layouts 20 --starts 2` adds the seeded arrays.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Controllers to compare, comma-separated (default: ac_sfc, ac, sfc, sw_open_loop).
    #[arg(long, value_delimiter = ',')]
    controllers: Vec<String>,
    /// A controller with its own configuration, LABEL=JSON (repeatable), over ac_sfc
    /// unless the JSON names another preset, e.g. 'wide={"heading":{"deadband_rad":0.5}}'.
    #[arg(long = "variant", value_name = "LABEL=JSON")]
    variants: Vec<String>,
    /// Seeded arrays: the scenario with master seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 1)]
    layouts: usize,
    /// Random starts per array.
    #[arg(long, default_value_t = 7)]
    starts: usize,
    /// Trials per start, differing only in their sensor-noise seed.
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Master seed of the first array (default: the scenario's own).
    #[arg(long)]
    seed_base: Option<u64>,
    /// World scenario with a `[[peg_fence]]` (default: the built-in
    /// scenarios/sidewinding-pegs.toml).
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Time limit of a trial, simulated s. The thesis ran a trial until the snake was
    /// through or had left the board; 300 s lets the slow escapes finish (at 90 s most
    /// of the controllers' time-outs got through later: docs/measurements.md).
    #[arg(long, default_value_t = 300.0)]
    seconds: f64,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    threads: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "lab-out/sidewinding")]
    out: PathBuf,
    /// Record every trial as MCAP into this directory (created if missing).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// No progress bar, no list of written files.
    #[arg(long)]
    quiet: bool,
    /// The emulated servos' position loop.
    #[arg(long, value_enum, default_value = "profiled")]
    servo_loop: PositionLoop,
    #[command(flatten)]
    nominal: crate::NominalArg,
}

pub fn run(args: Args) -> Result<(), LabError> {
    let module = SidewindingPegs;
    let threads = super::threads(args.threads)?;
    let base = match &args.scenario {
        Some(path) => WorldScenario::load(path)?,
        None => WorldScenario::parse(SIDEWINDING_PEGS_TOML)?,
    };
    if base.peg_fences.is_empty() {
        return Err(LabError::BadValue(
            "the scenario has no [[peg_fence]]: the experiment needs a peg array".into(),
        ));
    }
    let seed_base = args.seed_base.unwrap_or(base.seed);
    let layouts: Vec<Layout> = (0..args.layouts as u64)
        .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
        .collect();
    let gait = GaitKind::Sidewinding;
    let controllers =
        super::module_controllers(&module, &args.controllers, &args.variants, "ac_sfc")?;
    let trial = TrialConfig {
        limit_s: args.seconds,
        servo_loop: args.servo_loop,
        gaits: args.nominal.gaits(gait)?,
        ..TrialConfig::default()
    };
    let exp = Experiment {
        controllers,
        layouts,
        starts: args.starts,
        repeats: args.repeats,
        trial,
        record_dir: args.record.clone(),
    };
    let results = super::run_experiment(&module, &exp, threads, args.quiet)?;
    let ctx = super::context(&exp, Vec::new());
    let written = sidewinding::write_report(&args.out, &results, &ctx)?;
    super::finish(&written, &args.out, args.quiet);
    Ok(())
}
