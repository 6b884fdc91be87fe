//! One operator drives at a time. The first client to send a driving request holds the
//! drive until it stops (a stop from anyone: `hold`, `limp`, `estop`, `gait.stop`, the
//! dead-man), goes away, or sends no driving request for the lease's timeout; another
//! client's driving requests are refused meanwhile (`DRIVEN_BY_OTHER`, naming the
//! driver) until it takes over explicitly (`take_over`). Socket connections, Foxglove
//! clients and any later input meet the same lease: it is the operator API's
//! ([`crate::operator::Act::drives`], [`crate::operator::Act::stops`]).
//! Stops are never refused: whoever sees the robot may stop it.

use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use super::error::{OperatorError, code};

/// How long a driver keeps the drive without driving, unless configured.
pub const DEFAULT_DRIVER_TIMEOUT: Duration = Duration::from_secs(5);

#[derive(Debug, Clone)]
struct Holder {
    who: String,
    last: Instant,
}

/// Who drives (see the module's documentation).
#[derive(Debug)]
pub struct DriverLease {
    holder: Mutex<Option<Holder>>,
    timeout: Duration,
}

/// Who drives now, for `status`.
#[derive(Debug, Clone, PartialEq)]
pub struct Driver {
    pub who: String,
    /// Since its last driving request, s.
    pub idle_s: f64,
    /// When the lease lapses unless it drives again, s.
    pub expires_in_s: f64,
}

impl DriverLease {
    pub fn new(timeout: Duration) -> Self {
        Self {
            holder: Mutex::default(),
            timeout,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Option<Holder>> {
        // Every update leaves a whole value: a poisoned lock still holds a sound one.
        self.holder.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// `who` drives at `now`: it holds the drive, or takes a free or lapsed one;
    /// refused while another client holds it.
    pub fn claim(&self, who: &str, now: Instant) -> Result<(), OperatorError> {
        let mut h = self.lock();
        match h.as_mut() {
            Some(held) if held.who != who && now.duration_since(held.last) < self.timeout => {
                let left = self.timeout - now.duration_since(held.last);
                Err(OperatorError::new(
                    code::DRIVEN_BY_OTHER,
                    format!(
                        "refused: {} is driving (its drive lapses {:.1} s after its last \
                         driving request); call `take_over` to drive instead",
                        held.who,
                        left.as_secs_f64()
                    ),
                ))
            }
            Some(held) if held.who == who => {
                held.last = now;
                Ok(())
            }
            _ => {
                *h = Some(Holder {
                    who: who.to_owned(),
                    last: now,
                });
                Ok(())
            }
        }
    }

    /// `who` takes the drive, whoever held it; returns who did (if anyone else).
    pub fn take_over(&self, who: &str, now: Instant) -> Option<String> {
        let before = self.lock().replace(Holder {
            who: who.to_owned(),
            last: now,
        });
        before
            .filter(|b| b.who != who && now.duration_since(b.last) < self.timeout)
            .map(|b| b.who)
    }

    /// `who` stops driving (it went away); nothing if it did not hold the drive.
    pub fn release(&self, who: &str) {
        let mut h = self.lock();
        if h.as_ref().is_some_and(|held| held.who == who) {
            *h = None;
        }
    }

    /// The robot was stopped: the drive is free.
    pub fn stopped(&self) {
        *self.lock() = None;
    }

    /// Who drives at `now`, if anyone.
    pub fn driver(&self, now: Instant) -> Option<Driver> {
        let h = self.lock();
        let held = h.as_ref()?;
        let idle = now.duration_since(held.last);
        (idle < self.timeout).then(|| Driver {
            who: held.who.clone(),
            idle_s: idle.as_secs_f64(),
            expires_in_s: (self.timeout - idle).as_secs_f64(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_to_drive_holds_it_until_it_lapses_stops_or_leaves() {
        let t0 = Instant::now();
        let s = |x: f64| t0 + Duration::from_secs_f64(x);
        let lease = DriverLease::new(Duration::from_secs(5));
        lease.claim("a", s(0.0)).unwrap();
        let e = lease.claim("b", s(1.0)).unwrap_err();
        assert_eq!(e.code, code::DRIVEN_BY_OTHER);
        assert!(e.message.contains("a is driving") && e.message.contains("take_over"));
        lease.claim("a", s(4.0)).unwrap();
        assert!(lease.claim("b", s(8.0)).is_err(), "a drove again at 4 s");
        lease.claim("b", s(9.5)).unwrap();
        let holder = |at: f64| lease.driver(s(at)).map(|d| d.who);
        assert_eq!(holder(9.5).as_deref(), Some("b"));
        lease.release("a");
        assert_eq!(
            holder(9.6).as_deref(),
            Some("b"),
            "only the holder releases"
        );
        lease.release("b");
        lease.claim("a", s(10.0)).unwrap();
        lease.stopped();
        assert_eq!(lease.driver(s(10.0)), None);
    }

    #[test]
    fn taking_over_is_explicit_and_says_from_whom() {
        let t0 = Instant::now();
        let lease = DriverLease::new(Duration::from_secs(5));
        assert_eq!(lease.take_over("a", t0), None);
        assert_eq!(lease.take_over("b", t0), Some("a".to_owned()));
        assert!(lease.claim("a", t0).is_err());
        let d = lease.driver(t0).unwrap();
        assert_eq!(d.who, "b");
        assert!((d.expires_in_s - 5.0).abs() < 1e-9);
    }
}
