//! The peg board's `results.csv` row and `summary.md` table (one row per controller).

use std::fmt::Write as _;

use super::Pegboard;
use super::metrics::{MIN_PATH_M, TrialMetrics};
use crate::lab::metrics::mean_sd_median;
use crate::lab::runner::{TrialResult, controller_names};

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "success,seconds,cycles,path_m,distance_m,cycles_per_m,stuck_s,\
self_contacts,side_exit,progress_m";

/// One trial's row.
pub fn csv_row(r: &TrialResult<Pegboard>) -> String {
    let m = &r.metrics;
    format!(
        "{},{:.3},{:.4},{:.4},{:.4},{:.4},{:.2},{},{},{:.4}",
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
    )
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
pub fn summarise(results: &[TrialResult<Pegboard>]) -> Vec<ControllerSummary> {
    controller_names(results)
        .into_iter()
        .map(|name| {
            let mine: Vec<_> = results
                .iter()
                .filter(|r| r.controller == name)
                .map(|r| r.metrics)
                .collect();
            let mean = |f: &dyn Fn(&TrialMetrics) -> f64| {
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

/// The summary's table and its definitions.
pub fn summary_tables(results: &[TrialResult<Pegboard>]) -> String {
    let mut s = String::new();
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
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::report::{
        SummaryContext, csv_field, results_csv, summary_markdown, with_common_header,
    };

    fn result(controller: &str, start: usize, cpm: f64, success: bool) -> TrialResult<Pegboard> {
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
            stuck: Default::default(),
            odometry: Default::default(),
            position: Default::default(),
            plotted: None,
        }
    }

    #[test]
    fn csv_has_a_row_per_trial_with_every_column() {
        let rs = [result("a", 0, 10.0, true), result("b", 1, 20.0, false)];
        let csv = results_csv(&Pegboard::UNCONFIGURED, &rs);
        let lines: Vec<_> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(
            lines[0],
            with_common_header(&format!("controller,layout,start,repeat,{CSV_HEADER}"))
        );
        assert!(
            lines[1].starts_with(
                "a,seed1000,0,0,true,10.000,1.5000,0.1500,0.1000,10.0000,2.00,3,false,2.0000,"
            ),
            "{}",
            lines[1]
        );
        assert!(lines[2].contains(",false,-0.0500,"), "{}", lines[2]);
        assert!(lines.iter().all(|l| l.split(',').count() == 34));
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
            &Pegboard::UNCONFIGURED,
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
