//! The gait clock: the time the gait side of the loop (the selector, its blends and
//! fades, the driving controller) runs on. It advances with the loop's time at rate 1
//! until a **controlled stop** (the station's dead-man, `gait.stop`) ramps its rate to 0
//! within a short, given time: every joint set-point is a function of this clock, so the
//! whole body comes to rest within that time whatever the blend time, with no jump and
//! a bounded deceleration (the rate follows the daemon's smoothstep, C1). `gait.resume`
//! ramps it back up the same way. Time is an argument, nothing allocates.
//!
//! While the rate is 1 and no ramp runs, the clock reads `t − offset` with `offset`
//! constant (0 until the first stop), so a loop that is never stopped runs its gaits on
//! exactly the loop's time, bit for bit.

use crate::gait::smoothstep;

/// Shortest and longest controlled stop (and restart), s.
pub const STOP_TIME_RANGE_S: (f64, f64) = (0.05, 2.0);
/// A stop's or restart's time unless one is given, s: about a quarter of a slow
/// gait's cycle; a 1 rad/s joint decelerates at 5 rad/s² at most.
pub const DEFAULT_STOP_S: f64 = 0.3;

/// What the gait clock is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    /// At full rate.
    #[default]
    Running,
    /// Ramping down to rest.
    Stopping,
    /// At rest: the set-points stand still until `gait.resume`.
    Stopped,
    /// Ramping back up to full rate.
    Starting,
}

#[derive(Debug, Clone, Copy)]
struct Ramp {
    from: f64,
    to: f64,
    start_s: f64,
    duration_s: f64,
}

impl Ramp {
    fn rate(&self, t_s: f64) -> f64 {
        let (w, _) = smoothstep(t_s, self.start_s, self.duration_s);
        self.from + (self.to - self.from) * w
    }

    fn done(&self, t_s: f64) -> bool {
        t_s >= self.start_s + self.duration_s
    }
}

/// The gait side's time (see the module's documentation).
#[derive(Debug, Clone, Copy, Default)]
pub struct GaitClock {
    /// Loop time minus gait time, s: grows only while the rate is below 1.
    offset_s: f64,
    /// The loop time and rate of the last advance.
    last: Option<(f64, f64)>,
    ramp: Option<Ramp>,
    /// The rate when no ramp runs: 1 or 0.
    rate: f64,
}

impl GaitClock {
    pub fn new() -> Self {
        Self {
            rate: 1.0,
            ..Self::default()
        }
    }

    /// The gait time at loop time `t_s` (call once per cycle, `t_s` not decreasing).
    pub fn advance(&mut self, t_s: f64) -> f64 {
        let rate = self.rate_at(t_s);
        if let Some((last_t, last_rate)) = self.last {
            let dt = (t_s - last_t).max(0.0);
            // Trapezoid on the rate: exact where it is constant.
            let lag = 1.0 - 0.5 * (rate + last_rate);
            if lag != 0.0 {
                self.offset_s += lag * dt;
            }
        }
        if let Some(r) = self.ramp
            && r.done(t_s)
        {
            self.rate = r.to;
            self.ramp = None;
        }
        self.last = Some((t_s, rate));
        t_s - self.offset_s
    }

    /// The rate at loop time `t_s`, 0..1.
    fn rate_at(&self, t_s: f64) -> f64 {
        self.ramp.map_or(self.rate, |r| r.rate(t_s))
    }

    /// The rate of the last advance.
    pub fn rate(&self) -> f64 {
        self.last.map_or(self.rate, |(_, r)| r)
    }

    pub fn motion(&self) -> Motion {
        match self.ramp {
            Some(r) if r.to < r.from => Motion::Stopping,
            Some(_) => Motion::Starting,
            None if self.rate == 0.0 => Motion::Stopped,
            None => Motion::Running,
        }
    }

    /// Brings the gait to rest within `within_s` from loop time `t_s` (from whatever
    /// rate it has now; at rest already: nothing changes).
    pub fn stop(&mut self, t_s: f64, within_s: f64) {
        self.ramp_to(t_s, 0.0, within_s);
    }

    /// Brings it back to full rate within `within_s`.
    pub fn resume(&mut self, t_s: f64, within_s: f64) {
        self.ramp_to(t_s, 1.0, within_s);
    }

    /// Full rate at once: the gait restarts from a frozen, measured pose (a resync
    /// blends in from rest by itself).
    pub fn run(&mut self) {
        self.ramp = None;
        self.rate = 1.0;
        if let Some((t, _)) = self.last {
            self.last = Some((t, 1.0));
        }
    }

    fn ramp_to(&mut self, t_s: f64, to: f64, within_s: f64) {
        let from = self.rate_at(t_s);
        if from == to {
            self.ramp = None;
            self.rate = to;
            return;
        }
        // A partial ramp takes its share of the time, so the deceleration stays bounded.
        let duration_s = (within_s * (to - from).abs()).max(1e-3);
        self.ramp = Some(Ramp {
            from,
            to,
            start_s: t_s,
            duration_s,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1e-3;

    #[test]
    fn a_clock_never_stopped_reads_the_loops_time_exactly() {
        let mut c = GaitClock::new();
        for i in 0..5000u64 {
            let t = i as f64 * DT;
            assert_eq!(c.advance(t).to_bits(), t.to_bits());
        }
        assert_eq!(c.motion(), Motion::Running);
    }

    #[test]
    fn a_stop_comes_to_rest_within_its_time_and_resume_restarts_smoothly() {
        let mut c = GaitClock::new();
        let mut t = 0.0;
        let mut tau = c.advance(t);
        let mut last_rate = 1.0;
        for i in 1..=3000u64 {
            t = i as f64 * DT;
            if i == 1000 {
                c.stop(t, 0.3);
                assert_eq!(c.motion(), Motion::Stopping);
            }
            let next = c.advance(t);
            let rate = (next - tau) / DT;
            assert!((-1e-12..=1.0 + 1e-12).contains(&rate), "rate {rate} at {t}");
            // Smooth: the rate changes by at most 1.5/0.3 per second.
            assert!((rate - last_rate).abs() <= 1.5 / 0.3 * DT + 1e-9);
            if t >= 1.0 + 0.3 + DT {
                assert_eq!(next, tau, "at rest from 1.3 s on, not at {t}");
            }
            (tau, last_rate) = (next, rate);
        }
        assert_eq!(c.motion(), Motion::Stopped);
        // Over the ramp the clock went half the ramp's time (the smoothstep's mean).
        assert!((tau - (1.0 + 0.15)).abs() < 1e-3, "{tau}");
        c.resume(t, 0.3);
        assert_eq!(c.motion(), Motion::Starting);
        for i in 3001..=4000u64 {
            t = i as f64 * DT;
            c.advance(t);
        }
        assert_eq!(c.motion(), Motion::Running);
        assert!((c.rate() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn stopping_a_stopped_clock_or_running_a_running_one_changes_nothing() {
        let mut c = GaitClock::new();
        c.resume(0.0, 0.3);
        assert_eq!(c.motion(), Motion::Running);
        c.stop(0.0, 0.3);
        c.advance(0.0);
        c.advance(0.5);
        assert_eq!(c.motion(), Motion::Stopped);
        c.stop(0.5, 0.3);
        assert_eq!(c.motion(), Motion::Stopped);
        c.run();
        assert_eq!(c.motion(), Motion::Running);
    }
}
