//! `snake-lab`: controller comparisons in simulation. Each experiment of
//! `snaked::lab::registry` is a subcommand writing `results.csv`, `summary.md` and PNG
//! plots, whole or as one shard of a cluster sweep; `merge` joins the shards; `list`
//! names every experiment and its controllers. See `docs/lab.md`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Arg, ArgAction, Command};
use snaked::lab::LabError;
use snaked::lab::cli::command_line;
use snaked::lab::registry::{EXPERIMENTS, describe, find};
use snaked::lab::shard;

fn cli() -> Command {
    let mut cmd = Command::new("snake-lab")
        .version(env!("CARGO_PKG_VERSION"))
        .about("Controller comparisons for the snake robot in simulation (docs/lab.md).")
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(Command::new("list").about(
            "List every experiment, the controllers it compares by default (in report order) and what else it can run.",
        ))
        .subcommand(
            Command::new("merge")
                .about("Write the report of a sharded run from all its shard files.")
                .arg(
                    Arg::new("shards")
                        .value_name("DIR_OR_FILE")
                        .required(true)
                        .num_args(1..)
                        .value_parser(clap::value_parser!(PathBuf))
                        .help("Shard files, or directories holding shard-K-of-N.cbor files"),
                )
                .arg(
                    Arg::new("out")
                        .long("out")
                        .value_name("DIR")
                        .value_parser(clap::value_parser!(PathBuf))
                        .help("Output directory (default: the first directory given)"),
                )
                .arg(
                    Arg::new("expect")
                        .long("expect")
                        .value_name("N")
                        .value_parser(clap::builder::RangedU64ValueParser::<usize>::new().range(1..))
                        .help(
                            "The run's shard count: shards of another count are refused, and \
                             the missing ones are named even when no file is there",
                        ),
                )
                .arg(
                    Arg::new("quiet")
                        .long("quiet")
                        .action(ArgAction::SetTrue)
                        .help("No list of written files"),
                ),
        );
    for e in EXPERIMENTS {
        cmd = cmd.subcommand(e.command());
    }
    cmd
}

fn main() -> ExitCode {
    // Past a file-size limit (`ulimit -f`, a Slurm job's) a write of a result, a plot or a
    // trial's recording must fail with EFBIG and be reported with its path, not kill the
    // run with SIGXFSZ and lose what the other trials made.
    // SAFETY: only sets the signal's disposition; no handler runs.
    unsafe { libc::signal(libc::SIGXFSZ, libc::SIG_IGN) };
    let matches = cli().get_matches();
    let result = match matches.subcommand() {
        Some(("list", _)) => {
            list();
            Ok(())
        }
        Some(("merge", m)) => merge(m),
        Some((name, m)) => match find(name) {
            Some(e) => {
                let typed = std::iter::once("snake-lab".to_owned()).chain(std::env::args().skip(1));
                e.run(m, &command_line(typed))
            }
            None => Err(LabError::BadValue(format!("no experiment {name:?}"))),
        },
        None => Ok(()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // The causes the message does not already say.
            let mut msg = e.to_string();
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                let cause = s.to_string();
                if !msg.contains(&cause) {
                    msg = format!("{msg}: {cause}");
                }
                source = s.source();
            }
            eprintln!("snake-lab: {msg}");
            ExitCode::from(if e.is_bad_input() { 2 } else { 1 })
        }
    }
}

/// Every experiment: its name and summary, its default controllers, what else it can
/// run (`lab::registry::describe`).
fn list() {
    for e in EXPERIMENTS {
        println!("{}", describe(*e));
    }
}

fn merge(m: &clap::ArgMatches) -> Result<(), LabError> {
    let given: Vec<PathBuf> = m
        .get_many::<PathBuf>("shards")
        .map(|v| v.cloned().collect())
        .unwrap_or_default();
    let expect = m.get_one::<usize>("expect").copied();
    let files = shard::find(&given, expect)?;
    let heads = files
        .iter()
        .map(|p| Ok((p.clone(), shard::read_head(p)?)))
        .collect::<Result<Vec<_>, LabError>>()?;
    shard::check_complete(&heads, expect)?;
    let experiment = &heads[0].1.experiment;
    let lab = find(experiment).ok_or_else(|| {
        LabError::BadValue(format!(
            "the shards are of experiment {experiment:?}, which this snake-lab does not have"
        ))
    })?;
    let out = match m.get_one::<PathBuf>("out") {
        Some(dir) => dir.clone(),
        None => default_out(&given[0]),
    };
    lab.merge(&files, &out, m.get_flag("quiet"))
}

/// The first argument if it is a directory, else the directory of the file.
fn default_out(first: &Path) -> PathBuf {
    if first.is_dir() {
        first.to_owned()
    } else {
        first
            .parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
    }
}
