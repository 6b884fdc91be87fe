//! `results.csv` (one row per trial) and `summary.md` (one row per controller).

use std::fmt::Write as _;
use std::path::Path;

use super::LabError;
use super::experiment::ExperimentModule;
use super::metrics::{MIN_PATH_M, mean_sd_median};
use super::runner::{TrialResult, controller_names};
use super::strain::{Strain, StrainSummary};

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "controller,layout,start,success,seconds,cycles,path_m,distance_m,cycles_per_m,stuck_s,\
self_contacts,side_exit,progress_m";

/// `results.csv` as text.
pub fn results_csv(results: &[TrialResult]) -> String {
    let mut out = String::with_capacity(64 * (results.len() + 1));
    out.push_str(&with_strain_header(CSV_HEADER));
    out.push('\n');
    for r in results {
        let m = &r.metrics;
        let _ = writeln!(
            out,
            "{},{},{},{},{:.3},{:.4},{:.4},{:.4},{:.4},{:.2},{},{},{:.4},{}",
            csv_field(&r.controller),
            csv_field(&r.layout),
            r.start,
            m.success,
            m.seconds,
            m.cycles,
            m.path_m,
            m.distance_m,
            m.cycles_per_m,
            m.stuck_s,
            m.self_contacts,
            m.side_exit,
            m.progress_m,
            r.strain.csv_row()
        );
    }
    out
}

/// An experiment's CSV header with the strain columns every experiment appends.
pub fn with_strain_header(own: &str) -> String {
    format!("{own},{}", Strain::CSV_HEADER)
}

/// The summary's section on what the controllers asked of the actuators (any
/// experiment): per controller, medians and worst trials of [`Strain`].
pub fn strain_markdown<E: ExperimentModule>(results: &[TrialResult<E>]) -> String {
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
    s.push_str(
        "\nGuard-limited = cycles in which the set-point guard slowed a set-point to the \
         joints' speed (the controller asked for more). Peak joint speed = the fastest \
         joint speed a module reported in the trial; above motor speed = share of joint-time \
         reported faster than the motor's 3.46 rad/s (on the spring or thrown by a contact). \
         At torque limit = share of joint-time at 95 % of 7 N·m or more. Definitions: \
         docs/lab.md, \"Strain\".\n",
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

/// What the summary says about how the results were made.
#[derive(Debug, Clone, Default)]
pub struct SummaryContext {
    /// The exact command line.
    pub command: String,
    pub layouts: Vec<String>,
    pub starts: usize,
    /// Trials per start (differing in their sensor-noise seed).
    pub repeats: usize,
    pub limit_s: f64,
    /// PNG files written beside the summary (names).
    pub plots: Vec<String>,
    /// Controllers calibrated on open ground before the trials: label and what was
    /// measured (JSON).
    pub calibrations: Vec<(String, String)>,
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

/// One controller's figures over its trials.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerSummary {
    pub controller: String,
    pub trials: usize,
    pub successes: usize,
    pub side_exits: usize,
    /// Cycles per metre over all trials: mean, sample sd, median.
    pub cycles_per_m: (f64, f64, f64),
    pub mean_stuck_s: f64,
    pub mean_seconds: f64,
    pub mean_path_m: f64,
    pub mean_progress_m: f64,
}

/// Per-controller figures, controllers in the order they first appear in `results`.
pub fn summarise(results: &[TrialResult]) -> Vec<ControllerSummary> {
    super::runner::controller_names(results)
        .into_iter()
        .map(|name| {
            let mine: Vec<_> = results
                .iter()
                .filter(|r| r.controller == name)
                .map(|r| r.metrics)
                .collect();
            let mean = |f: &dyn Fn(&super::metrics::TrialMetrics) -> f64| {
                mine.iter().map(f).sum::<f64>() / mine.len() as f64
            };
            let cpm: Vec<f64> = mine.iter().map(|m| m.cycles_per_m).collect();
            ControllerSummary {
                controller: name.to_owned(),
                trials: mine.len(),
                successes: mine.iter().filter(|m| m.success).count(),
                side_exits: mine.iter().filter(|m| m.side_exit).count(),
                cycles_per_m: mean_sd_median(&cpm).expect("a named controller has trials"),
                mean_stuck_s: mean(&|m| m.stuck_s),
                mean_seconds: mean(&|m| m.seconds),
                mean_path_m: mean(&|m| m.path_m),
                mean_progress_m: mean(&|m| m.progress_m),
            }
        })
        .collect()
}

/// `summary.md` as text.
pub fn summary_markdown(results: &[TrialResult], ctx: &SummaryContext) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Peg-board experiment (SPEC §5)\n");
    let _ = writeln!(s, "Command:\n\n```sh\n{}\n```\n", ctx.command);
    let _ = writeln!(
        s,
        "{} layouts ({}), {} start(s) each, time limit {} s.\n",
        ctx.layouts.len(),
        ctx.layouts.join(", "),
        ctx.starts,
        ctx.limit_s
    );
    s.push_str(
        "| controller | trials | success | side exits | cycles/m mean ± sd | cycles/m median \
         | stuck s (mean) | trial s (mean) | path m (mean) | progress m (mean) |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for c in summarise(results) {
        let (mean, sd, median) = c.cycles_per_m;
        let _ = writeln!(
            s,
            "| {} | {} | {}/{} ({:.0} %) | {} | {:.2} ± {:.2} | {:.2} | {:.1} | {:.1} | {:.2} | {:+.2} |",
            c.controller,
            c.trials,
            c.successes,
            c.trials,
            100.0 * c.successes as f64 / c.trials as f64,
            c.side_exits,
            mean,
            sd,
            median,
            c.mean_stuck_s,
            c.mean_seconds,
            c.mean_path_m,
            c.mean_progress_m
        );
    }
    let _ = writeln!(
        s,
        "\nTime to traverse = nominal body-wave cycles (ωT·t/2π at the end of the trial) per \
         metre of the body centre's smoothed path; lower is better. Every trial counts, failed \
         ones with the cycles and path they had at the time limit; a smoothed path under \
         {:.0} cm counts as {:.0} cm. A trial ends when the front half of the body leaves \
         the board by any edge but the one it entered (as the thesis's did); success = it left \
         by the far edge, across the board; side exits are counted apart. Progress = the \
         centre's signed displacement towards the far edge, first to last position (negative: \
         it drifted back). Stuck = time in 2 s windows in which \
         the smoothed centre moved under 2 cm. Definitions: docs/lab.md.",
        MIN_PATH_M * 100.0,
        MIN_PATH_M * 100.0
    );
    s.push_str(&calibrations_markdown(ctx));
    s.push_str(&crate::lab::report::strain_markdown(results));
    let _ = writeln!(s, "\nPer trial: `results.csv`.");
    if !ctx.plots.is_empty() {
        s.push_str("\nPlots:\n\n");
        for p in &ctx.plots {
            let _ = writeln!(s, "- `{p}`");
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::metrics::TrialMetrics;

    fn result(controller: &str, start: usize, cpm: f64, success: bool) -> TrialResult {
        TrialResult {
            controller: controller.into(),
            layout: "seed1000".into(),
            start,
            repeat: 0,
            metrics: TrialMetrics {
                success,
                seconds: 10.0,
                cycles: 1.5,
                path_m: 1.5 / cpm,
                distance_m: 0.1,
                cycles_per_m: cpm,
                stuck_s: 2.0,
                self_contacts: 3,
                side_exit: !success && start == 2,
                progress_m: if success { 2.0 } else { -0.05 },
            },
            strain: Default::default(),
            plotted: None,
        }
    }

    #[test]
    fn csv_has_a_row_per_trial_with_every_column() {
        let rs = [result("a", 0, 10.0, true), result("b", 1, 20.0, false)];
        let csv = results_csv(&rs);
        let lines: Vec<_> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], with_strain_header(CSV_HEADER));
        assert!(
            lines[1].starts_with(
                "a,seed1000,0,true,10.000,1.5000,0.1500,0.1000,10.0000,2.00,3,false,2.0000,"
            ),
            "{}",
            lines[1]
        );
        assert!(lines[2].contains(",false,-0.0500,"), "{}", lines[2]);
        assert!(lines.iter().all(|l| l.split(',').count() == 18));
        assert_eq!(csv_field("a,b"), "\"a,b\"");
    }

    #[test]
    fn summary_counts_every_trial_per_controller() {
        let rs = [
            result("b", 0, 10.0, true),
            result("b", 1, 20.0, false),
            result("b", 2, 60.0, false),
            result("a", 0, 5.0, true),
        ];
        let sum = summarise(&rs);
        assert_eq!(sum.len(), 2);
        assert_eq!(sum[0].controller, "b", "order of appearance");
        assert_eq!((sum[0].trials, sum[0].successes), (3, 1));
        assert_eq!(sum[0].side_exits, 1, "start 2 left by a side");
        assert!((sum[0].mean_progress_m - (2.0 - 0.1) / 3.0).abs() < 1e-12);
        assert_eq!(sum[0].cycles_per_m.0, 30.0);
        assert_eq!(sum[0].cycles_per_m.2, 20.0);
        let md = summary_markdown(
            &rs,
            &SummaryContext {
                command: "snake-lab pegboard --layouts 1".into(),
                layouts: vec!["seed1000".into()],
                starts: 3,
                repeats: 1,
                limit_s: 120.0,
                plots: vec!["cycles_per_m.png".into()],
                calibrations: vec![("dc_switching".into(), "{\"lateral_rad\":[0.1]}".into())],
            },
        );
        assert!(md.contains("snake-lab pegboard --layouts 1"));
        assert!(
            md.contains("- dc_switching: `{\"lateral_rad\":[0.1]}`"),
            "{md}"
        );
        assert!(
            md.contains("| b | 3 | 1/3 (33 %) | 1 | 30.00 ± 26.46 | 20.00 |"),
            "{md}"
        );
        assert!(md.contains("| a | 1 | 1/1 (100 %) | 0 | 5.00 ± 0.00 | 5.00 |"));
        assert!(md.contains("`cycles_per_m.png`"));
    }
}
