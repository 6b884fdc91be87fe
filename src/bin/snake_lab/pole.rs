//! `snake-lab pole`: the pole-climbing experiment (issue 12, SPEC §6, docs/lab.md).

use std::path::PathBuf;

use snaked::emu::servo::PositionLoop;
use snaked::gait::GaitKind;
use snaked::lab::LabError;
use snaked::lab::pole::{self, PoleClimb, poles};
use snaked::lab::runner::Experiment;
use snaked::lab::trial::TrialConfig;

/// Options. The defaults: the named set of six poles, 3 starts each.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Controllers to compare, comma-separated (default: fixed, central, windowed,
    /// windowed_adaptive).
    #[arg(long, value_delimiter = ',')]
    controllers: Vec<String>,
    /// A controller with its own configuration, LABEL=JSON (repeatable), over
    /// windowed_adaptive unless the JSON names another preset, e.g.
    /// 'soft={"gains":{"stiffness":16}}'.
    #[arg(long = "variant", value_name = "LABEL=JSON")]
    variants: Vec<String>,
    /// Poles of the named set to run, comma-separated (default: all; `none` for only
    /// seeded ones): step-up, step-down, taper-up, taper-down, waist, bulge.
    #[arg(long, value_delimiter = ',')]
    poles: Vec<String>,
    /// Seeded poles: seeds seed-base .. seed-base + N - 1.
    #[arg(long, default_value_t = 0)]
    seeded: usize,
    #[arg(long, default_value_t = 100)]
    seed_base: u64,
    /// Random starts per pole (heading, roll, gap to the pole).
    #[arg(long, default_value_t = 3)]
    starts: usize,
    /// Trials per start, differing only in their sensor-noise seed.
    #[arg(long, default_value_t = 1)]
    repeats: usize,
    /// Seconds in the rolling gait before the helix is selected (0.2: the body still
    /// lies straight; from about 1 s the half-formed rolling arc carries its middle off
    /// the pole as it straightens: docs/lab.md).
    #[arg(long, default_value_t = 0.2)]
    lead_in: f64,
    /// Skin–pole friction.
    #[arg(long, default_value_t = 0.6)]
    mu: f64,
    /// Time limit of a trial, simulated s.
    #[arg(long, default_value_t = 150.0)]
    seconds: f64,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    threads: Option<usize>,
    /// Output directory.
    #[arg(long, default_value = "lab-out/pole")]
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
    let threads = super::threads(args.threads)?;
    let named = poles::named_set();
    let mut designs = Vec::new();
    if args.poles.is_empty() {
        designs.extend(named.iter().cloned());
    } else if args.poles != ["none"] {
        for p in &args.poles {
            let d = named.iter().find(|d| d.name == p.trim()).ok_or_else(|| {
                let known: Vec<_> = named.iter().map(|d| d.name.as_str()).collect();
                LabError::BadValue(format!(
                    "no pole {p:?} in the named set; known: {}",
                    known.join(", ")
                ))
            })?;
            designs.push(d.clone());
        }
    }
    designs.extend((0..args.seeded as u64).map(|k| poles::seeded(args.seed_base + k)));
    if !(args.mu.is_finite() && args.mu > 0.0 && args.mu <= 2.0) {
        return Err(LabError::BadValue(format!(
            "--mu must be in (0, 2], not {}",
            args.mu
        )));
    }
    if !(args.lead_in.is_finite() && (0.0..=60.0).contains(&args.lead_in)) {
        return Err(LabError::BadValue(format!(
            "--lead-in must be 0-60 s, not {}",
            args.lead_in
        )));
    }
    let module = PoleClimb {
        designs,
        mu: args.mu,
        lead_in_s: args.lead_in,
        ..PoleClimb::default()
    };
    let layouts = module.layouts()?;
    let gait = GaitKind::RollingHelix;
    let controllers = super::module_controllers(
        &module,
        &args.controllers,
        &args.variants,
        "windowed_adaptive",
    )?;
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
    let written = pole::write_report(&args.out, &module, &results, &ctx)?;
    super::finish(&written, &args.out, args.quiet);
    Ok(())
}
