//! The report of any experiment: `results.csv` (one row per trial, the experiment's
//! columns then the strain's), `summary.md` (how the run was made, the experiment's
//! tables, the calibrations, the strain, the plots) and the plots, written by
//! [`write_report`] from the experiment's pieces ([`Experiment`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::LabError;
use super::experiment::Experiment;
pub use super::experiment::SummaryContext;
use super::experiment::{TrialResult, controller_names};
use super::odometry_check::{OdometryCheck, odometry_markdown};
use super::position_check::{PositionCheck, position_markdown};
use super::strain::{Strain, StrainSummary};
use super::stuck_check::{StuckCheck, stuck_markdown};

/// An experiment's CSV header with the columns every experiment appends: the
/// strain's, the stuck check's and the odometry check's.
pub fn with_common_header(own: &str) -> String {
    format!(
        "{own},{},{},{},{}",
        Strain::CSV_HEADER,
        StuckCheck::CSV_HEADER,
        OdometryCheck::CSV_HEADER,
        PositionCheck::CSV_HEADER
    )
}

/// The summary's section on what the controllers asked of the actuators (any
/// experiment): per controller, medians and worst trials of [`Strain`].
pub fn strain_markdown<E: Experiment>(results: &[TrialResult<E>]) -> String {
    let mut s = String::from(
        "\nWhat each controller asked of the actuators (every cycle of every trial):\n\n",
    );
    s.push_str(StrainSummary::TABLE_HEADER);
    s.push('\n');
    for name in controller_names(results) {
        let mine = results.iter().filter(|r| r.controller == name);
        let _ = writeln!(
            s,
            "{}",
            StrainSummary::of(mine.map(|r| &r.strain)).table_row(name)
        );
    }
    let _ = write!(
        s,
        "\nGuard-limited = cycles in which the set-point guard slowed a set-point to the \
         joints' speed (the controller asked for more). Peak joint speed = the fastest \
         joint speed a module reported in the trial; above motor speed = share of joint-time \
         reported faster than the motor's {} rad/s (on the spring or thrown by a contact). \
         At torque limit = share of joint-time at 95 % of {} N·m or more. Definitions: \
         docs/lab.md, \"Strain\".\n",
        crate::module::MODULE_MAX_SPEED_RAD_S,
        crate::module::MODULE_MAX_TORQUE_NM,
    );
    s
}

pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The calibrations section of a summary (empty when there were none).
pub fn calibrations_markdown(ctx: &SummaryContext) -> String {
    let mut s = String::new();
    if ctx.calibrations.is_empty() {
        return s;
    }
    s.push_str(
        "\nCalibrated on open ground before the trials (`controller.calibrate`, 3 gait \
         cycles, the trials' ground without obstacles), friction offsets in rad:\n\n",
    );
    for (label, json) in &ctx.calibrations {
        let _ = writeln!(s, "- {label}: `{json}`");
    }
    s
}

/// Writes `text` to `path`.
pub fn write_text(path: &Path, text: &str) -> Result<(), LabError> {
    std::fs::write(path, text).map_err(|source| LabError::Io {
        path: path.to_owned(),
        source,
    })
}

/// `results.csv` as text: per trial its keys (controller, layout, start, repeat), the
/// experiment's columns and the strain's.
pub fn results_csv<E: Experiment>(module: &E, results: &[TrialResult<E>]) -> String {
    let mut out = String::with_capacity(120 * (results.len() + 1));
    let keys = module.csv_keys().join(",");
    out.push_str(&with_common_header(&format!(
        "{keys},{}",
        module.csv_header()
    )));
    out.push('\n');
    for r in results {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{}",
            csv_field(&r.controller),
            csv_field(&r.layout),
            r.start,
            r.repeat,
            module.csv_row(r),
            r.strain.csv_row(),
            r.stuck.csv_row(),
            r.odometry.csv_row(),
            r.position.csv_row()
        );
    }
    out
}

/// `summary.md` as text.
pub fn summary_markdown<E: Experiment>(
    module: &E,
    results: &[TrialResult<E>],
    ctx: &SummaryContext,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n", module.title());
    let _ = writeln!(s, "Command:\n\n```sh\n{}\n```\n", ctx.command);
    let _ = writeln!(
        s,
        "{} layout(s) ({}), {} start(s) each, {} trial(s) per start (sensor-noise seeds), \
         at most {} s per trial.\n",
        ctx.layouts.len(),
        ctx.layouts.join(", "),
        ctx.starts,
        ctx.repeats,
        ctx.limit_s
    );
    s.push_str(&module.summary_tables(results, ctx));
    s.push_str(&calibrations_markdown(ctx));
    s.push_str(&strain_markdown(results));
    s.push_str(&stuck_markdown(pooled(results, |c: &mut StuckCheck, r| {
        c.add(&r.stuck)
    })));
    s.push_str(&odometry_markdown(pooled(
        results,
        |c: &mut OdometryCheck, r| c.add(&r.odometry),
    )));
    s.push_str(&position_markdown(pooled(
        results,
        |c: &mut PositionCheck, r| c.add(&r.position),
    )));
    let _ = writeln!(s, "\nPer trial: `results.csv`.");
    if !ctx.plots.is_empty() {
        s.push_str("\nPlots:\n\n");
        for p in &ctx.plots {
            let _ = writeln!(s, "- `{p}`");
        }
    }
    s
}

/// Per controller (in order), a check pooled over its trials by `add`.
fn pooled<'a, E: Experiment, C: Default>(
    results: &'a [TrialResult<E>],
    add: impl Fn(&mut C, &TrialResult<E>) + 'a,
) -> impl Iterator<Item = (&'a str, C)> + 'a {
    controller_names(results).into_iter().map(move |name| {
        let mut c = C::default();
        results
            .iter()
            .filter(|r| r.controller == name)
            .for_each(|r| add(&mut c, r));
        (name, c)
    })
}

/// Writes `results.csv`, the experiment's plots (over every trial, then each
/// controller's plotted trial) and `summary.md` into `dir` (created if missing);
/// returns the files written.
pub fn write_report<E: Experiment>(
    module: &E,
    dir: &Path,
    results: &[TrialResult<E>],
    ctx: &SummaryContext,
) -> Result<Vec<PathBuf>, LabError> {
    std::fs::create_dir_all(dir).map_err(|source| LabError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    let csv = dir.join("results.csv");
    write_text(&csv, &results_csv(module, results))?;
    written.push(csv);
    written.extend(module.run_plots(dir, results)?);
    // The summary lists the run's plots and each controller's first trial's.
    let mut shown: Vec<PathBuf> = written[1..].to_vec();
    let mut seen = std::collections::BTreeSet::new();
    for r in results {
        let Some((world, goal, rec)) = &r.plotted else {
            continue;
        };
        if seen.insert(r.controller.as_str()) {
            let plots = module.trial_plots(dir, r, (world, goal, rec))?;
            shown.extend(plots.iter().cloned());
            written.extend(plots);
        } else {
            // `--plot-all`: the other trials' plots, a folder each.
            let sub = dir.join("trials").join(format!(
                "{}-s{}-r{}",
                crate::lab::file_stem(&r.layout),
                r.start,
                r.repeat
            ));
            std::fs::create_dir_all(&sub).map_err(|source| LabError::Io {
                path: sub.clone(),
                source,
            })?;
            written.extend(module.trial_plots(&sub, r, (world, goal, rec))?);
        }
    }
    let mut ctx = ctx.clone();
    ctx.plots = shown
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let md = dir.join("summary.md");
    write_text(&md, &summary_markdown(module, results, &ctx))?;
    written.push(md);
    Ok(written)
}
