//! How the fused position (an outside source's fixes with the body's own motion,
//! `estimation::world_position`) did against the ground truth, in any experiment run
//! with a simulated source (`--pose-source`): per sample, the distance from the fused
//! chassis position to the true one (the links' centroid) while it is valid, and how
//! often it was valid. Empty (all zero) without a source.

use std::fmt::Write as _;

use super::trial::TrialRecord;

/// One trial's check (sums, so trials pool).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PositionCheck {
    pub samples: u64,
    /// Samples in which the position was valid.
    pub tracked: u64,
    pub error_sum_m: f64,
    pub error_max_m: f64,
    /// Valid samples more than [`FAR_M`] off.
    pub far: u64,
}

/// An error past this counts as far, m.
pub const FAR_M: f64 = 0.05;

impl PositionCheck {
    pub fn of(rec: &TrialRecord) -> Self {
        let mut c = Self::default();
        for &e in &rec.position_error_m {
            c.samples += 1;
            if e.is_finite() {
                c.tracked += 1;
                c.error_sum_m += e;
                c.error_max_m = c.error_max_m.max(e);
                c.far += u64::from(e > FAR_M);
            }
        }
        c
    }

    pub const CSV_HEADER: &'static str =
        "position_tracked_pct,position_err_mean_m,position_err_max_m,position_far_pct";

    /// Tracked (%), mean and largest error (m), far (% of tracked); NaN without a source.
    fn figures(&self) -> (f64, f64, f64, f64) {
        let ratio = |a: f64, b: u64| if b > 0 { a / b as f64 } else { f64::NAN };
        let max = if self.tracked > 0 {
            self.error_max_m
        } else {
            f64::NAN
        };
        (
            100.0 * ratio(self.tracked as f64, self.samples),
            ratio(self.error_sum_m, self.tracked),
            max,
            100.0 * ratio(self.far as f64, self.tracked),
        )
    }

    /// This trial's CSV cells.
    pub fn csv_row(&self) -> String {
        let (t, m, x, f) = self.figures();
        format!("{t:.1},{m:.4},{x:.4},{f:.1}")
    }

    /// Sums of several trials.
    pub fn add(&mut self, o: &PositionCheck) {
        self.samples += o.samples;
        self.tracked += o.tracked;
        self.error_sum_m += o.error_sum_m;
        self.error_max_m = self.error_max_m.max(o.error_max_m);
        self.far += o.far;
    }
}

/// The summary's table (nothing without a source): per controller, the pooled check.
pub fn position_markdown<'a>(rows: impl Iterator<Item = (&'a str, PositionCheck)>) -> String {
    let rows: Vec<_> = rows.filter(|(_, c)| c.samples > 0).collect();
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "\nThe fused position (the simulated source's fixes with the body's own motion) \
         against the truth (pooled):\n\n\
         | controller | samples | valid % | mean error mm | largest error mm | off by more than 5 cm % |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (name, c) in rows {
        let (t, m, x, f) = c.figures();
        let _ = writeln!(
            s,
            "| {name} | {} | {t:.1} | {:.1} | {:.1} | {f:.1} |",
            c.samples,
            m * 1e3,
            x * 1e3
        );
    }
    let _ = write!(
        s,
        "\nEvery sample: the fused chassis position against the links' true centroid while \
         the position is valid (docs/estimation.md, \"Where the body is\").\n"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trial_s_errors_pool_and_print() {
        let rec = TrialRecord {
            position_error_m: vec![f64::NAN, 0.01, 0.03, 0.08],
            ..crate::lab::plots::tests::record(0)
        };
        let c = PositionCheck::of(&rec);
        assert_eq!((c.samples, c.tracked, c.far), (4, 3, 1));
        assert_eq!(c.csv_row(), "75.0,0.0400,0.0800,33.3");
        let mut all = PositionCheck::default();
        all.add(&c);
        all.add(&c);
        assert_eq!(all.samples, 8);
        let md = position_markdown([("a", all)].into_iter());
        assert!(md.contains("| a | 8 | 75.0 | 40.0 | 80.0 | 33.3 |"), "{md}");
        assert!(position_markdown([("a", PositionCheck::default())].into_iter()).is_empty());
        assert_eq!(
            PositionCheck::CSV_HEADER.split(',').count(),
            c.csv_row().split(',').count()
        );
    }
}
