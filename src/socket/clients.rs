//! The client table: at most `max_clients` connections are served at once, and a stop
//! must always get through. When the table is full, a new connection takes the slot of
//! the connection idle the longest (no request for at least [`EVICTABLE_IDLE`], no
//! telemetry stream), which is told why and closed; if none is that idle, the new
//! connection is served over the limit for one stop request (`estop`, `limp`, `hold`)
//! and then closed. See docs/control-socket.md, "Connections".

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::sync::Notify;

/// A connection idle this long may give its slot to a newcomer when the table is full.
pub const EVICTABLE_IDLE: Duration = Duration::from_secs(1);
/// Connections served over the limit at once (each for one stop request, briefly).
pub const MAX_OVER_LIMIT: usize = 16;

/// One served connection, as the table sees it.
pub(crate) struct Client {
    id: u64,
    /// Milliseconds since the table's start at the last request (or the connection).
    last_active_ms: AtomicU64,
    subscribed: AtomicBool,
    /// Notified when the connection is to close to make room.
    pub(crate) evicted: Notify,
    epoch: Instant,
}

impl Client {
    /// The connection's number (never reused while the server runs).
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// A request arrived (or was answered).
    pub(crate) fn touch(&self) {
        let ms = self.epoch.elapsed().as_millis() as u64;
        self.last_active_ms.store(ms, Ordering::Relaxed);
    }

    pub(crate) fn set_subscribed(&self, on: bool) {
        self.subscribed.store(on, Ordering::Relaxed);
    }

    fn idle(&self) -> Duration {
        let now = self.epoch.elapsed().as_millis() as u64;
        Duration::from_millis(now.saturating_sub(self.last_active_ms.load(Ordering::Relaxed)))
    }
}

/// What a new connection gets.
pub(crate) enum Admission {
    /// A slot (released when the guard drops).
    Served(Arc<Client>, Seat),
    /// No slot: served for one stop request, then closed (released on drop).
    OverLimit(OverLimitSeat),
    /// Not even that: told and closed.
    Refused,
}

/// The table of served connections.
pub(crate) struct Clients {
    max: usize,
    epoch: Instant,
    next_id: AtomicU64,
    served: Mutex<Vec<Arc<Client>>>,
    over_limit: std::sync::atomic::AtomicUsize,
}

impl Clients {
    pub(crate) fn new(max: usize) -> Arc<Self> {
        Arc::new(Self {
            max,
            epoch: Instant::now(),
            next_id: AtomicU64::new(1),
            served: Mutex::new(Vec::new()),
            over_limit: std::sync::atomic::AtomicUsize::new(0),
        })
    }

    pub(crate) fn max(&self) -> usize {
        self.max
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Arc<Client>>> {
        self.served.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Admits a new connection (see the module docs).
    pub(crate) fn admit(self: &Arc<Self>) -> Admission {
        let mut served = self.lock();
        if served.len() >= self.max {
            let idlest = served
                .iter()
                .enumerate()
                .filter(|(_, c)| !c.subscribed.load(Ordering::Relaxed))
                .map(|(i, c)| (i, c.idle()))
                .filter(|(_, idle)| *idle >= EVICTABLE_IDLE)
                .max_by_key(|(_, idle)| *idle);
            match idlest {
                Some((i, _)) => {
                    let old = served.swap_remove(i);
                    old.evicted.notify_one();
                }
                None => {
                    drop(served);
                    return self.over_limit_seat();
                }
            }
        }
        let client = Arc::new(Client {
            id: self.next_id.fetch_add(1, Ordering::Relaxed),
            last_active_ms: AtomicU64::new(self.epoch.elapsed().as_millis() as u64),
            subscribed: AtomicBool::new(false),
            evicted: Notify::new(),
            epoch: self.epoch,
        });
        served.push(client.clone());
        let seat = Seat {
            clients: self.clone(),
            id: client.id,
        };
        Admission::Served(client, seat)
    }

    fn over_limit_seat(self: &Arc<Self>) -> Admission {
        let n = self.over_limit.fetch_add(1, Ordering::AcqRel);
        if n >= MAX_OVER_LIMIT {
            self.over_limit.fetch_sub(1, Ordering::AcqRel);
            return Admission::Refused;
        }
        Admission::OverLimit(OverLimitSeat(self.clone()))
    }
}

/// A served connection's place in the table, released when it ends.
pub(crate) struct Seat {
    clients: Arc<Clients>,
    id: u64,
}

impl Drop for Seat {
    fn drop(&mut self) {
        self.clients.lock().retain(|c| c.id != self.id);
    }
}

/// A connection served over the limit, released when it ends.
pub(crate) struct OverLimitSeat(Arc<Clients>);

impl Drop for OverLimitSeat {
    fn drop(&mut self) {
        self.0.over_limit.fetch_sub(1, Ordering::AcqRel);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_table_evicts_the_idlest_or_serves_over_the_limit() {
        let t = Clients::new(2);
        let Admission::Served(a, _sa) = t.admit() else {
            panic!("a slot")
        };
        let Admission::Served(b, _sb) = t.admit() else {
            panic!("a slot")
        };
        // Both just arrived: nobody to evict; over the limit instead.
        assert!(matches!(t.admit(), Admission::OverLimit(_)));
        // `a` idle long enough, `b` streaming: `a` goes.
        a.last_active_ms.store(0, Ordering::Relaxed);
        b.set_subscribed(true);
        std::thread::sleep(EVICTABLE_IDLE + Duration::from_millis(20));
        b.touch();
        let Admission::Served(_c, _sc) = t.admit() else {
            panic!("a's slot")
        };
        assert_eq!(t.lock().len(), 2);
        assert!(t.lock().iter().all(|x| x.id != a.id), "a was evicted");
        // Over-limit seats are bounded too.
        let seats: Vec<_> = (0..MAX_OVER_LIMIT).map(|_| t.admit()).collect();
        assert!(seats.iter().all(|s| matches!(s, Admission::OverLimit(_))));
        assert!(matches!(t.admit(), Admission::Refused));
        drop(seats);
        assert!(matches!(t.admit(), Admission::OverLimit(_)));
    }
}
