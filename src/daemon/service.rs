//! The service manager's side: sd_notify READY / STATUS / STOPPING and the
//! watchdog, which pings only while the loop's heartbeat moves (a wedged loop
//! stops the pings and systemd restarts the daemon).
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use sd_notify::NotifyState;

/// Tell systemd the daemon is ready (no-op outside systemd).
pub fn notify_ready(status: &str) {
    let _ = sd_notify::notify(&[NotifyState::Ready, NotifyState::Status(status)]);
}

pub fn notify_status(status: &str) {
    let _ = sd_notify::notify(&[NotifyState::Status(status)]);
}

pub fn notify_stopping() {
    let _ = sd_notify::notify(&[NotifyState::Stopping]);
}

/// Pings the watchdog at half its interval while the heartbeat advances.
pub struct Watchdog {
    interval: Option<Duration>,
    heartbeat: Arc<AtomicU64>,
    last_beat: u64,
    last_ping: Instant,
}

impl Watchdog {
    /// The interval systemd asked for (`WATCHDOG_USEC`), if any.
    pub fn from_env(heartbeat: Arc<AtomicU64>) -> Self {
        Self::new(sd_notify::watchdog_enabled(), heartbeat)
    }

    /// Pings at half of `timeout`; `None` disables the watchdog.
    pub fn new(timeout: Option<Duration>, heartbeat: Arc<AtomicU64>) -> Self {
        Self {
            interval: timeout.map(|d| d / 2),
            heartbeat,
            last_beat: 0,
            last_ping: Instant::now(),
        }
    }

    pub fn enabled(&self) -> bool {
        self.interval.is_some()
    }

    /// Call often (every few tens of ms); pings when due and the loop is alive.
    /// Returns false when the loop has not advanced since the last due ping.
    pub fn poll(&mut self) -> bool {
        let Some(interval) = self.interval else {
            return true;
        };
        if self.last_ping.elapsed() < interval {
            return true;
        }
        let beat = self.heartbeat.load(Ordering::Acquire);
        let alive = beat != self.last_beat;
        if alive {
            let _ = sd_notify::notify(&[NotifyState::Watchdog]);
            self.last_beat = beat;
        }
        self.last_ping = Instant::now();
        alive
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pings_only_while_the_heartbeat_moves() {
        let beat = Arc::new(AtomicU64::new(0));
        let mut w = Watchdog::new(Some(Duration::from_millis(2)), beat.clone());
        assert!(w.enabled());
        std::thread::sleep(Duration::from_millis(2));
        assert!(!w.poll(), "no cycle yet: no ping");
        beat.fetch_add(5, Ordering::Release);
        std::thread::sleep(Duration::from_millis(2));
        assert!(w.poll(), "the loop turned: ping");
        std::thread::sleep(Duration::from_millis(2));
        assert!(!w.poll(), "stalled since the last ping: no ping");
    }

    #[test]
    fn disabled_without_a_timeout() {
        let mut w = Watchdog::new(None, Arc::new(AtomicU64::new(0)));
        assert!(!w.enabled());
        assert!(w.poll());
    }
}
