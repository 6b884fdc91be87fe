//! How the estimator's contact odometry (`estimation::odometry`) did against the ground
//! truth, in any experiment: over every gait cycle of a trial, the odometry's
//! displacement of the body's centre against the true one, turned into the truth's
//! frame by the heading offset at the cycle's start (so the gyros' yaw drift does not
//! count). A cycle counts as moving when the true centre went [`MOVING_M`] or more, and
//! as still under [`STILL_M`]. Definitions: docs/lab.md, "Odometry check".

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

use nalgebra::Vector3;

use super::trial::TrialRecord;
use crate::estimation::chassis::{Chassis, chassis};
use crate::num::wrap_pi;

/// Moving: the true centre went at least this far over the gait cycle, m.
pub const MOVING_M: f64 = 0.05;
/// Still: it went less than this, m.
pub const STILL_M: f64 = 0.02;
/// A direction within this of the truth's counts as right, rad.
pub const RIGHT_WITHIN_RAD: f64 = PI / 6.0;

/// One trial's check (sums, so trials pool).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OdometryCheck {
    /// Moving cycles (sampled every sample, overlapping), and the sum of their
    /// direction errors' magnitudes, rad, and how many were within 30°.
    pub moving: u64,
    pub direction_err_sum_rad: f64,
    pub direction_right: u64,
    /// Over the moving cycles, the odometry's length and the truth's, m.
    pub odometry_len_m: f64,
    pub true_len_m: f64,
    /// Still cycles, and those in which the odometry read moving.
    pub still: u64,
    pub still_read_moving: u64,
}

/// The true virtual chassis at sample `k` (of the true links, as the estimator
/// computes it from its own), continuing `last`.
fn true_chassis(rec: &TrialRecord, k: usize, last: Option<&Chassis>) -> Option<Chassis> {
    let links = rec.links_at(k);
    let heights = rec.heights_at(k);
    if links.is_empty() || heights.len() != links.len() {
        return None;
    }
    let points: Vec<Vector3<f64>> = links
        .iter()
        .zip(heights)
        .map(|(l, &z)| Vector3::new(l[0], l[1], z))
        .collect();
    Some(chassis(&points, last))
}

impl OdometryCheck {
    /// Of `rec` (nothing when it holds no estimates).
    pub fn of(rec: &TrialRecord) -> OdometryCheck {
        let mut c = OdometryCheck::default();
        let n = rec.centre_m.len().min(rec.estimate.len());
        let freq = rec.temporal_freq_rad_s.abs();
        if n == 0 || freq < 1e-9 || rec.sample_dt_s <= 0.0 {
            return c;
        }
        let lag = ((TAU / freq / rec.sample_dt_s).round() as usize).max(1);
        let mut truth: Vec<Option<Chassis>> = Vec::with_capacity(n);
        for k in 0..n {
            let last = truth.last().copied().flatten();
            truth.push(true_chassis(rec, k, last.as_ref()));
        }
        for k in lag..n {
            let (a, b) = (rec.centre_m[k - lag], rec.centre_m[k]);
            let (ea, eb) = (rec.estimate[k - lag], rec.estimate[k]);
            let Some(t0) = truth[k - lag] else { continue };
            if !(ea.iter().chain(&eb).all(|x| x.is_finite())) {
                continue;
            }
            let d_true = [b[0] - a[0], b[1] - a[1]];
            let offset = t0.heading_rad() - ea[2];
            let (s, co) = offset.sin_cos();
            let (dx, dy) = (eb[0] - ea[0], eb[1] - ea[1]);
            let d_est = [co * dx - s * dy, s * dx + co * dy];
            let true_len = d_true[0].hypot(d_true[1]);
            let est_len = d_est[0].hypot(d_est[1]);
            if true_len >= MOVING_M {
                let err = wrap_pi(d_est[1].atan2(d_est[0]) - d_true[1].atan2(d_true[0])).abs();
                c.moving += 1;
                c.direction_err_sum_rad += err;
                c.direction_right += u64::from(err <= RIGHT_WITHIN_RAD);
                c.odometry_len_m += est_len;
                c.true_len_m += true_len;
            } else if true_len < STILL_M {
                c.still += 1;
                c.still_read_moving += u64::from(est_len >= MOVING_M);
            }
        }
        c
    }

    pub const CSV_HEADER: &'static str = "odometry_direction_err_deg,odometry_right_pct,odometry_length_ratio,odometry_false_motion_pct";

    /// Mean direction error (deg), right within 30° (%), length ratio, still cycles read
    /// moving (%).
    fn figures(&self) -> (f64, f64, f64, f64) {
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
        (
            ratio(self.direction_err_sum_rad, self.moving as f64).to_degrees(),
            100.0 * ratio(self.direction_right as f64, self.moving as f64),
            ratio(self.odometry_len_m, self.true_len_m),
            100.0 * ratio(self.still_read_moving as f64, self.still as f64),
        )
    }

    /// This trial's CSV cells.
    pub fn csv_row(&self) -> String {
        let (d, r, l, f) = self.figures();
        format!("{d:.1},{r:.1},{l:.2},{f:.1}")
    }

    /// Sums of several trials.
    pub fn add(&mut self, o: &OdometryCheck) {
        self.moving += o.moving;
        self.direction_err_sum_rad += o.direction_err_sum_rad;
        self.direction_right += o.direction_right;
        self.odometry_len_m += o.odometry_len_m;
        self.true_len_m += o.true_len_m;
        self.still += o.still;
        self.still_read_moving += o.still_read_moving;
    }
}

/// The summary's table: per controller, the pooled check.
pub fn odometry_markdown<'a>(rows: impl Iterator<Item = (&'a str, OdometryCheck)>) -> String {
    let mut s = String::from(
        "\nThe estimator's contact odometry against the truth, over each gait cycle (pooled):\n\n\
         | controller | moving cycles | mean direction error ° | within 30° % | length ratio | still cycles read moving % |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (name, c) in rows {
        let (d, r, l, f) = c.figures();
        let _ = writeln!(
            s,
            "| {name} | {} | {d:.0} | {r:.0} | {l:.2} | {f:.0} |",
            c.moving
        );
    }
    let _ = write!(
        s,
        "\nEvery sample's last gait cycle: moving when the true centre went {MOVING_M} m or \
         more, still under {STILL_M} m; the odometry's displacement turned by the heading \
         offset at the cycle's start. Definitions: docs/lab.md, \"Odometry check\".\n"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record at 10 Hz with a 1 s cycle: a straight body of 5 links heading +x whose
    /// centre moves 0.1 m/s for 5 s, then stands; the estimate's world is turned by
    /// -0.5 rad, and its odometry goes on at 0.1 m/s throughout (it slides).
    fn record() -> TrialRecord {
        let (dt, yaw) = (0.1, -0.5f64);
        let (s, c) = yaw.sin_cos();
        let mut rec = crate::lab::plots::tests::record(0);
        rec.sample_dt_s = dt;
        rec.temporal_freq_rad_s = TAU;
        rec.start_links_m = vec![[0.0; 2]; 5];
        (rec.centre_m, rec.links_m, rec.heights_m, rec.estimate) = Default::default();
        for k in 0..100 {
            let t = k as f64 * dt;
            let x = 0.1 * t.min(5.0);
            rec.centre_m.push([x, 0.0]);
            rec.links_m
                .extend((0..5).map(|i| [x + (2.0 - i as f64) * 0.1, 0.0]));
            rec.heights_m.extend([0.0; 5]);
            let odo = 0.1 * t;
            rec.estimate.push([c * odo, s * odo, yaw]);
        }
        rec
    }

    #[test]
    fn turns_the_odometry_into_the_truth_s_frame_and_counts_false_motion() {
        let c = OdometryCheck::of(&record());
        let (dir, right, ratio, false_motion) = c.figures();
        // Cycles ending 1.0-5.0 s moved 0.1 m: right, in the truth's frame.
        assert!(c.moving >= 35, "{c:?}");
        assert!(dir < 1e-6 && right == 100.0, "{c:?}");
        // Only the cycles ending 5-6 s, half moving, read longer than the truth.
        assert!((1.0..1.05).contains(&ratio), "{c:?}");
        // Cycles ending after 6 s stood still while the odometry read 0.1 m.
        assert!(c.still >= 35 && false_motion == 100.0, "{c:?}");
        assert_eq!(
            c.csv_row().split(',').count(),
            OdometryCheck::CSV_HEADER.split(',').count()
        );
        assert_eq!(
            OdometryCheck::of(&crate::lab::plots::tests::record(0)).moving,
            0
        );
    }
}
