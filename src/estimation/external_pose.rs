//! The daemon's pose input: where the body is according to something outside it
//! (motion capture, visual odometry, a total station), as such sources give it: a
//! stamped position, perhaps an orientation, perhaps how good it is. Every source (the
//! control socket's `pose.external`, the ROS 2 node's `PoseStamped`) writes through one
//! [`PoseInput`], which turns the source's wall-clock stamp into loop time, so the
//! estimator can take the body's motion since the fix into account. The newest fix
//! waits in a triple buffer; the loop's [`ExternalFixEstimator`] takes it each cycle
//! without waiting, locking or allocating and reports it in the body estimate
//! ([`FixState`]). A fix that is not finite, whose orientation is not a rotation, or
//! whose stamp is in the future or too old, is refused with the reason and counted.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};

pub use crate::controller_interface::position::FixState;
use crate::controller_interface::{BodyEstimate, Estimator, Observation};

/// A fix stamped further ahead of the daemon's clock than this is refused, s.
pub const MAX_AHEAD_S: f64 = 0.05;
/// A fix older than this on arrival is refused, s.
pub const MAX_LATENCY_S: f64 = 5.0;

/// One fix as a source gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct ExternalFix {
    /// When it was measured, ns since the Unix epoch (the source's clock, assumed in
    /// step with the daemon's).
    pub stamp_unix_ns: u64,
    /// The tracked point in the source's world, m.
    pub position_m: [f64; 3],
    /// The tracked body's orientation in the source's world (w, x, y, z), if given.
    pub orientation_wxyz: Option<[f64; 4]>,
    /// The position's standard deviation, m, if given.
    pub position_sd_m: Option<f64>,
    /// Who sent it (logs, status).
    pub source: String,
}

/// A fix as the loop holds it (`Copy`: it crosses the triple buffer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// How many fixes the input has stored, this one included (0: none yet).
    pub number: u64,
    /// When it was measured, loop time, s.
    pub t_s: f64,
    pub position_m: [f64; 3],
    /// Normalised (w, x, y, z); `None`: the source gave none.
    pub orientation_wxyz: Option<[f64; 4]>,
    /// NaN: not given.
    pub position_sd_m: f64,
}

impl Fix {
    pub const NONE: Fix = Fix {
        number: 0,
        t_s: f64::NEG_INFINITY,
        position_m: [0.0; 3],
        orientation_wxyz: None,
        position_sd_m: f64::NAN,
    };
}

/// What the input counts.
#[derive(Debug, Default)]
pub struct PoseCounters {
    pub received: AtomicU64,
    pub refused: AtomicU64,
    /// The newest stored fix's arrival, ns since the Unix epoch (0: none).
    pub last_unix_ns: AtomicU64,
}

/// The sources' end, cheap to clone; writing takes a short lock only sources contend
/// for (the loop reads the other end).
#[derive(Clone)]
pub struct PoseInput {
    input: Arc<Mutex<triple_buffer::Input<Fix>>>,
    counters: Arc<PoseCounters>,
    /// CLOCK_MONOTONIC at loop time 0 (`None`: the loop's time is simulated).
    epoch_monotonic_ns: Option<u64>,
}

impl std::fmt::Debug for PoseInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PoseInput")
            .field("epoch_monotonic_ns", &self.epoch_monotonic_ns)
            .finish()
    }
}

impl PartialEq for PoseInput {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.input, &other.input)
    }
}

/// The loop's end.
pub struct PoseReader {
    output: triple_buffer::Output<Fix>,
}

/// A pose input for a loop whose time 0 was `epoch_monotonic_ns` (CLOCK_MONOTONIC;
/// `None` in lockstep: then only [`PoseInput::write_loop_time`] takes fixes).
pub fn pose_input(epoch_monotonic_ns: Option<u64>) -> (PoseInput, PoseReader) {
    let (input, output) = triple_buffer::triple_buffer(&Fix::NONE);
    (
        PoseInput {
            input: Arc::new(Mutex::new(input)),
            counters: Arc::default(),
            epoch_monotonic_ns,
        },
        PoseReader { output },
    )
}

fn realtime_and_monotonic_ns() -> (u64, u64) {
    let read = |clock| {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: a valid timespec; both clocks always exist on Linux.
        unsafe { libc::clock_gettime(clock, &mut ts) };
        ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
    };
    (read(libc::CLOCK_REALTIME), read(libc::CLOCK_MONOTONIC))
}

impl PoseInput {
    pub fn counters(&self) -> &Arc<PoseCounters> {
        &self.counters
    }

    /// Stores `fix` (its stamp turned into loop time), or refuses it with the reason.
    /// Answers the fix's loop time and how old it was on arrival, s.
    pub fn write(&self, fix: &ExternalFix) -> Result<(f64, f64), String> {
        let (now_unix, now_mono) = realtime_and_monotonic_ns();
        let Some(epoch) = self.epoch_monotonic_ns else {
            return self.refuse("the loop's time is simulated (lockstep): it has no wall clock");
        };
        let latency_s = (now_unix as f64 - fix.stamp_unix_ns as f64) * 1e-9;
        if latency_s < -MAX_AHEAD_S {
            return self.refuse(&format!(
                "the stamp is {:.3} s ahead of the daemon's clock",
                -latency_s
            ));
        }
        if latency_s > MAX_LATENCY_S {
            return self.refuse(&format!(
                "the stamp is {latency_s:.3} s old (at most {MAX_LATENCY_S} s)"
            ));
        }
        let t_s = (now_mono as f64 - epoch as f64) * 1e-9 - latency_s;
        self.write_loop_time(t_s, fix, now_unix)
            .map(|t| (t, latency_s))
    }

    /// Stores `fix` measured at loop time `t_s` (a simulated source, which knows the
    /// loop's time), or refuses it. `now_unix_ns` is when it arrived.
    pub fn write_loop_time(
        &self,
        t_s: f64,
        fix: &ExternalFix,
        now_unix_ns: u64,
    ) -> Result<f64, String> {
        let p = fix.position_m;
        if !(t_s.is_finite() && p.iter().all(|x| x.is_finite())) {
            return self.refuse("the position is not finite");
        }
        let orientation = match fix.orientation_wxyz {
            None => None,
            Some(q) => {
                let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                if !norm.is_finite() || (norm - 1.0).abs() > 0.1 {
                    return self.refuse(&format!("the orientation's norm is {norm:.3}, not 1"));
                }
                Some(q.map(|x| x / norm))
            }
        };
        let sd = match fix.position_sd_m {
            Some(sd) if !(sd.is_finite() && sd > 0.0) => {
                return self.refuse("position_sd_m must be a positive number");
            }
            Some(sd) => sd,
            None => f64::NAN,
        };
        let mut input = self.input.lock().unwrap_or_else(|e| e.into_inner());
        let number = self.counters.received.fetch_add(1, Relaxed) + 1;
        input.write(Fix {
            number,
            t_s,
            position_m: p,
            orientation_wxyz: orientation,
            position_sd_m: sd,
        });
        self.counters.last_unix_ns.store(now_unix_ns, Relaxed);
        Ok(t_s)
    }

    fn refuse<T>(&self, why: &str) -> Result<T, String> {
        self.counters.refused.fetch_add(1, Relaxed);
        Err(why.to_owned())
    }
}

impl PoseReader {
    /// The newest fix (`number` 0: none yet).
    pub fn latest(&mut self) -> Fix {
        *self.output.read()
    }
}

/// The loop's side: each cycle, the newest fix into the body estimate's `fix`. Runs
/// after the estimators of the body's own sensors; allocation-free.
pub struct ExternalFixEstimator {
    reader: PoseReader,
    latest: Fix,
}

impl ExternalFixEstimator {
    pub fn new(reader: PoseReader) -> Self {
        Self {
            reader,
            latest: Fix::NONE,
        }
    }

    /// The newest fix taken (`number` 0: none yet).
    pub fn latest(&self) -> Fix {
        self.latest
    }
}

impl Estimator for ExternalFixEstimator {
    fn update(&mut self, t_s: f64, _obs: &Observation<'_>, out: &mut BodyEstimate) {
        let f = self.reader.latest();
        self.latest = f;
        out.fix = if f.number == 0 {
            FixState::NONE
        } else {
            FixState {
                number: f.number,
                position_m: f.position_m,
                orientation_wxyz: f.orientation_wxyz,
                age_s: (t_s - f.t_s).max(0.0),
            }
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fix(stamp_unix_ns: u64, x: f64) -> ExternalFix {
        ExternalFix {
            stamp_unix_ns,
            position_m: [x, 2.0, 0.0],
            orientation_wxyz: Some([1.0, 0.0, 0.0, 0.0]),
            position_sd_m: Some(0.002),
            source: "test".into(),
        }
    }

    #[test]
    fn a_fix_becomes_loop_time_and_a_bad_one_is_refused() {
        let (now_unix, now_mono) = realtime_and_monotonic_ns();
        // The loop started 10 s ago; a fix measured 20 ms ago is at loop time ~9.98 s.
        let (input, mut reader) = pose_input(Some(now_mono - 10_000_000_000));
        let (t_s, latency) = input.write(&fix(now_unix - 20_000_000, 1.5)).unwrap();
        assert!((t_s - 9.98).abs() < 0.01, "{t_s}");
        assert!((latency - 0.02).abs() < 0.01, "{latency}");
        let f = reader.latest();
        assert_eq!((f.number, f.position_m[0]), (1, 1.5));
        assert_eq!(f.position_sd_m, 0.002);
        // Refused: ahead, too old, not finite, not a rotation, a bad deviation.
        assert!(input.write(&fix(now_unix + 1_000_000_000, 0.0)).is_err());
        assert!(input.write(&fix(now_unix - 60_000_000_000, 0.0)).is_err());
        assert!(input.write(&fix(now_unix, f64::NAN)).is_err());
        let mut q = fix(now_unix, 0.0);
        q.orientation_wxyz = Some([0.0; 4]);
        assert!(input.write(&q).unwrap_err().contains("norm"));
        q.orientation_wxyz = None;
        q.position_sd_m = Some(-1.0);
        assert!(input.write(&q).is_err());
        assert_eq!(reader.latest().number, 1, "the refused ones are not stored");
        let c = input.counters();
        assert_eq!((c.received.load(Relaxed), c.refused.load(Relaxed)), (1, 5));
        // Lockstep has no wall clock: only loop-time fixes.
        let (sim, mut r) = pose_input(None);
        assert!(sim.write(&fix(now_unix, 0.0)).is_err());
        sim.write_loop_time(3.0, &fix(0, 0.5), 0).unwrap();
        assert_eq!(r.latest().t_s, 3.0);
    }

    #[test]
    fn the_estimator_reports_the_newest_fix_and_its_age() {
        let (input, reader) = pose_input(None);
        let mut e = ExternalFixEstimator::new(reader);
        let mut out = BodyEstimate::NONE;
        let obs = Observation::NONE;
        e.update(1.0, &obs, &mut out);
        assert_eq!(out.fix, FixState::NONE);
        input.write_loop_time(0.9, &fix(0, 1.0), 0).unwrap();
        e.update(1.0, &obs, &mut out);
        assert_eq!(out.fix.number, 1);
        assert!((out.fix.age_s - 0.1).abs() < 1e-12);
        e.update(1.5, &obs, &mut out);
        assert!(
            (out.fix.age_s - 0.6).abs() < 1e-12,
            "it ages while no new one comes"
        );
    }
}
