//! `results.csv` (one row per trial) and `summary.md` of a displacement experiment:
//! per controller the velocity over all trials, its spread across poses, and every
//! pose's mean (the paper's Fig. 6 as a table).

use std::fmt::Write as _;

use super::Displacement;
use super::metrics::summarise;
use crate::lab::runner::TrialResult;

/// The CSV header; one row per trial follows in plan order.
pub const CSV_HEADER: &str = "seconds,displacement_m,\
velocity_bl_min,forward_bl_min,left_field,self_contacts,mode_switches,directional_share";

/// One trial's row.
pub fn csv_row(r: &TrialResult<Displacement>) -> String {
    let m = &r.metrics;
    format!(
        "{:.3},{:.4},{:.4},{:.4},{},{},{},{:.3}",
        m.seconds,
        m.displacement_m,
        m.velocity_bl_min,
        m.forward_bl_min,
        u8::from(m.left_field),
        m.self_contacts,
        m.mode_switches,
        m.directional_share,
    )
}

/// The summary's tables (per controller, per pose) and their definitions.
pub fn summary_tables(results: &[TrialResult<Displacement>]) -> String {
    let mut s = String::new();
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
    s
}
