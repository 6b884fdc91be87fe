//! Admission of new connections: limits on the connections the server holds (in total and per
//! peer IP address, counted from the moment a connection is accepted, so connections that have
//! not completed their handshake count too), the back-off after a failed accept, and rate-limited
//! warnings for both.

use std::collections::HashMap;
use std::fmt::Display;
use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use std::time::Duration;

use crate::throttler::Throttler;

/// The first delay after a failed accept.
const ACCEPT_BACKOFF_MIN: Duration = Duration::from_millis(5);
/// The longest delay between two failed accepts.
const ACCEPT_BACKOFF_MAX: Duration = Duration::from_secs(1);
/// At most one warning per kind of event in this interval.
const WARN_INTERVAL: Duration = Duration::from_secs(10);

/// Why a connection was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// The server holds `max_connections` connections.
    Total(usize),
    /// The server holds `max_connections_per_ip` connections from the peer's address.
    PerIp(usize),
}

impl Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Total(n) => write!(f, "the server holds {n} connections (max_connections)"),
            Refusal::PerIp(n) => write!(
                f,
                "the server holds {n} connections from this address (max_connections_per_ip)"
            ),
        }
    }
}

#[derive(Debug, Default)]
struct Counts {
    total: usize,
    per_ip: HashMap<IpAddr, usize>,
}

/// The connections the server holds, against its limits.
#[derive(Debug)]
pub(crate) struct ConnectionLimits {
    max_total: Option<usize>,
    max_per_ip: Option<usize>,
    counts: parking_lot::Mutex<Counts>,
}

impl ConnectionLimits {
    pub fn new(max_total: Option<usize>, max_per_ip: Option<usize>) -> Arc<Self> {
        Arc::new(Self {
            max_total,
            max_per_ip,
            counts: parking_lot::Mutex::default(),
        })
    }

    /// Counts a new connection from `addr`, unless it would exceed a limit. The connection is
    /// counted until the returned permit is dropped.
    pub fn admit(self: &Arc<Self>, addr: SocketAddr) -> Result<ConnectionPermit, Refusal> {
        let ip = addr.ip().to_canonical();
        let mut counts = self.counts.lock();
        if let Some(max) = self.max_total
            && counts.total >= max
        {
            return Err(Refusal::Total(max));
        }
        let from_ip = counts.per_ip.get(&ip).copied().unwrap_or(0);
        if let Some(max) = self.max_per_ip
            && from_ip >= max
        {
            return Err(Refusal::PerIp(max));
        }
        counts.total += 1;
        counts.per_ip.insert(ip, from_ip + 1);
        Ok(ConnectionPermit {
            limits: self.clone(),
            ip,
        })
    }
}

/// A connection counted against the server's limits, until dropped.
#[derive(Debug)]
pub(crate) struct ConnectionPermit {
    limits: Arc<ConnectionLimits>,
    ip: IpAddr,
}

impl Drop for ConnectionPermit {
    fn drop(&mut self) {
        let mut counts = self.limits.counts.lock();
        counts.total = counts.total.saturating_sub(1);
        if let Some(n) = counts.per_ip.get_mut(&self.ip) {
            *n = n.saturating_sub(1);
            if *n == 0 {
                counts.per_ip.remove(&self.ip);
            }
        }
    }
}

/// The delay before the next accept after a failed one: doubling from 5 ms to 1 s, back to 5 ms
/// after a successful accept.
#[derive(Debug)]
pub(crate) struct AcceptBackoff {
    next: Duration,
}

impl AcceptBackoff {
    pub fn new() -> Self {
        Self {
            next: ACCEPT_BACKOFF_MIN,
        }
    }

    /// The delay to wait now; the next one is twice as long (at most 1 s).
    pub fn delay(&mut self) -> Duration {
        let d = self.next;
        self.next = (d * 2).min(ACCEPT_BACKOFF_MAX);
        d
    }

    pub fn reset(&mut self) {
        self.next = ACCEPT_BACKOFF_MIN;
    }
}

/// A warning logged at most once per interval; the events in between are counted and the count
/// is reported with the next warning.
#[derive(Debug)]
pub(crate) struct RateLimitedWarning {
    throttler: Throttler,
    suppressed: usize,
}

impl RateLimitedWarning {
    pub fn new() -> Self {
        Self {
            throttler: Throttler::new(WARN_INTERVAL),
            suppressed: 0,
        }
    }

    /// Logs `message` unless a warning was logged less than the interval ago.
    pub fn warn(&mut self, message: impl FnOnce() -> String) {
        if self.throttler.try_acquire() {
            let message = message();
            match std::mem::take(&mut self.suppressed) {
                0 => tracing::warn!("{message}"),
                n => tracing::warn!(
                    "{message} ({n} more since the last warning, not logged; at most one every \
                     {WARN_INTERVAL:?})"
                ),
            }
        } else {
            self.suppressed += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_limits_count_from_admission_until_the_permit_drops() {
        let limits = ConnectionLimits::new(Some(3), Some(2));
        let a: SocketAddr = "127.0.0.1:1000".parse().unwrap();
        let b: SocketAddr = "127.0.0.2:1000".parse().unwrap();
        let a1 = limits.admit(a).unwrap();
        let _a2 = limits.admit(a).unwrap();
        assert_eq!(limits.admit(a).unwrap_err(), Refusal::PerIp(2));
        let _b1 = limits.admit(b).unwrap();
        assert_eq!(limits.admit(b).unwrap_err(), Refusal::Total(3));
        drop(a1);
        let _b2 = limits.admit(b).unwrap();
        assert_eq!(limits.admit(a).unwrap_err(), Refusal::Total(3));
    }

    #[test]
    fn test_backoff_doubles_up_to_a_second_and_resets() {
        let mut b = AcceptBackoff::new();
        let delays: Vec<_> = (0..10).map(|_| b.delay()).collect();
        assert_eq!(delays[0], Duration::from_millis(5));
        assert_eq!(delays[1], Duration::from_millis(10));
        assert_eq!(delays[9], Duration::from_secs(1));
        b.reset();
        assert_eq!(b.delay(), Duration::from_millis(5));
    }
}
