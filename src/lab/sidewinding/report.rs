//! `results.csv` (one row per trial) and `summary.md` of the sidewinding experiment:
//! per controller its failed attempts, openings passed before entering, time to
//! reverse beyond the array, the reversals and the heading errors (the thesis's
//! Fig. 4.15 and 4.16 as a table).

use std::fmt::Write as _;

use super::SidewindingPegs;
use super::metrics::summarise;
use crate::lab::runner::TrialResult;

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "outcome,seconds,first_opening,\
opening,openings_passed,opening_width_m,reversals,first_reversal_s,reverse_beyond_s,\
heading_error_end_rad,estimate_error_mean_rad,estimate_error_max_rad,progress_m,self_contacts";

fn opt(v: Option<usize>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

/// One trial's row.
pub fn csv_row(r: &TrialResult<SidewindingPegs>) -> String {
    let m = &r.metrics;
    format!(
        "{},{:.2},{},{},{},{:.3},{},{:.2},{:.2},{:.3},{:.3},{:.3},{:.3},{}",
        m.outcome.name(),
        m.seconds,
        opt(m.first_opening),
        opt(m.opening),
        opt(m.openings_passed),
        m.opening_width_m,
        m.reversals,
        m.first_reversal_s,
        m.reverse_beyond_s,
        m.heading_error_end_rad,
        m.estimate_error_mean_rad,
        m.estimate_error_max_rad,
        m.progress_m,
        m.self_contacts,
    )
}

fn stat(s: Option<(f64, f64, f64)>, digits: usize) -> String {
    s.map_or_else(
        || "–".into(),
        |(m, sd, _)| format!("{m:.digits$} ± {sd:.digits$}"),
    )
}

/// The summary's table and its definitions.
pub fn summary_tables(results: &[TrialResult<SidewindingPegs>]) -> String {
    let mut s = String::new();
    s.push_str(
        "| controller | trials | through | failed: off board | failed: time | openings passed \
         | reverse beyond s | β reversed | end heading error rad | estimate error rad (mean / max) \
         | progress m |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for c in summarise(results) {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.3} / {:.3} | {:.2} ± {:.2} |",
            c.controller,
            c.trials,
            c.through,
            c.off_board,
            c.timeouts,
            stat(c.openings_passed, 2),
            stat(c.reverse_beyond_s, 1),
            c.reversed,
            stat(c.heading_error_end_rad, 2),
            c.estimate_error_mean_rad,
            c.estimate_error_max_rad,
            c.progress_m.0,
            c.progress_m.1
        );
    }
    let _ = writeln!(
        s,
        "\nThrough = every link beyond the pegs (peg radius + jitter + module radius past \
         the array's line). Failed attempt = not through: the body went round an end of the \
         array or 1 m back from it (off board), or the time ran out. Openings passed = \
         openings between the one nearest the first link to come up to the array and the \
         one most links last crossed through (through trials only). Reverse beyond = the \
         later of the first β reversal and passing the array (trials that did both). End \
         heading error = the true heading (the virtual chassis of the true links, mean \
         over the last gait cycle) against the nominal one for the controller's well \
         (flipped by each counted reversal). Estimate error = the controller's low-passed \
         heading estimate against the true heading low-passed alike, aligned at the first \
         estimate. Mean ± sample sd. Definitions: docs/lab.md."
    );
    s
}
