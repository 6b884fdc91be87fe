//! The crossing experiment's `results.csv` row and `summary.md` tables.

use std::fmt::Write as _;

use super::Crossing;
use super::metrics::{CrossingMetrics, Outcome};
use super::starts::StartKind;
use crate::lab::metrics::mean_sd_median;
use crate::lab::runner::{TrialResult, controller_names};

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str =
    "start_kind,outcome,seconds,progress_m,lateral_m,stuck_s,self_contacts,gait_switches";

/// One trial's row.
pub fn csv_row(r: &TrialResult<Crossing>) -> String {
    let m = &r.metrics;
    format!(
        "{},{},{:.2},{:.4},{:.4},{:.1},{},{}",
        m.kind.name(),
        m.outcome.name(),
        m.seconds,
        m.progress_m,
        m.lateral_m,
        m.stuck_s,
        m.self_contacts,
        m.gait_switches,
    )
}

fn count(ms: &[CrossingMetrics], f: impl Fn(&CrossingMetrics) -> bool) -> usize {
    ms.iter().filter(|m| f(m)).count()
}

/// Per controller: crossed, side exits, crossed per start kind, time to cross, stuck
/// time, progress.
pub fn summary_tables(exp: &Crossing, results: &[TrialResult<Crossing>]) -> String {
    let mut s = format!(
        "Skin µ {} (floor and obstacles). Travel +x; trials end when the front half of the \
         body leaves the board (across: by the far edge; a side: by a side edge) or at the \
         limit.\n\n\
         | controller | trials | crossed | side exits | along-edge | along-inside | across-edge | across-inside | time to cross s (median) | stuck s (mean) | progress m (mean) | gait switches (mean) |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        exp.skin.mu()
    );
    for name in controller_names(results) {
        let ms: Vec<CrossingMetrics> = results
            .iter()
            .filter(|r| r.controller == name)
            .map(|r| r.metrics)
            .collect();
        let n = ms.len();
        let crossed = count(&ms, |m| m.outcome == Outcome::Crossed);
        let per_kind: Vec<String> = StartKind::ALL
            .iter()
            .map(|&k| {
                let of_kind = count(&ms, |m| m.kind == k);
                let ok = count(&ms, |m| m.kind == k && m.outcome == Outcome::Crossed);
                format!("{ok}/{of_kind}")
            })
            .collect();
        let times: Vec<f64> = ms
            .iter()
            .filter(|m| m.outcome == Outcome::Crossed)
            .map(|m| m.seconds)
            .collect();
        let median_time = mean_sd_median(&times).map_or(f64::NAN, |(_, _, m)| m);
        let mean = |f: fn(&CrossingMetrics) -> f64| ms.iter().map(f).sum::<f64>() / n.max(1) as f64;
        let _ = writeln!(
            s,
            "| {name} | {n} | {crossed}/{n} ({:.0} %) | {} | {} | {:.1} | {:.1} | {:+.2} | {:.1} |",
            100.0 * crossed as f64 / n.max(1) as f64,
            count(&ms, |m| m.outcome == Outcome::Side),
            per_kind.join(" | "),
            median_time,
            mean(|m| m.stuck_s),
            mean(|m| m.progress_m),
            mean(|m| f64::from(m.gait_switches)),
        );
    }
    s.push_str(
        "\nStarts: at the entry edge (the body before the board) or inside (its middle \
         0.7-1.0 m in), lying along the travel (facing +x) or across it (facing +y), yaw \
         ±0.3 rad. Each controller is aimed: `controller.heading` set at the takeover to the \
         body heading that travels +x in its gait. Time to cross over the crossed trials. \
         Stuck = time in 2 s windows in which the centre moved under 2 cm. Definitions: \
         docs/lab.md, \"Crossing\".\n",
    );
    s
}
