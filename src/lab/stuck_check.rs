//! How the loop's stuck detector (`navigation::stuck`) did against the ground truth,
//! in any experiment (issue 28, point 2): how often it said stuck while the body made
//! way, how much of the time the body was jammed it said so, and how soon after a jam
//! began. The truth at a sample: the body centre's net displacement over the last
//! gait cycle (the wave's sway cancels over a whole cycle). Definitions: docs/lab.md.

use std::fmt::Write as _;

use super::trial::TrialRecord;

/// Moving: the centre went at least this far over the last gait cycle, m.
pub const MOVING_M: f64 = 0.05;
/// Jammed: it went less than this, m.
pub const JAMMED_M: f64 = 0.01;
/// A jam counts as an episode when it lasts this many gait cycles.
pub const EPISODE_CYCLES: f64 = 3.0;

/// One trial's check.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StuckCheck {
    /// Time the body was moving, and of it the time reported stuck, s.
    pub moving_s: f64,
    pub moving_stuck_s: f64,
    /// Time it was jammed, and of it the time reported stuck, s.
    pub jammed_s: f64,
    pub jammed_stuck_s: f64,
    /// Jam episodes, those in which stuck was reported, and the sum of the delays
    /// from the episode's start (the start of its first jammed cycle) to the report, s.
    pub episodes: u64,
    pub episodes_reported: u64,
    pub delay_sum_s: f64,
}

impl StuckCheck {
    /// Of `rec` (nothing when it holds no detector's reports).
    pub fn of(rec: &TrialRecord) -> StuckCheck {
        let mut c = StuckCheck::default();
        let n = rec.centre_m.len().min(rec.stuck_reported.len());
        let freq = rec.temporal_freq_rad_s.abs();
        if n == 0 || freq < 1e-9 || rec.sample_dt_s <= 0.0 {
            return c;
        }
        let cycle_s = std::f64::consts::TAU / freq;
        let lag = ((cycle_s / rec.sample_dt_s).round() as usize).max(1);
        let need = (EPISODE_CYCLES * cycle_s / rec.sample_dt_s).round() as usize;
        // The current run of jammed samples: where it began and whether it was reported.
        let mut run: Option<(usize, Option<usize>)> = None;
        let close = |run: Option<(usize, Option<usize>)>, end: usize, c: &mut StuckCheck| {
            if let Some((start, reported)) = run
                && end - start + lag >= need
            {
                c.episodes += 1;
                if let Some(k) = reported {
                    c.episodes_reported += 1;
                    // The jam began a cycle before its first jammed sample.
                    c.delay_sum_s += (k + lag - start) as f64 * rec.sample_dt_s;
                }
            }
        };
        for k in lag..n {
            let (a, b) = (rec.centre_m[k - lag], rec.centre_m[k]);
            let d = (b[0] - a[0]).hypot(b[1] - a[1]);
            let stuck = rec.stuck_reported[k];
            let dt = rec.sample_dt_s;
            if d >= MOVING_M {
                c.moving_s += dt;
                c.moving_stuck_s += if stuck { dt } else { 0.0 };
            }
            if d < JAMMED_M {
                c.jammed_s += dt;
                c.jammed_stuck_s += if stuck { dt } else { 0.0 };
                let (_, reported) = run.get_or_insert((k, None));
                if stuck && reported.is_none() {
                    *reported = Some(k);
                }
            } else {
                close(run.take(), k, &mut c);
            }
        }
        close(run.take(), n, &mut c);
        c
    }

    pub const CSV_HEADER: &'static str = "moving_s,stuck_while_moving_pct,jammed_s,stuck_while_jammed_pct,jam_episodes,jams_reported,jam_report_delay_s";

    /// The figures as reported: moving s, stuck while moving %, jammed s, stuck while
    /// jammed %, jam episodes, those reported, the mean delay s.
    fn figures(&self) -> (f64, f64, f64, f64, u64, u64, f64) {
        (
            self.moving_s,
            pct(self.moving_stuck_s, self.moving_s),
            self.jammed_s,
            pct(self.jammed_stuck_s, self.jammed_s),
            self.episodes,
            self.episodes_reported,
            self.delay_sum_s / self.episodes_reported.max(1) as f64,
        )
    }

    /// This trial's CSV cells.
    pub fn csv_row(&self) -> String {
        let (m, mp, j, jp, e, r, d) = self.figures();
        format!("{m:.1},{mp:.2},{j:.1},{jp:.2},{e},{r},{d:.2}")
    }

    /// Sums of several trials.
    pub fn add(&mut self, o: &StuckCheck) {
        self.moving_s += o.moving_s;
        self.moving_stuck_s += o.moving_stuck_s;
        self.jammed_s += o.jammed_s;
        self.jammed_stuck_s += o.jammed_stuck_s;
        self.episodes += o.episodes;
        self.episodes_reported += o.episodes_reported;
        self.delay_sum_s += o.delay_sum_s;
    }
}

fn pct(part: f64, whole: f64) -> f64 {
    if whole <= 0.0 {
        f64::NAN
    } else {
        100.0 * part / whole
    }
}

/// The summary's table: per controller, the pooled check.
pub fn stuck_markdown<'a>(rows: impl Iterator<Item = (&'a str, StuckCheck)>) -> String {
    let mut s = String::from(
        "\nThe loop's stuck detector against the truth (pooled over the trials):\n\n\
         | controller | moving s | stuck while moving % | jammed s | stuck while jammed % | jams reported | mean delay s |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (name, c) in rows {
        let (m, mp, j, jp, e, r, d) = c.figures();
        let _ = writeln!(
            s,
            "| {name} | {m:.0} | {mp:.1} | {j:.0} | {jp:.1} | {r}/{e} | {d:.1} |"
        );
    }
    let _ = write!(
        s,
        "\nMoving = the body centre went {MOVING_M} m or more over the last gait cycle; jammed = \
         under {JAMMED_M} m. A jam is an episode when it lasts {EPISODE_CYCLES} cycles; its delay \
         runs from the start of its first jammed cycle to the first stuck report. The detector \
         needs a whole cycle to compare with, so the delay is at least two cycles. Definitions: \
         docs/lab.md, \"Stuck check\".\n"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record at 10 Hz with a 1 s cycle: the centre moves `speed(t)` m/s.
    fn record(
        seconds: f64,
        speed: impl Fn(f64) -> f64,
        stuck: impl Fn(f64) -> bool,
    ) -> TrialRecord {
        let dt = 0.1;
        let n = (seconds / dt) as usize;
        let mut x = 0.0;
        let mut centre = Vec::new();
        let mut reported = Vec::new();
        for k in 0..n {
            let t = k as f64 * dt;
            centre.push([x, 0.0]);
            reported.push(stuck(t));
            x += speed(t) * dt;
        }
        let mut rec = crate::lab::plots::tests::record(0);
        rec.sample_dt_s = dt;
        rec.temporal_freq_rad_s = std::f64::consts::TAU;
        rec.centre_m = centre;
        rec.stuck_reported = reported;
        rec
    }

    #[test]
    fn counts_false_reports_detections_and_the_delay() {
        // Moving 0.2 m/s for 10 s, then jammed for 10 s; stuck reported from 12.5 s.
        let rec = record(
            20.0,
            |t| if t < 10.0 { 0.2 } else { 0.0 },
            |t| t >= 12.5 || (3.0..3.5).contains(&t),
        );
        let c = StuckCheck::of(&rec);
        assert!((c.moving_stuck_s - 0.5).abs() < 1e-9, "{c:?}");
        assert!((c.moving_s - 10.0).abs() < 0.3, "{c:?}");
        assert_eq!((c.episodes, c.episodes_reported), (1, 1), "{c:?}");
        // The jam began at 10 s (the first jammed cycle ends at 11 s); reported at 12.5 s.
        assert!((c.delay_sum_s - 2.5).abs() < 0.15, "{c:?}");
        assert!(pct(c.jammed_stuck_s, c.jammed_s) > 70.0, "{c:?}");
        let row = c.csv_row();
        assert_eq!(
            row.split(',').count(),
            StuckCheck::CSV_HEADER.split(',').count()
        );
        // A jam never reported, and one too short to count.
        let rec = record(
            20.0,
            |t| {
                if (5.0..6.5).contains(&t) || t > 12.0 {
                    0.0
                } else {
                    0.2
                }
            },
            |_| false,
        );
        let c = StuckCheck::of(&rec);
        assert_eq!((c.episodes, c.episodes_reported), (1, 0), "{c:?}");
        // No detector in the record: nothing.
        let mut rec = rec;
        rec.stuck_reported.clear();
        assert_eq!(StuckCheck::of(&rec), StuckCheck::default());
    }
}
