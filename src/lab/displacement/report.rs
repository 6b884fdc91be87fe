//! `results.csv` (one row per trial) and `summary.md` of a displacement experiment:
//! per controller the velocity over all trials, its spread across poses, and every
//! pose's mean (the paper's Fig. 6 as a table).

use std::fmt::Write as _;

use super::Displacement;
use super::metrics::summarise;
use crate::lab::report::{SummaryContext, calibrations_markdown, csv_field, with_strain_header};
use crate::lab::runner::TrialResult;

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "controller,layout,pose,repeat,seconds,displacement_m,\
velocity_bl_min,forward_bl_min,left_field,self_contacts,mode_switches,directional_share";

/// `results.csv` as text.
pub fn results_csv(results: &[TrialResult<Displacement>]) -> String {
    let mut out = String::with_capacity(80 * (results.len() + 1));
    out.push_str(&with_strain_header(CSV_HEADER));
    out.push('\n');
    for r in results {
        let m = &r.metrics;
        let _ = writeln!(
            out,
            "{},{},{},{},{:.3},{:.4},{:.4},{:.4},{},{},{},{:.3},{}",
            csv_field(&r.controller),
            csv_field(&r.layout),
            r.start,
            r.repeat,
            m.seconds,
            m.displacement_m,
            m.velocity_bl_min,
            m.forward_bl_min,
            u8::from(m.left_field),
            m.self_contacts,
            m.mode_switches,
            m.directional_share,
            r.strain.csv_row()
        );
    }
    out
}

/// `summary.md` as text, titled `title`.
pub fn summary_markdown(
    title: &str,
    results: &[TrialResult<Displacement>],
    ctx: &SummaryContext,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {title}\n");
    let _ = writeln!(s, "Command:\n\n```sh\n{}\n```\n", ctx.command);
    let _ = writeln!(
        s,
        "{} layout(s) ({}), {} pose(s) each, {} trial(s) per pose (sensor-noise seeds), {} s \
         per trial.\n",
        ctx.layouts.len(),
        ctx.layouts.join(", "),
        ctx.starts,
        ctx.repeats,
        ctx.limit_s
    );
    s.push_str(
        "| controller | trials | BL/min mean ± sd | median | sd across poses | worst pose \
         | forward BL/min mean ± sd | left the field | self-contacts | mode switches \
         | time in PDC/NDC |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    let sums = summarise(results);
    for c in &sums {
        let (mean, sd, median) = c.velocity;
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} ± {:.3} | {:.3} | {:.3} | {:.3} | {:+.3} ± {:.3} | {}/{} | {:.1} | {:.1} | {:.0} % |",
            c.controller,
            c.trials,
            mean,
            sd,
            median,
            c.pose_sd,
            c.worst_pose,
            c.forward.0,
            c.forward.1,
            c.left_field,
            c.trials,
            c.self_contacts_mean,
            c.mode_switches_mean,
            100.0 * c.directional_share_mean
        );
    }
    if let Some(first) = sums.first() {
        s.push_str("\nMean velocity per pose, BL/min (± sd over its trials):\n\n| pose |");
        for c in &sums {
            let _ = write!(s, " {} |", c.controller);
        }
        s.push_str("\n| --- |");
        for _ in &sums {
            s.push_str(" ---: |");
        }
        s.push('\n');
        for (k, p) in first.poses.iter().enumerate() {
            let _ = write!(s, "| {} pose {} |", p.layout, p.start);
            for c in &sums {
                match c.poses.get(k) {
                    Some(q) => {
                        let _ = write!(s, " {:.3} ± {:.3} |", q.velocity.0, q.velocity.1);
                    }
                    None => s.push_str(" |"),
                }
            }
            s.push('\n');
        }
    }
    let _ = writeln!(
        s,
        "\nVelocity = straight-line displacement of the body's geometric centre (mean of the \
         links) from the start to the end of the trial, in body lengths (the modules' total \
         length) per minute (the reference's metric, unsigned). Forward = the same \
         displacement along the body's start heading, tail to head, signed: a body sliding \
         tail first scores negative. A trial ends early when the body's centre leaves the \
         obstacles' bounding box (left the field), its velocity taken over the time it took. \
         Sd across poses = sample sd of the pose means. Self-contacts = \
         contact onsets between non-adjacent links. Time in PDC/NDC = share of the samples \
         with at least one window in a directional mode. Definitions: docs/lab.md."
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
