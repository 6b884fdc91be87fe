//! `results.csv` (one row per trial) and `summary.md` of the pole experiment: per
//! controller how many trials reached the top, fell, stalled or never got on, the
//! height climbed per gait cycle, the slips and the grip; then each pole's outcomes.

use std::fmt::Write as _;

use super::PoleClimb;
use super::metrics::Outcome;
use crate::lab::metrics::mean_sd_median;
use crate::lab::runner::{TrialResult, controller_names};

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "outcome,seconds,top_s,max_height_m,\
climb_per_cycle_m,slips,slid_m,grip_mean_nm,changes_passed";

/// One trial's row.
pub fn csv_row(r: &TrialResult<PoleClimb>) -> String {
    let m = &r.metrics;
    format!(
        "{},{:.2},{},{:.3},{:.4},{},{:.3},{:.3},{}",
        m.outcome.name(),
        m.seconds,
        m.top_s.map_or_else(String::new, |t| format!("{t:.2}")),
        m.max_height_m,
        m.climb_per_cycle_m,
        m.slips,
        m.slid_m,
        m.grip_mean_nm,
        m.changes_passed,
    )
}

fn stat(v: &[f64], digits: usize) -> String {
    mean_sd_median(v).map_or_else(
        || "–".into(),
        |(m, sd, _)| format!("{m:.digits$} ± {sd:.digits$}"),
    )
}

/// The poles' designs as a table.
fn poles_table(designs: &[super::poles::PoleDesign]) -> String {
    let mut s = String::from(
        "| pole | foot m | changes (from height m: to × foot, over m) |\n| --- | ---: | --- |\n",
    );
    for d in designs {
        let changes: Vec<String> = d
            .changes
            .iter()
            .map(|c| {
                if c.length_m > 0.0 {
                    format!("{:.2}: ×{:.2} over {:.2}", c.at_m, c.factor, c.length_m)
                } else {
                    format!("{:.2}: ×{:.2} step", c.at_m, c.factor)
                }
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {:.3} | {} |",
            d.name,
            d.foot_m,
            changes.join("; ")
        );
    }
    s
}

/// The summary's tables and their definitions; `designs` the poles run.
pub fn summary_tables(
    results: &[TrialResult<PoleClimb>],
    designs: &[super::poles::PoleDesign],
) -> String {
    let mut s = String::new();
    s.push_str(
        "| controller | trials | top | fell | stalled | not on | median s to top | climb m/cycle \
         | slips / trial | slid m / trial | grip N·m |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    let names = controller_names(results);
    for name in &names {
        let mine: Vec<_> = results.iter().filter(|r| r.controller == *name).collect();
        let count = |o: Outcome| mine.iter().filter(|r| r.metrics.outcome == o).count();
        let tops: Vec<f64> = mine.iter().filter_map(|r| r.metrics.top_s).collect();
        let on: Vec<_> = mine
            .iter()
            .filter(|r| r.metrics.outcome != Outcome::NotOn)
            .collect();
        let per = |f: &dyn Fn(&super::metrics::PoleMetrics) -> f64| -> Vec<f64> {
            on.iter().map(|r| f(&r.metrics)).collect()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            name,
            mine.len(),
            count(Outcome::Top),
            count(Outcome::Fell),
            count(Outcome::Stalled),
            count(Outcome::NotOn),
            mean_sd_median(&tops).map_or_else(|| "–".into(), |(_, _, m)| format!("{m:.0}")),
            stat(&per(&|m| m.climb_per_cycle_m), 3),
            stat(&per(&|m| m.slips as f64), 1),
            stat(&per(&|m| m.slid_m), 2),
            stat(&per(&|m| m.grip_mean_nm), 2),
        );
    }
    let _ = writeln!(
        s,
        "\nTop = the body's centre (mean of its links) at {:.1} m, above every diameter \
         change. Fell = got on (centre above 0.2 m) and came back below 0.1 m. Stalled = on \
         the pole, below the top, at the time limit. Not on = the centre never rose 0.2 m. \
         Climb per cycle = height gained from getting on to the top (or the highest point) \
         per gait cycle (2π/ωT). A slip = the centre dropping 3 cm within 1 s (a fall is \
         one). Grip = the controller's `grip_nm` signal (mean |τ_ext| over the joints) \
         while on the pole. Mean ± sample sd over the trials that got on. Definitions: \
         docs/lab.md.",
        super::poles::TOP_M
    );
    let mut poles: Vec<&str> = Vec::new();
    for r in results {
        if !poles.contains(&r.layout.as_str()) {
            poles.push(&r.layout);
        }
    }
    s.push_str("\nOutcomes per pole (top / fell / stalled / not on):\n\n| pole |");
    for n in &names {
        let _ = write!(s, " {n} |");
    }
    s.push_str("\n| --- |");
    for _ in &names {
        s.push_str(" ---: |");
    }
    s.push('\n');
    for p in &poles {
        let _ = write!(s, "| {p} |");
        for n in &names {
            let mine: Vec<_> = results
                .iter()
                .filter(|r| r.controller == *n && r.layout == *p)
                .collect();
            let c = |o: Outcome| mine.iter().filter(|r| r.metrics.outcome == o).count();
            let _ = write!(
                s,
                " {} / {} / {} / {} |",
                c(Outcome::Top),
                c(Outcome::Fell),
                c(Outcome::Stalled),
                c(Outcome::NotOn)
            );
        }
        s.push('\n');
    }
    s.push_str("\nThe poles:\n\n");
    s.push_str(&poles_table(designs));
    s
}
