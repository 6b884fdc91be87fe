//! Each module's clock against the host's, so that feedback which left the module late
//! (or sat in a queue on the way) shows its age, even when it arrives at a steady rate.
//!
//! A feedback stamped `module_time_us` by the module and arriving at `rx` (host clock)
//! gives the sample `rx − module_time = offset + delay`, with `delay ≥ 0`. The offset
//! between the two clocks is the **lower envelope** of the samples: the least-delayed
//! feedback sets it, and it may rise no faster than clocks drift ([`MAX_DRIFT`]), so a
//! delay that appears shows as `sample − envelope` at once. The drift itself is
//! estimated from the envelope (its slope over the session) and carried forward, so a
//! module whose crystal runs slow does not look ever later.
//!
//! What this cannot see is a delay that was there from the first feedback on (it is
//! indistinguishable from the offset): the command round trip (`command_age_ns`, from
//! `last_command_seq`) bounds that one. The daemon takes the older of the two.

/// Fastest drift allowed between a module's clock and the host's beyond the estimated
/// one: crystals stay within 100 ppm; 500 ppm leaves room for the estimate's error.
pub(super) const MAX_DRIFT: f64 = 500e-6;
/// Least time between the envelope points the drift is estimated over, ns.
const DRIFT_BASELINE_NS: u64 = 2_000_000_000;

#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ModuleClock {
    /// The envelope's last point: (host time, offset ns); `None` before the first.
    anchor: Option<(u64, i64)>,
    /// The first envelope point of the session, for the drift estimate.
    first: Option<(u64, i64)>,
    /// Estimated drift, ns of offset per ns of host time.
    drift: f64,
}

impl ModuleClock {
    /// Take one feedback; returns how late it was on arrival, ns.
    pub(crate) fn observe(&mut self, rx_ns: u64, module_time_us: u64) -> u64 {
        let sample = rx_ns as i64 - (module_time_us.saturating_mul(1000)) as i64;
        let Some((at, offset)) = self.anchor else {
            self.anchor = Some((rx_ns, sample));
            self.first = Some((rx_ns, sample));
            return 0;
        };
        let dt = rx_ns.saturating_sub(at) as f64;
        let expected = offset as f64 + self.drift * dt;
        let ceiling = expected + MAX_DRIFT * dt;
        if (sample as f64) <= ceiling {
            // On or below the envelope: this feedback is (nearly) undelayed.
            self.anchor = Some((rx_ns, sample.min(ceiling as i64)));
            self.update_drift(rx_ns, sample);
            (sample as f64 - expected).max(0.0) as u64
        } else {
            (sample as f64 - expected) as u64
        }
    }

    /// Estimated drift of the module's clock, parts per million (positive: it runs
    /// slow against the host's).
    #[cfg(test)]
    pub(crate) fn drift_ppm(&self) -> f64 {
        self.drift * 1e6
    }

    fn update_drift(&mut self, rx_ns: u64, sample: i64) {
        if let Some((t0, o0)) = self.first {
            let span = rx_ns.saturating_sub(t0);
            if span >= DRIFT_BASELINE_NS {
                let d = (sample - o0) as f64 / span as f64;
                self.drift = d.clamp(-MAX_DRIFT, MAX_DRIFT);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    /// Feedback every ms for `secs`, sent at module time `t·(1 − drift)` (µs), arriving
    /// `delay(t)` later; returns the ages.
    fn run(secs: u64, drift: f64, delay: impl Fn(u64) -> u64) -> Vec<u64> {
        let mut c = ModuleClock::default();
        let offset = 5_000_000_000u64; // the host's clock started earlier
        (0..secs * 1000)
            .map(|k| {
                let t = k * MS;
                let module_us = ((t as f64) * (1.0 - drift) / 1000.0) as u64;
                c.observe(offset + t + delay(t), module_us)
            })
            .collect()
    }

    #[test]
    fn steady_feedback_is_fresh_even_with_drift() {
        for drift in [0.0, 80e-6, -80e-6] {
            let ages = run(20, drift, |_| 30_000);
            let worst = ages.iter().skip(3000).max().unwrap();
            assert!(*worst < 100_000, "drift {drift}: up to {worst} ns");
        }
    }

    #[test]
    fn a_delay_that_appears_shows_at_once() {
        let ages = run(10, 50e-6, |t| if t >= 5_000 * MS { 60 * MS } else { 0 });
        assert!(ages[4_999] < MS);
        for (k, &a) in ages.iter().enumerate().skip(5_000) {
            assert!(
                a > 58 * MS && a < 62 * MS,
                "at {k} ms: {a} ns for a 60 ms delay"
            );
        }
    }

    #[test]
    fn the_drift_is_estimated() {
        let mut c = ModuleClock::default();
        for k in 0..5000u64 {
            let t = k * MS;
            c.observe(t, ((t as f64) * (1.0 - 100e-6) / 1000.0) as u64);
        }
        assert!((c.drift_ppm() - 100.0).abs() < 5.0, "{}", c.drift_ppm());
    }

    #[test]
    fn jitter_on_the_way_reads_as_jitter() {
        // Up to 2 ms of random-ish queueing: the ages stay within it.
        let ages = run(5, 0.0, |t| (t / MS * 7919) % (2 * MS));
        assert!(ages.iter().all(|&a| a <= 2 * MS + 1000));
    }
}
