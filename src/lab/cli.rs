//! `snake-lab`'s command line for any experiment: the options every experiment has
//! ([`CommonArgs`], flattened beside the experiment's own), and [`Plugin`], which turns
//! an [`Experiment`] into a subcommand that runs it whole or as one shard, and merges
//! its shards. The binary only lists [`crate::lab::registry::EXPERIMENTS`].

use std::path::{Path, PathBuf};

use clap::parser::ValueSource;
use clap::{Args, FromArgMatches};

use super::LabError;
use super::compared::LabController;
use super::experiment::Experiment;
use super::layout::Layout;
use super::pose_source::SourceConfig;
use super::report::{SummaryContext, write_report};
use super::runner::{RunOptions, Setup, plan_fingerprint, run_share};
use super::shard::{self, Shard, ShardFile, ShardHead};
use super::trial::{TrialConfig, patch_nominal, patch_nominal_json};
use crate::emu::servo::PositionLoop;
use crate::gait::GaitKind;

/// The options of every experiment. `--starts`, `--repeats`, `--seconds` and `--out`
/// default to the experiment's own (shown by `--help`), the first three to a protocol
/// file's where the experiment has one (`lab::protocol`).
#[derive(Debug, Clone, clap::Args)]
pub struct CommonArgs {
    /// Controllers to compare, comma-separated (default: the experiment's, see
    /// `snake-lab list`).
    #[arg(long, value_delimiter = ',')]
    pub controllers: Vec<String>,
    /// A controller with its own configuration, LABEL=JSON (repeatable), compared after
    /// the named ones. JSON is a selection as `controller.set` takes it
    /// ({"controller", "preset", "config"}), over the experiment's base controller
    /// unless it names another; other keys override the configuration (docs/lab.md).
    #[arg(long = "variant", value_name = "LABEL=JSON")]
    pub variants: Vec<String>,
    /// Starts (poses) per layout (a protocol file's value, if it gives one, before the
    /// default).
    #[arg(long)]
    pub starts: Option<usize>,
    /// Trials per start, differing only in their sensor-noise seed (a protocol file's
    /// value, if it gives one, before the default).
    #[arg(long)]
    pub repeats: Option<usize>,
    /// Time limit of a trial, simulated s (a protocol file's value, if it gives one,
    /// before the default).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Worker threads (default: the available parallelism).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Record every trial as MCAP into this directory (created if missing):
    /// CONTROLLER-LAYOUT-sSTART.mcap, replayable in Foxglove (docs/recording.md).
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Run controllers that calibrate (directional compliance) uncalibrated, instead
    /// of calibrating them on open ground first.
    #[arg(long)]
    pub no_calibrate: bool,
    /// No progress bar, no list of written files.
    #[arg(long)]
    pub quiet: bool,
    /// Plot every trial (into trials/LAYOUT-sSTART-rREPEAT/ of the output), not only
    /// each controller's first.
    #[arg(long)]
    pub plot_all: bool,
    /// The emulated servos' position loop: `profiled` (the default) or `speed-clamped`
    /// (the earlier loop, to reproduce results measured with it: docs/emulator.md, "The
    /// servo loop").
    #[arg(long, value_enum, default_value = "profiled")]
    pub servo_loop: PositionLoop,
    /// The experiment's gait's nominal parameters, a partial set as the socket's
    /// `params.set` takes it, checked as the daemon checks it (default: the daemon's,
    /// docs/gaits.md, patched by the scenario's protocol if it has one; given, it
    /// patches those), e.g. '{"amplitude_lat_rad":1.1,"spatial_freq_rad":6.28}'.
    #[arg(long = "nominal", value_name = "JSON")]
    pub nominal: Option<String>,
    /// The gait `--nominal` patches, by name (default: the experiment's; crossing runs
    /// every gait, so e.g. `--nominal-gait sidewinding`).
    #[arg(long, value_name = "GAIT", requires = "nominal")]
    pub nominal_gait: Option<String>,
    /// A simulated outside position source fused into the pose estimate, its error
    /// reported (docs/estimation.md): `lab` (100 Hz, 2 mm, 15 ms), `degraded` (10 Hz,
    /// 2 cm, 100 ms, 10 % of the time occluded), or a JSON object of its fields over
    /// `lab`'s, e.g. '{"rate_hz":30,"latency_s":0.05,"occlusions_per_s":0.2,"occlusion_s":2}'
    /// (default: none).
    #[arg(long, value_name = "lab|degraded|JSON")]
    pub pose_source: Option<String>,
    /// Run only the K-th of N shares of the trials (1 <= K <= N) and write
    /// OUT/shard-K-of-N.cbor; `snake-lab merge` writes the report from all N.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
}

/// An experiment as `snake-lab` sees it, whatever its types.
pub trait Lab: Sync {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn controllers(&self) -> &'static [&'static str];
    /// The gait its controllers run (a controller name resolves in it first).
    fn gait(&self) -> GaitKind;
    /// Whether it compares gaits (any gait's controllers and the navigator).
    fn any_gait(&self) -> bool;
    /// The controller a `--variant` overrides unless its JSON names another.
    fn variant_base(&self) -> &'static str;
    /// Its subcommand: the common options and its own, with its defaults.
    fn command(&self) -> clap::Command;
    /// Runs it as `matches` (of [`Lab::command`]) ask; `command` is the command line as
    /// typed, for the summary.
    fn run(&self, matches: &clap::ArgMatches, command: &str) -> Result<(), LabError>;
    /// Merges its complete set of shard files into one report in `out`.
    fn merge(&self, files: &[PathBuf], out: &Path, quiet: bool) -> Result<(), LabError>;
}

/// An [`Experiment`] as a [`Lab`]: the value is the experiment before its options
/// configure it.
pub struct Plugin<E>(pub E);

impl<E: Experiment> Lab for Plugin<E> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn summary(&self) -> &'static str {
        self.0.summary()
    }
    fn controllers(&self) -> &'static [&'static str] {
        self.0.controllers()
    }
    fn gait(&self) -> GaitKind {
        self.0.gait()
    }
    fn any_gait(&self) -> bool {
        self.0.any_gait()
    }
    fn variant_base(&self) -> &'static str {
        self.0.variant_base()
    }

    fn command(&self) -> clap::Command {
        let d = self.0.defaults();
        // clap keeps defaults as 'static strings; a handful per process.
        let leak = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
        let cmd = clap::Command::new(self.0.name()).about(self.0.summary());
        // The experiment's summary, not the option structs' doc comments.
        let cmd = E::Args::augment_args(CommonArgs::augment_args(cmd))
            .about(self.0.summary())
            .long_about(None);
        cmd.mut_arg("starts", |a| a.default_value(leak(d.starts.to_string())))
            .mut_arg("repeats", |a| a.default_value(leak(d.repeats.to_string())))
            .mut_arg("seconds", |a| a.default_value(leak(d.seconds.to_string())))
            .mut_arg("out", |a| {
                a.default_value(leak(format!("lab-out/{}", self.0.name())))
            })
    }

    fn run(&self, matches: &clap::ArgMatches, command: &str) -> Result<(), LabError> {
        let bad = |e: clap::Error| LabError::BadValue(e.to_string());
        let common = CommonArgs::from_arg_matches(matches).map_err(bad)?;
        let own = E::Args::from_arg_matches(matches).map_err(bad)?;
        let d = self.0.defaults();
        let mut trial = TrialConfig {
            limit_s: common.seconds.unwrap_or(d.seconds),
            servo_loop: common.servo_loop,
            pose_source: common.pose_source.as_deref().map(pose_source).transpose()?,
            ..TrialConfig::default()
        };
        let (module, layouts) = self.0.configure(&own, &mut trial)?;
        // What the command line gives, else the scenario's protocol, else the defaults.
        let typed = |id: &str| matches.value_source(id) == Some(ValueSource::CommandLine);
        let protocol = module.protocol().map(|p| p.spec).unwrap_or_default();
        let count = |id: &str, given: Option<usize>, file: Option<usize>, default: usize| {
            match typed(id) {
                true => given,
                false => file.or(given),
            }
            .unwrap_or(default)
        };
        if !typed("seconds")
            && let Some(s) = protocol.seconds
        {
            trial.limit_s = s;
        }
        let nominal_gait = match common.nominal_gait.as_deref() {
            None => module.gait(),
            Some(name) => GaitKind::from_name(name).ok_or_else(|| {
                LabError::BadValue(format!("--nominal-gait {name:?}: not a gait"))
            })?,
        };
        // The daemon's nominal (TrialConfig's), the protocol's patch, then --nominal.
        if let Some(p) = module.protocol()
            && let Some(patch) = &p.spec.nominal
        {
            let what = format!("{}: [protocol] nominal", p.source);
            patch_nominal(&mut trial.gaits, module.gait(), patch, &what)?;
        }
        if let Some(json) = common.nominal.as_deref() {
            patch_nominal_json(&mut trial.gaits, nominal_gait, json)?;
        }
        let module = module.with_trial(&trial);
        let starts = count("starts", common.starts, protocol.starts, d.starts);
        let repeats = count("repeats", common.repeats, protocol.repeats, d.repeats);
        check_counts(&layouts, starts, repeats, trial.limit_s)?;
        let threads = threads(common.threads)?;
        let mut controllers = compared(&module, &common.controllers, &common.variants)?;
        let calibrations = if common.no_calibrate {
            Vec::new()
        } else {
            calibrate_all(&mut controllers, &layouts, &trial, common.quiet)?
        };
        if let Some(dir) = &common.record {
            std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
                path: dir.clone(),
                source,
            })?;
        }
        let setup = Setup {
            controllers,
            layouts,
            starts,
            repeats,
            trial,
            record_dir: common.record.clone(),
        };
        let out = common
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from("lab-out").join(self.0.name()));
        let opts = RunOptions {
            threads,
            progress: !common.quiet,
            shard: common.shard,
            plot_all: common.plot_all,
        };
        let results = run_share(&module, &setup, opts)?;
        let context = SummaryContext {
            command: without_shard(command),
            layouts: setup.layouts.iter().map(|l| l.name.clone()).collect(),
            starts: setup.starts,
            repeats: setup.repeats,
            limit_s: setup.trial.limit_s,
            plots: Vec::new(),
            calibrations,
        };
        match common.shard {
            Some(shard) => {
                let head = ShardHead {
                    format: shard::FORMAT,
                    experiment: module.name().to_owned(),
                    shard,
                    trials: setup.controllers.len()
                        * setup.layouts.len()
                        * setup.starts
                        * setup.repeats,
                    plan: plan_fingerprint(&module, &setup),
                };
                let file = ShardFile {
                    head,
                    module,
                    context,
                    results,
                };
                let path = shard::write(&out, &file)?;
                if !common.quiet {
                    eprintln!(
                        "wrote {} ({} of {} trials); `snake-lab merge {}` once all {} are done",
                        path.display(),
                        file.results.len(),
                        file.head.trials,
                        out.display(),
                        shard.n
                    );
                }
            }
            None => {
                let results: Vec<_> = results.into_iter().map(|(_, r)| r).collect();
                let written = write_report(&module, &out, &results, &context)?;
                finish(&written, &out, common.quiet);
            }
        }
        Ok(())
    }

    fn merge(&self, files: &[PathBuf], out: &Path, quiet: bool) -> Result<(), LabError> {
        let shards = files
            .iter()
            .map(|p| shard::read_file::<E>(p))
            .collect::<Result<Vec<_>, _>>()?;
        let (module, context, results) = shard::merge_results(shards)?;
        let written = write_report(&module, out, &results, &context)?;
        finish(&written, out, quiet);
        Ok(())
    }
}

/// Checks what the runner would refuse, before the calibrations (which take a while).
fn check_counts(
    layouts: &[Layout],
    starts: usize,
    repeats: usize,
    limit_s: f64,
) -> Result<(), LabError> {
    if layouts.is_empty() {
        return Err(LabError::NoLayouts);
    }
    if starts == 0 {
        return Err(LabError::NoStarts);
    }
    if repeats == 0 {
        return Err(LabError::BadValue("--repeats must be at least 1".into()));
    }
    if !(limit_s.is_finite() && limit_s > 0.0) {
        return Err(LabError::BadValue(format!(
            "the time limit must be positive, not {limit_s} s"
        )));
    }
    Ok(())
}

/// The compared controllers of `module`: the names given (its own list when none),
/// then each `LABEL=JSON` variant over its variant base unless it names another.
pub fn compared<E: Experiment>(
    module: &E,
    given: &[String],
    variants: &[String],
) -> Result<Vec<LabController>, LabError> {
    let gait = module.gait();
    let names: Vec<&str> = if given.is_empty() {
        module.controllers().to_vec()
    } else {
        given.iter().map(|n| n.trim()).collect()
    };
    let mut controllers = names
        .into_iter()
        .map(|n| match module.any_gait() {
            true => LabController::named_any(gait, n),
            false => LabController::named(gait, n),
        })
        .collect::<Result<Vec<_>, _>>()?;
    for spec in variants {
        let base = module.variant_base();
        controllers.push(match module.any_gait() {
            true => LabController::variant_any(gait, spec, base)?,
            false => LabController::variant_on(gait, spec, base)?,
        });
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
        if let Some(done) = super::calibration::calibrate(c, &ground, trial)? {
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

/// Lists the files written (unless quiet) and prints the summary.
fn finish(written: &[PathBuf], out: &Path, quiet: bool) {
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

/// `args` as one shell command line, each argument quoted where needed.
pub fn command_line(args: impl IntoIterator<Item = String>) -> String {
    args.into_iter()
        .map(|a| {
            if !a.is_empty()
                && a.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./,=:+@".contains(c))
            {
                a
            } else {
                format!("'{}'", a.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// `command` without its `--shard K/N` (or `--shard=K/N`): the command of the one
/// unsharded run the shards make up.
fn without_shard(command: &str) -> String {
    let words: Vec<&str> = command.split(' ').collect();
    let mut out = Vec::with_capacity(words.len());
    let mut skip = false;
    for w in words {
        if skip {
            skip = false;
        } else if w == "--shard" {
            skip = true;
        } else if !w.starts_with("--shard=") {
            out.push(w);
        }
    }
    out.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shard_is_not_part_of_the_runs_command() {
        assert_eq!(
            without_shard("snake-lab pegboard --shard 2/3 --layouts 4"),
            "snake-lab pegboard --layouts 4"
        );
        assert_eq!(
            without_shard("snake-lab pegboard --layouts 4 --shard=1/3"),
            "snake-lab pegboard --layouts 4"
        );
        assert_eq!(
            command_line(["snake-lab".into(), "--nominal".into(), "{\"a\":1}".into()]),
            "snake-lab --nominal '{\"a\":1}'"
        );
    }
}

/// `--pose-source`: a named source, or fields over the lab's.
pub fn pose_source(spec: &str) -> Result<SourceConfig, LabError> {
    let bad = |why: String| LabError::BadValue(format!("--pose-source {spec:?}: {why}"));
    let source = match spec.trim() {
        "lab" => SourceConfig::LAB,
        "degraded" => SourceConfig::DEGRADED,
        json if json.starts_with('{') => {
            let mut v = serde_json::to_value(SourceConfig::LAB).map_err(|e| bad(e.to_string()))?;
            let patch: serde_json::Value =
                serde_json::from_str(json).map_err(|e| bad(e.to_string()))?;
            let (Some(base), Some(fields)) = (v.as_object_mut(), patch.as_object()) else {
                return Err(bad("a JSON object of the source's fields".into()));
            };
            for (k, x) in fields {
                base.insert(k.clone(), x.clone());
            }
            serde_json::from_value(v).map_err(|e| bad(e.to_string()))?
        }
        _ => return Err(bad("`lab`, `degraded` or a JSON object".into())),
    };
    source.check().map_err(bad)?;
    Ok(source)
}

#[cfg(test)]
mod pose_source_tests {
    use super::*;

    #[test]
    fn pose_source_is_named_or_patched_and_checked() {
        assert_eq!(pose_source("lab").unwrap(), SourceConfig::LAB);
        assert_eq!(pose_source("degraded").unwrap(), SourceConfig::DEGRADED);
        let s = pose_source(r#"{"rate_hz": 30, "latency_s": 0.05}"#).unwrap();
        assert_eq!((s.rate_hz, s.latency_s, s.noise_m), (30.0, 0.05, 0.002));
        for bad in ["mocap", r#"{"rate": 3}"#, r#"{"rate_hz": -1}"#, "[1]"] {
            let e = pose_source(bad).unwrap_err().to_string();
            assert!(e.contains("--pose-source"), "{bad}: {e}");
        }
    }
}
