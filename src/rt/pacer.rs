//! Pacing of the loop: real time on absolute deadlines, or lockstep with the
//! emulator (each cycle waits for the feedback of the next simulated period, so
//! tests and experiments run as fast as the machine allows and deterministically).
use crate::bus::FeedbackWait;
use crate::rt::sys;

/// One cycle as the pacer hands it to the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cycle {
    pub index: u64,
    /// Nominal loop time of this cycle, ns since the loop started: what controllers see.
    pub t_ns: u64,
    /// The clock feedback ages are measured on, ns since the loop started: the real
    /// wake-up time in real time, the nominal time in lockstep (simulated time).
    pub clock_ns: u64,
    /// How late the cycle started after its deadline, ns (0 in lockstep).
    pub lateness_ns: u64,
    /// Periods skipped before this cycle because the previous one overran.
    pub skipped: u64,
}

pub trait Pacer: Send {
    fn period_ns(&self) -> u64;
    /// Wait for the next cycle and return it.
    fn next_cycle(&mut self) -> Cycle;
    /// How the bus waits for this cycle's feedback.
    fn feedback_wait(&self, cycle: &Cycle, last_module_time_us: Option<u64>) -> FeedbackWait;
    /// Monotonic ns since the loop started, for measuring compute time.
    fn elapsed_ns(&self) -> u64;

    /// The CLOCK_MONOTONIC instant of loop time 0, where loop time runs with it (real
    /// time; `None` in lockstep, whose time is simulated): how a time stamped outside
    /// becomes loop time.
    fn epoch_monotonic_ns(&self) -> Option<u64> {
        None
    }
}

/// Absolute deadlines with `clock_nanosleep(TIMER_ABSTIME)`. When a cycle overruns
/// past the next deadline, the missed periods are skipped (not run back to back),
/// as ros2_control does. With a busy-wait, the sleep ends that long before the
/// deadline and the rest is spun on the clock, so the wake-up latency (up to that
/// long) is spent before the deadline instead of after it.
pub struct RealTimePacer {
    period_ns: u64,
    start_ns: u64,
    next_index: u64,
    busy_wait_ns: u64,
}

impl RealTimePacer {
    pub fn new(period_ns: u64) -> Self {
        Self::with_busy_wait(period_ns, 0)
    }

    /// Sleep until `busy_wait_ns` before each deadline, then spin until it.
    pub fn with_busy_wait(period_ns: u64, busy_wait_ns: u64) -> Self {
        Self {
            period_ns,
            start_ns: sys::monotonic_ns(),
            next_index: 0,
            busy_wait_ns: busy_wait_ns.min(period_ns),
        }
    }
}

impl Pacer for RealTimePacer {
    fn period_ns(&self) -> u64 {
        self.period_ns
    }

    fn next_cycle(&mut self) -> Cycle {
        let now = sys::monotonic_ns() - self.start_ns;
        let mut index = self.next_index;
        let mut skipped = 0;
        // Overrun: the deadline of `index` already lies a whole period behind; skip to
        // the latest deadline not yet passed by more than one period.
        let latest = now / self.period_ns;
        if latest > index {
            skipped = latest - index;
            index = latest;
        }
        let deadline = self.start_ns + index * self.period_ns;
        let woke = if self.busy_wait_ns == 0 {
            sys::sleep_until_ns(deadline);
            sys::monotonic_ns()
        } else {
            sys::sleep_until_ns(deadline.saturating_sub(self.busy_wait_ns));
            sys::spin_until_ns(deadline)
        };
        self.next_index = index + 1;
        Cycle {
            index,
            t_ns: index * self.period_ns,
            clock_ns: woke - self.start_ns,
            lateness_ns: woke.saturating_sub(deadline),
            skipped,
        }
    }

    fn feedback_wait(&self, _cycle: &Cycle, _last: Option<u64>) -> FeedbackWait {
        FeedbackWait::None
    }

    fn elapsed_ns(&self) -> u64 {
        sys::monotonic_ns() - self.start_ns
    }

    fn epoch_monotonic_ns(&self) -> Option<u64> {
        Some(self.start_ns)
    }
}

/// Lockstep: no sleeping; the bus blocks until the emulator has advanced one period.
pub struct LockstepPacer {
    period_ns: u64,
    start_ns: u64,
    next_index: u64,
    timeout_ns: u64,
}

impl LockstepPacer {
    pub fn new(period_ns: u64, timeout_ns: u64) -> Self {
        Self {
            period_ns,
            start_ns: sys::monotonic_ns(),
            next_index: 0,
            timeout_ns,
        }
    }
}

impl Pacer for LockstepPacer {
    fn period_ns(&self) -> u64 {
        self.period_ns
    }

    fn next_cycle(&mut self) -> Cycle {
        let index = self.next_index;
        self.next_index += 1;
        let t_ns = index * self.period_ns;
        Cycle {
            index,
            t_ns,
            clock_ns: t_ns,
            lateness_ns: 0,
            skipped: 0,
        }
    }

    fn feedback_wait(&self, _cycle: &Cycle, last_module_time_us: Option<u64>) -> FeedbackWait {
        // The first cycle takes the feedback modules send when configured; every later
        // one waits for the step after the newest seen.
        let min_module_time_us = match last_module_time_us {
            None => 0,
            Some(t) => t + self.period_ns / 1000,
        };
        FeedbackWait::Lockstep {
            min_module_time_us,
            timeout_ns: self.timeout_ns,
        }
    }

    fn elapsed_ns(&self) -> u64 {
        sys::monotonic_ns() - self.start_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lockstep_cycles_advance_by_one_period_and_wait_for_the_next_step() {
        let mut p = LockstepPacer::new(1_000_000, 5);
        let c0 = p.next_cycle();
        let c1 = p.next_cycle();
        assert_eq!((c0.t_ns, c1.t_ns, c1.index), (0, 1_000_000, 1));
        assert_eq!(c1.clock_ns, c1.t_ns);
        assert_eq!(
            p.feedback_wait(&c0, None),
            FeedbackWait::Lockstep {
                min_module_time_us: 0,
                timeout_ns: 5
            }
        );
        assert_eq!(
            p.feedback_wait(&c1, Some(7000)),
            FeedbackWait::Lockstep {
                min_module_time_us: 8000,
                timeout_ns: 5
            }
        );
    }

    #[test]
    fn real_time_cycles_keep_nominal_time_and_skip_missed_periods() {
        let mut p = RealTimePacer::new(1_000_000);
        let c0 = p.next_cycle();
        assert_eq!(c0.t_ns, c0.index * 1_000_000);
        // Simulate a long overrun: the next cycle must not try to catch up period by period.
        std::thread::sleep(std::time::Duration::from_millis(5));
        let c1 = p.next_cycle();
        assert!(c1.index > c0.index + 1, "overrun periods are skipped");
        assert_eq!(c1.skipped, c1.index - c0.index - 1);
        assert_eq!(c1.t_ns, c1.index * 1_000_000);
    }

    #[test]
    fn busy_waiting_cycles_start_at_or_after_their_deadline() {
        let mut p = RealTimePacer::with_busy_wait(1_000_000, 200_000);
        let mut last = 0;
        for _ in 0..20 {
            let c = p.next_cycle();
            // Never early: lateness is measured from the deadline, and clock_ns is the
            // real start, so it is at least the nominal time.
            assert!(c.clock_ns >= c.t_ns);
            assert_eq!(c.lateness_ns, c.clock_ns - c.t_ns);
            assert!(c.index >= last);
            last = c.index + 1;
        }
    }
}
