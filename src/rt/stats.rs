//! Per-cycle statistics in fixed-bucket histograms: `Copy`, sized at compile
//! time, so recording and publishing them never allocates.
use serde::Serialize;

/// Sub-buckets per power of two (2^3 = 8): a bucket's width is at most 1/8 of its value.
const SUB_BITS: u32 = 3;
const SUB: u64 = 1 << SUB_BITS;
/// Values up to 2^40 ns (about 18 minutes) have their own bucket; larger ones land in the last.
const MAX_MSB: u32 = 40;
pub const BUCKETS: usize = (((MAX_MSB - SUB_BITS + 1) as u64) * SUB + SUB) as usize;

/// A histogram of nanosecond values with log-linear buckets (HDR-style, 3 significant bits).
#[derive(Clone, Copy)]
pub struct Histogram {
    counts: [u32; BUCKETS],
    count: u64,
    sum_ns: u64,
    min_ns: u64,
    max_ns: u64,
}

impl Default for Histogram {
    fn default() -> Self {
        Self {
            counts: [0; BUCKETS],
            count: 0,
            sum_ns: 0,
            min_ns: u64::MAX,
            max_ns: 0,
        }
    }
}

fn bucket_of(v: u64) -> usize {
    if v < SUB {
        return v as usize;
    }
    let msb = 63 - v.leading_zeros();
    if msb > MAX_MSB {
        return BUCKETS - 1;
    }
    let shift = msb - SUB_BITS;
    (((msb - SUB_BITS + 1) as u64) * SUB + ((v >> shift) & (SUB - 1))) as usize
}

/// Largest value that falls in bucket `i`.
fn bucket_upper(i: usize) -> u64 {
    let i = i as u64;
    if i < SUB {
        return i;
    }
    let octave = i / SUB - 1; // msb - SUB_BITS
    let sub = i % SUB;
    let shift = octave as u32;
    ((SUB + sub + 1) << shift) - 1
}

/// The 1-based rank of the `q` quantile (0..=1) among `count` samples.
fn rank_of(q: f64, count: u64) -> u64 {
    ((q.clamp(0.0, 1.0) * count as f64).ceil() as u64).max(1)
}

impl Histogram {
    pub fn record(&mut self, v_ns: u64) {
        let b = bucket_of(v_ns);
        self.counts[b] = self.counts[b].saturating_add(1);
        self.count += 1;
        self.sum_ns = self.sum_ns.saturating_add(v_ns);
        self.min_ns = self.min_ns.min(v_ns);
        self.max_ns = self.max_ns.max(v_ns);
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    /// Value below which a fraction `q` (0..=1) of the samples lie: the upper edge of
    /// the bucket that holds that rank, capped by the exact maximum.
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.count == 0 {
            return 0;
        }
        let rank = rank_of(q, self.count);
        let mut seen = 0u64;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c as u64;
            if seen >= rank {
                // The last bucket is open-ended: only the exact maximum bounds it.
                if i == BUCKETS - 1 {
                    return self.max_ns;
                }
                return bucket_upper(i).min(self.max_ns);
            }
        }
        self.max_ns
    }

    pub fn summary(&self) -> Summary {
        let us = |ns: u64| ns as f64 / 1000.0;
        Summary {
            count: self.count,
            mean_us: if self.count == 0 {
                0.0
            } else {
                us(self.sum_ns) / self.count as f64
            },
            min_us: if self.count == 0 {
                0.0
            } else {
                us(self.min_ns)
            },
            p50_us: us(self.quantile_ns(0.5)),
            p99_us: us(self.quantile_ns(0.99)),
            p999_us: us(self.quantile_ns(0.999)),
            max_us: us(self.max_ns),
        }
    }
}

/// Values below this have a bucket of their own 1 µs wide in a [`LatencyHistogram`].
pub const FINE_LIMIT_NS: u64 = 200_000;
const FINE_BUCKETS: usize = (FINE_LIMIT_NS / 1000) as usize;

/// A wake-up latency histogram fine enough to compare with cyclictest's: 1 µs buckets
/// up to 200 µs (where a loop's p99 lies), the log-linear [`Histogram`] above. Its
/// quantiles below 200 µs are whole µs, truncated, as cyclictest's `-h` histogram
/// counts them, so the two compare bucket for bucket.
#[derive(Clone, Copy)]
pub struct LatencyHistogram {
    fine: [u32; FINE_BUCKETS],
    /// Every value (count, sum, min, max, and the ranks beyond the fine range).
    all: Histogram,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self {
            fine: [0; FINE_BUCKETS],
            all: Histogram::default(),
        }
    }
}

impl LatencyHistogram {
    pub fn record(&mut self, v_ns: u64) {
        if v_ns < FINE_LIMIT_NS {
            let b = (v_ns / 1000) as usize;
            self.fine[b] = self.fine[b].saturating_add(1);
        }
        self.all.record(v_ns);
    }

    pub fn count(&self) -> u64 {
        self.all.count
    }

    /// The `q` quantile: a whole µs (the lower edge of its 1 µs bucket) below 200 µs,
    /// the coarse histogram's upper bucket edge above.
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.all.count == 0 {
            return 0;
        }
        let rank = rank_of(q, self.all.count);
        let mut seen = 0u64;
        for (i, &c) in self.fine.iter().enumerate() {
            seen += c as u64;
            if seen >= rank {
                return i as u64 * 1000;
            }
        }
        self.all.quantile_ns(q)
    }

    pub fn summary(&self) -> Summary {
        let us = |ns: u64| ns as f64 / 1000.0;
        Summary {
            p50_us: us(self.quantile_ns(0.5)),
            p99_us: us(self.quantile_ns(0.99)),
            p999_us: us(self.quantile_ns(0.999)),
            ..self.all.summary()
        }
    }
}

/// A histogram as the socket reports it, µs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Summary {
    pub count: u64,
    pub mean_us: f64,
    pub min_us: f64,
    pub p50_us: f64,
    pub p99_us: f64,
    pub p999_us: f64,
    pub max_us: f64,
}

/// Everything the loop measures about itself.
#[derive(Clone, Copy, Default)]
pub struct LoopStats {
    pub cycles: u64,
    /// Cycle start − its absolute deadline (`start + index × period`): what cyclictest
    /// reports as latency, in 1 µs buckets.
    pub wakeup_latency: LatencyHistogram,
    /// |time between successive cycle starts − the periods between their deadlines|:
    /// the jitter of the period (the first cycle has none).
    pub period_error: Histogram,
    /// The previous cycle's (index, start), for the period error.
    last_start: Option<(u64, u64)>,
    /// Time from cycle start to commands sent.
    pub compute: Histogram,
    /// Time in the bus's `receive` and `send` within a cycle (part of `compute`).
    pub bus_io: Histogram,
    /// Age of the oldest module's newest feedback at the cycle's start.
    pub feedback_age: Histogram,
    /// Cycles whose work ran past the next deadline (those periods are skipped).
    pub overruns: u64,
    /// Periods skipped after overruns.
    pub skipped_periods: u64,
    /// Module-cycles in which a module sent no new feedback.
    pub late_feedback: u64,
    /// Bus send or receive calls that failed (including lockstep timeouts).
    pub bus_errors: u64,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StatsReport {
    pub cycles: u64,
    pub wakeup_latency: Summary,
    pub period_error: Summary,
    pub compute: Summary,
    /// Time in the bus's `receive` and `send` per cycle.
    pub bus_io: Summary,
    pub feedback_age: Summary,
    pub overruns: u64,
    pub skipped_periods: u64,
    pub late_feedback: u64,
    pub bus_errors: u64,
}

impl LoopStats {
    /// A cycle's start (`start_ns` on the loop's clock, `lateness_ns` after its
    /// deadline) into the wake-up latency and the period error.
    pub fn record_start(&mut self, index: u64, start_ns: u64, lateness_ns: u64, period_ns: u64) {
        self.wakeup_latency.record(lateness_ns);
        if let Some((last_index, last_ns)) = self.last_start {
            let expected = index.saturating_sub(last_index) * period_ns;
            self.period_error
                .record(start_ns.saturating_sub(last_ns).abs_diff(expected));
        }
        self.last_start = Some((index, start_ns));
    }

    pub fn report(&self) -> StatsReport {
        StatsReport {
            cycles: self.cycles,
            wakeup_latency: self.wakeup_latency.summary(),
            period_error: self.period_error.summary(),
            compute: self.compute.summary(),
            bus_io: self.bus_io.summary(),
            feedback_age: self.feedback_age.summary(),
            overruns: self.overruns,
            skipped_periods: self.skipped_periods,
            late_feedback: self.late_feedback,
            bus_errors: self.bus_errors,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_monotonic_and_tight() {
        let mut prev = 0;
        for v in (0..5_000_000u64).step_by(997) {
            let b = bucket_of(v);
            assert!(b >= prev, "bucket order at {v}");
            prev = b;
            assert!(bucket_upper(b) >= v, "{v} above its bucket's upper edge");
            assert!(
                bucket_upper(b) as f64 <= v as f64 * 1.125 + 1.0,
                "bucket too wide at {v}"
            );
        }
    }

    #[test]
    fn quantiles_of_a_uniform_sample() {
        let mut h = Histogram::default();
        for v in 1..=100_000u64 {
            h.record(v * 10);
        }
        let p50 = h.quantile_ns(0.5) as f64;
        assert!((p50 - 500_000.0).abs() / 500_000.0 < 0.13, "p50 {p50}");
        assert_eq!(h.quantile_ns(1.0), 1_000_000);
        let s = h.summary();
        assert_eq!(s.count, 100_000);
        assert!((s.mean_us - 500.005).abs() < 1e-6);
        assert_eq!(s.max_us, 1000.0);
    }

    #[test]
    fn latency_quantiles_are_whole_microseconds_below_200_and_coarse_above() {
        let mut h = LatencyHistogram::default();
        // 990 samples at 14.3-14.9 µs, 9 at 37.5 µs, one at 263 µs: as cyclictest counts
        // them, p50 and p99 are 14 (the 990th sample is the last at 14), p99.5 is 37,
        // and the maximum lies beyond the fine range.
        for i in 0..990u64 {
            h.record(14_300 + i % 7 * 100);
        }
        for _ in 0..9 {
            h.record(37_500);
        }
        h.record(263_000);
        assert_eq!(h.count(), 1000);
        assert_eq!(h.quantile_ns(0.5), 14_000);
        assert_eq!(h.quantile_ns(0.99), 14_000);
        assert_eq!(h.quantile_ns(0.995), 37_000);
        assert_eq!(
            h.quantile_ns(1.0),
            263_000,
            "beyond 200 µs: the exact maximum caps it"
        );
        let s = h.summary();
        assert_eq!((s.p50_us, s.max_us, s.min_us), (14.0, 263.0, 14.3));
    }

    #[test]
    fn the_period_error_is_the_interval_jitter_and_the_latency_the_lateness() {
        let mut s = LoopStats::default();
        let period = 1_000_000;
        // Every cycle 20 µs late: latency 20 µs each, yet the period is exact.
        for i in 0..10u64 {
            s.record_start(i, i * period + 20_000, 20_000, period);
        }
        assert_eq!(s.wakeup_latency.count(), 10);
        assert_eq!(s.period_error.count(), 9, "the first cycle has no period");
        assert_eq!(s.period_error.quantile_ns(1.0), 0);
        assert_eq!(s.wakeup_latency.quantile_ns(0.5), 20_000);
        // One cycle 50 µs late, then two periods skipped: the intervals around it err
        // by 30 µs, and a skip is not an error.
        s.record_start(10, 10 * period + 50_000, 50_000, period);
        s.record_start(13, 13 * period + 20_000, 20_000, period);
        assert_eq!(s.period_error.quantile_ns(1.0), 30_000);
        assert_eq!(s.period_error.count(), 11);
    }

    #[test]
    fn huge_values_land_in_the_last_bucket() {
        let mut h = Histogram::default();
        h.record(u64::MAX / 2);
        assert_eq!(h.quantile_ns(0.5), u64::MAX / 2);
    }
}
