//! Fault injection for the UDP emulator, deterministic from a seed:
//! - **loss**: each feedback datagram the emulator sends and each command it receives
//!   is dropped with probability `loss_pct / 100`;
//! - **delay**: feedback is held in a fixed-capacity queue until `delay_s` after it was
//!   produced (a full queue drops, and is counted);
//! - **silence**: module `k` answers nothing and hears nothing from time `t`,
//!   for `duration` or for good.
//!
//! Times are the simulation clock, so a lockstep run with faults is reproducible.

use std::collections::VecDeque;
use std::str::FromStr;

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Module `module` is silent from `start_s` for `duration_s` (forever when `None`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Silence {
    pub module: usize,
    pub start_s: f64,
    pub duration_s: Option<f64>,
}

impl Silence {
    pub fn covers(&self, module: usize, t_s: f64) -> bool {
        module == self.module
            && t_s >= self.start_s
            && self.duration_s.is_none_or(|d| t_s < self.start_s + d)
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultError {
    #[error("silence {0:?}: expected K@T or K@T+D (module index, start s, duration s)")]
    BadSilence(String),
    #[error("loss must be within 0..=100 %, got {0}")]
    BadLoss(f64),
    #[error("delay must be finite and >= 0 s, got {0}")]
    BadDelay(f64),
    #[error("silence refers to module {module}, but there are only {modules}")]
    NoSuchModule { module: usize, modules: usize },
}

impl FromStr for Silence {
    type Err = FaultError;
    /// `K@T[+D]`: module index K (0-based), start T s, optional duration D s.
    fn from_str(s: &str) -> Result<Self, FaultError> {
        let bad = || FaultError::BadSilence(s.to_owned());
        let (k, rest) = s.split_once('@').ok_or_else(bad)?;
        let (t, d) = match rest.split_once('+') {
            Some((t, d)) => (t, Some(d)),
            None => (rest, None),
        };
        let module = k.trim().parse().map_err(|_| bad())?;
        let start_s: f64 = t.trim().parse().map_err(|_| bad())?;
        let duration_s = d
            .map(|d| d.trim().parse::<f64>().map_err(|_| bad()))
            .transpose()?;
        let ok = start_s.is_finite()
            && start_s >= 0.0
            && duration_s.is_none_or(|d| d.is_finite() && d >= 0.0);
        if !ok {
            return Err(bad());
        }
        Ok(Silence {
            module,
            start_s,
            duration_s,
        })
    }
}

/// What to break, and the seed that makes it reproducible.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultConfig {
    /// Loss probability of each feedback sent and each command received, %.
    pub loss_pct: f64,
    /// Extra latency of every feedback, s.
    pub delay_s: f64,
    pub silences: Vec<Silence>,
    pub seed: u64,
    /// Feedback datagrams the delay queue can hold.
    pub delay_capacity: usize,
}

impl Default for FaultConfig {
    fn default() -> Self {
        Self {
            loss_pct: 0.0,
            delay_s: 0.0,
            silences: Vec::new(),
            seed: 0,
            delay_capacity: 8192,
        }
    }
}

/// The fault injector.
#[derive(Debug, Clone)]
pub struct Faults {
    config: FaultConfig,
    loss_p: f64,
    rng: Pcg64,
}

impl Faults {
    pub fn new(config: FaultConfig, modules: usize) -> Result<Self, FaultError> {
        if !(0.0..=100.0).contains(&config.loss_pct) {
            return Err(FaultError::BadLoss(config.loss_pct));
        }
        if !(config.delay_s.is_finite() && config.delay_s >= 0.0) {
            return Err(FaultError::BadDelay(config.delay_s));
        }
        if let Some(s) = config.silences.iter().find(|s| s.module >= modules) {
            return Err(FaultError::NoSuchModule {
                module: s.module,
                modules,
            });
        }
        Ok(Self {
            loss_p: config.loss_pct / 100.0,
            rng: Pcg64::seed_from_u64(config.seed),
            config,
        })
    }

    pub fn config(&self) -> &FaultConfig {
        &self.config
    }

    /// Draw whether the next datagram is lost (no draw when loss is off).
    pub fn lose(&mut self) -> bool {
        self.loss_p > 0.0 && self.rng.random_bool(self.loss_p)
    }

    /// True when module `module` is silent at `t_s`.
    pub fn is_silent(&self, module: usize, t_s: f64) -> bool {
        self.config.silences.iter().any(|s| s.covers(module, t_s))
    }

    pub fn delay_s(&self) -> f64 {
        self.config.delay_s
    }
}

/// A FIFO of items released at a fixed delay, sized once (never grows).
/// With a constant delay, FIFO order is release order.
#[derive(Debug, Clone)]
pub struct DelayQueue<T> {
    items: VecDeque<(f64, T)>,
    capacity: usize,
}

impl<T> DelayQueue<T> {
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            items: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Hold `item` until `release_s`; gives it back when the queue is full.
    pub fn push(&mut self, release_s: f64, item: T) -> Result<(), T> {
        if self.items.len() >= self.capacity {
            return Err(item);
        }
        self.items.push_back((release_s, item));
        Ok(())
    }

    /// The oldest item whose release time has come.
    pub fn pop_due(&mut self, now_s: f64) -> Option<T> {
        if self.items.front().is_some_and(|(at, _)| *at <= now_s) {
            self.items.pop_front().map(|(_, item)| item)
        } else {
            None
        }
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn faults(loss_pct: f64, seed: u64) -> Faults {
        Faults::new(
            FaultConfig {
                loss_pct,
                seed,
                ..FaultConfig::default()
            },
            4,
        )
        .unwrap()
    }

    #[test]
    fn parse_silence() {
        let s: Silence = "3@2.5".parse().unwrap();
        assert_eq!(
            s,
            Silence {
                module: 3,
                start_s: 2.5,
                duration_s: None
            }
        );
        let s: Silence = "0@1+0.5".parse().unwrap();
        assert_eq!(s.duration_s, Some(0.5));
        for bad in ["", "3", "x@1", "1@", "1@2+", "1@-1", "1@nan", "1@1+-2"] {
            assert!(bad.parse::<Silence>().is_err(), "{bad} parsed");
        }
    }

    #[test]
    fn silence_window() {
        let s: Silence = "1@2+0.5".parse().unwrap();
        assert!(!s.covers(1, 1.99));
        assert!(s.covers(1, 2.0));
        assert!(s.covers(1, 2.49));
        assert!(!s.covers(1, 2.5));
        assert!(!s.covers(0, 2.2));
        let forever: Silence = "1@2".parse().unwrap();
        assert!(forever.covers(1, 1e6));
        let f = Faults::new(
            FaultConfig {
                silences: vec![s],
                ..FaultConfig::default()
            },
            2,
        )
        .unwrap();
        assert!(f.is_silent(1, 2.1));
        assert!(!f.is_silent(0, 2.1));
    }

    #[test]
    fn loss_rate_is_about_right_and_seeded() {
        let mut f = faults(20.0, 1);
        let lost = (0..10_000).filter(|_| f.lose()).count();
        assert!((1700..2300).contains(&lost), "{lost}");
        let draw = |seed| {
            let mut f = faults(50.0, seed);
            (0..64).map(|_| f.lose()).collect::<Vec<_>>()
        };
        assert_eq!(draw(5), draw(5));
        assert_ne!(draw(5), draw(6));
        let mut none = faults(0.0, 1);
        assert!((0..1000).all(|_| !none.lose()));
        let mut all = faults(100.0, 1);
        assert!((0..1000).all(|_| all.lose()));
    }

    #[test]
    fn bad_configs_refused() {
        assert!(
            Faults::new(
                FaultConfig {
                    loss_pct: 101.0,
                    ..FaultConfig::default()
                },
                1
            )
            .is_err()
        );
        assert!(
            Faults::new(
                FaultConfig {
                    delay_s: -1.0,
                    ..FaultConfig::default()
                },
                1
            )
            .is_err()
        );
        let silences = vec!["4@0".parse().unwrap()];
        let err = Faults::new(
            FaultConfig {
                silences,
                ..FaultConfig::default()
            },
            4,
        )
        .unwrap_err();
        assert_eq!(
            err,
            FaultError::NoSuchModule {
                module: 4,
                modules: 4
            }
        );
    }

    #[test]
    fn delay_queue_releases_in_time_and_refuses_when_full() {
        let mut q = DelayQueue::with_capacity(2);
        q.push(0.010, 'a').unwrap();
        q.push(0.011, 'b').unwrap();
        assert_eq!(q.push(0.012, 'c'), Err('c'));
        assert_eq!(q.pop_due(0.009), None);
        assert_eq!(q.pop_due(0.010), Some('a'));
        assert_eq!(q.pop_due(0.010), None);
        assert_eq!(q.pop_due(0.020), Some('b'));
        assert!(q.is_empty());
        // Capacity never grows.
        assert!(q.items.capacity() >= 2);
    }
}
