//! `snake-lab peg-array` and `snake-lab rock-pile`: the directional-compliance paper's
//! experiments (SPEC §8, docs/lab.md).

use std::path::PathBuf;

use snaked::emu::servo::PositionLoop;
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::GaitKind;
use snaked::lab::LabError;
use snaked::lab::board::Layout;
use snaked::lab::displacement::{self, Displacement, MODULES, Terrain};
use snaked::lab::experiment::ExperimentModule;
use snaked::lab::runner::Experiment;
use snaked::lab::trial::TrialConfig;

/// Options of both experiments. The defaults are the paper's protocol: one layout,
/// 5 random poses, 4 trials per pose, 2 minutes each.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Controllers to compare, comma-separated (default: NC, NDC, PDC and switching
    /// of the terrain's plane count).
    #[arg(long, value_delimiter = ',')]
    controllers: Vec<String>,
    /// A controller with its own configuration, LABEL=JSON (repeatable), over the
    /// terrain's switching controller unless the JSON names another, e.g.
    /// 'wide={"thresholds":{"low_rad_s":-1.0,"high_rad_s":1.0,"reference":"threshold"}}'.
    #[arg(long = "variant", value_name = "LABEL=JSON")]
    variants: Vec<String>,
    /// Seeded layouts: the scenario with master seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 1)]
    layouts: usize,
    /// Random poses (position and heading) per layout.
    #[arg(long, default_value_t = 5)]
    starts: usize,
    /// Trials per pose, differing only in their sensor-noise seed.
    #[arg(long, default_value_t = 4)]
    repeats: usize,
    /// Master seed of the first layout (default: the scenario's own).
    #[arg(long)]
    seed_base: Option<u64>,
    /// World scenario the layouts come from (default: the built-in
    /// scenarios/peg-array.toml or scenarios/rock-pile-3d.toml).
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Modules of the snake (the paper's robot has 16).
    #[arg(long, default_value_t = MODULES)]
    modules: usize,
    /// Time of a trial, simulated s.
    #[arg(long, default_value_t = 120.0)]
    seconds: f64,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    threads: Option<usize>,
    /// Output directory (default: lab-out/peg-array or lab-out/rock-pile).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Record every trial as MCAP into this directory (created if missing).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// Run uncalibrated (friction offset 0) instead of calibrating on open ground first.
    #[arg(long)]
    no_calibrate: bool,
    /// No progress bar, no list of written files.
    #[arg(long)]
    quiet: bool,
    /// The emulated servos' position loop: `profiled` (the default) or `speed-clamped`
    /// (the loop before 2026-12-02, unstable when links are held in the air; the earlier
    /// lab results were measured with it: docs/emulator.md, "The servo loop").
    #[arg(long, value_enum, default_value = "profiled")]
    servo_loop: PositionLoop,
    #[command(flatten)]
    nominal: crate::NominalArg,
}

pub fn run(terrain: Terrain, args: Args) -> Result<(), LabError> {
    let module = Displacement { terrain };
    let threads = super::threads(args.threads)?;
    let base = match &args.scenario {
        Some(path) => WorldScenario::load(path)?,
        None => WorldScenario::parse(module.scenario_toml())?,
    };
    // Checked before the calibrations, which take a while.
    if args.layouts == 0 {
        return Err(LabError::NoLayouts);
    }
    if args.starts == 0 {
        return Err(LabError::NoStarts);
    }
    if args.repeats == 0 {
        return Err(LabError::BadValue("--repeats must be at least 1".into()));
    }
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        return Err(LabError::BadValue(format!(
            "the time limit must be positive, not {} s",
            args.seconds
        )));
    }
    if !(2..=64).contains(&args.modules) {
        return Err(LabError::BadValue(format!(
            "--modules must be 2 ..= 64, not {}",
            args.modules
        )));
    }
    let seed_base = args.seed_base.unwrap_or(base.seed);
    let layouts: Vec<Layout> = (0..args.layouts as u64)
        .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
        .collect();
    let variant_base = match terrain {
        Terrain::PegArray => "dc_switching",
        Terrain::RockPile => "dc3d_switching",
    };
    let mut controllers =
        super::module_controllers(&module, &args.controllers, &args.variants, variant_base)?;
    let trial = TrialConfig {
        modules: args.modules,
        limit_s: args.seconds,
        servo_loop: args.servo_loop,
        gaits: args.nominal.gaits(GaitKind::Slithering)?,
        ..TrialConfig::default()
    };
    let calibrations = if args.no_calibrate {
        Vec::new()
    } else {
        super::calibrate_all(&mut controllers, &layouts, &trial, args.quiet)?
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
    let ctx = super::context(&exp, calibrations);
    let out = args
        .out
        .unwrap_or_else(|| PathBuf::from("lab-out").join(module.name()));
    let written = displacement::write_report(&module, &out, &results, &ctx)?;
    super::finish(&written, &out, args.quiet);
    Ok(())
}
