//! Latched messages: what is published once (the world, controller infos) is re-sent to
//! each client that subscribes later; and how many clients are connected.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{ChannelId, PartialMetadata, RawChannel};

/// A latched message: its channel, a key (a newer message of the same key replaces
/// it), the payload and its log time.
struct Latched {
    channel: Arc<RawChannel>,
    key: u64,
    payload: Vec<u8>,
    log_time: u64,
}

/// The server's listener: counts clients and re-sends latched messages on subscribe.
#[derive(Default)]
pub struct Latch {
    clients: AtomicUsize,
    latched: Mutex<HashMap<ChannelId, Vec<Latched>>>,
}

impl Latch {
    /// Poisoning is shrugged off: a latched message is still worth showing.
    fn latched(&self) -> MutexGuard<'_, HashMap<ChannelId, Vec<Latched>>> {
        self.latched.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Keeps `payload` for clients that subscribe to `channel` later.
    pub fn keep(&self, channel: &Arc<RawChannel>, key: u64, payload: &[u8], log_time: u64) {
        let mut map = self.latched();
        let list = map.entry(channel.id()).or_default();
        let entry = Latched {
            channel: channel.clone(),
            key,
            payload: payload.to_vec(),
            log_time,
        };
        match list.iter_mut().find(|l| l.key == key) {
            Some(l) => *l = entry,
            None => list.push(entry),
        }
    }

    pub fn clients(&self) -> usize {
        self.clients.load(Ordering::Relaxed)
    }
}

impl ServerListener for Latch {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        // The subscription is registered before this callback, so the client's sink
        // receives what is logged to it here.
        let map = self.latched();
        for l in map.get(&channel.id()).into_iter().flatten() {
            let meta = PartialMetadata {
                log_time: Some(l.log_time),
            };
            l.channel
                .log_with_meta_to_sink(&l.payload, meta, client.sink_id());
        }
    }

    fn on_client_connect(&self) {
        self.clients.fetch_add(1, Ordering::Relaxed);
    }

    fn on_client_disconnect(&self) {
        // Saturating: never wraps even if the server reported an unmatched disconnect.
        let _ = self
            .clients
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1));
    }
}
