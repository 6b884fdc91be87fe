//! Start-up handshake of the bus: Acquire every module, then Settings.
use std::fmt;
use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use super::UdpCounters;
use super::endpoints::Endpoints;
use super::{FoundModule, UdpBus, net};
use crate::bus::Bus;
use crate::protocol::{Key, MAX_DATAGRAM, Message, NO_SESSION, Nonce, Settings};

/// Valid feedback rates, Hz (docs/protocol.md §3.5).
const FEEDBACK_RATE_RANGE_HZ: std::ops::RangeInclusive<f32> = 1.0..=2000.0;
/// Valid command lifetimes, s (docs/protocol.md §3.5).
const COMMAND_LIFETIME_RANGE_S: std::ops::RangeInclusive<f32> = 0.001..=10.0;
/// Longest pause between resends of an unanswered request.
const MAX_RESEND: Duration = Duration::from_millis(100);

/// One module that failed the handshake, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct FailedModule {
    pub name: String,
    pub addr: SocketAddr,
    pub reason: FailReason,
}

#[derive(Debug, Clone, PartialEq)]
pub enum FailReason {
    /// Did not answer before the timeout.
    NoAnswer,
    /// Refused the Acquire: another session owns it (which one, modules never say).
    Owned,
    /// Acknowledged other settings than those sent (it refused them).
    KeptSettings(Settings),
}

impl fmt::Display for FailedModule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at {}: ", self.name, self.addr)?;
        match self.reason {
            FailReason::NoAnswer => write!(f, "no answer"),
            FailReason::Owned => write!(
                f,
                "driven by another session (it frees itself 1 s after that session falls silent)"
            ),
            FailReason::KeptSettings(s) => write!(
                f,
                "refused the settings, kept {} Hz / {} s / {:?}",
                s.feedback_rate_hz, s.command_lifetime_s, s.strategy
            ),
        }
    }
}

fn list(failed: &[FailedModule]) -> String {
    let parts: Vec<String> = failed.iter().map(ToString::to_string).collect();
    parts.join("; ")
}

/// Why [`UdpBus::connect`] failed. Modules acquired before the failure are released.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    #[error("bus socket: {0}")]
    Io(#[from] io::Error),
    #[error("no modules to connect to")]
    NoModules,
    #[error("session 0 is reserved (\"no session\")")]
    NoSession,
    #[error("two modules share the address {0} and unit {1}")]
    DuplicateAddress(SocketAddr, u16),
    #[error("invalid settings: {0}")]
    InvalidSettings(&'static str),
    #[error("could not acquire {} of {total} modules: {}", .failed.len(), list(.failed))]
    Acquire {
        failed: Vec<FailedModule>,
        total: usize,
    },
    #[error("settings not in force on {} of {total} modules: {}", .failed.len(), list(.failed))]
    Settings {
        failed: Vec<FailedModule>,
        total: usize,
    },
}

fn check_settings(s: &Settings) -> Result<(), ConnectError> {
    if !FEEDBACK_RATE_RANGE_HZ.contains(&s.feedback_rate_hz) {
        return Err(ConnectError::InvalidSettings(
            "feedback rate outside 1..=2000 Hz",
        ));
    }
    if !COMMAND_LIFETIME_RANGE_S.contains(&s.command_lifetime_s) {
        return Err(ConnectError::InvalidSettings(
            "command lifetime outside 0.001..=10 s",
        ));
    }
    Ok(())
}

/// Bit-exact, as the module echoes what it holds.
fn same_settings(a: &Settings, b: &Settings) -> bool {
    a.feedback_rate_hz.to_bits() == b.feedback_rate_hz.to_bits()
        && a.command_lifetime_s.to_bits() == b.command_lifetime_s.to_bits()
        && a.strategy == b.strategy
}

impl UdpBus {
    /// Acquire every module of `found` (head first) under `session`, then put
    /// `settings` in force on each. One socket bound to `bind` (e.g. `127.0.0.1:0`,
    /// see [`super::default_bind`]) talks to them all; it is where the modules will
    /// stream feedback. Unanswered or refused requests are resent (at most every
    /// 100 ms) until `timeout`, which applies to each of the two phases.
    ///
    /// Fails naming every module that refused or did not answer; anything acquired by
    /// then is released again. On an open network ([`Key::OPEN`]); see
    /// [`UdpBus::connect_keyed`].
    pub fn connect(
        found: &[FoundModule],
        settings: Settings,
        bind: SocketAddr,
        session: u32,
        timeout: Duration,
    ) -> Result<UdpBus, ConnectError> {
        Self::connect_keyed(found, settings, bind, session, timeout, Key::OPEN)
    }

    /// [`UdpBus::connect`] on a network keyed with `network_key`: each module's
    /// session key is derived from it and the nonces both sides pick at Acquire.
    pub fn connect_keyed(
        found: &[FoundModule],
        settings: Settings,
        bind: SocketAddr,
        session: u32,
        timeout: Duration,
        network_key: Key,
    ) -> Result<UdpBus, ConnectError> {
        if found.is_empty() {
            return Err(ConnectError::NoModules);
        }
        if session == NO_SESSION {
            return Err(ConnectError::NoSession);
        }
        let endpoints =
            Endpoints::new(found).map_err(|(a, u)| ConnectError::DuplicateAddress(a, u))?;
        check_settings(&settings)?;
        let n = found.len();
        let socket = net::open(bind, false)?;
        // Best effort: without stamps, arrival is when the loop drains the socket.
        let _ = super::batch::RecvBatch::enable_timestamps(&socket);
        let mut bus = UdpBus {
            socket,
            session,
            network_key,
            modules: found.to_vec(),
            keys: vec![network_key; n],
            slots: vec![Default::default(); n],
            endpoints,
            settings,
            tx_buf: [0; MAX_DATAGRAM],
            batch: Some(super::batch::RecvBatch::new()),
            rx_clock: None,
            tx_seq: 0,
            command_seq: 0,
            sent_ns: Box::new([0; super::SENT_RING]),
            last_receive_ns: 0,
            receives: 0,
            counters: UdpCounters::default(),
            // Nothing to release until something is acquired.
            released: true,
        };

        // One nonce for the whole group: each module adds its own, and the MAC too.
        let host_nonce: Nonce = rand::random();
        let mut answered = vec![false; n];
        let mut keys = vec![None; n];
        let granted = bus.handshake(
            &Message::Acquire(host_nonce),
            timeout,
            &mut |i, msg| match msg {
                Message::AcquireReply(r) => {
                    answered[i] = true;
                    if r.granted {
                        let mac = &found[i].announce.mac;
                        keys[i] = Some(network_key.session_key(
                            session,
                            mac,
                            &host_nonce,
                            &r.module_nonce,
                        ));
                    }
                    // A refused module is asked again: its owner may time out meanwhile.
                    Some(r.granted)
                }
                _ => None,
            },
        )?;
        for (k, key) in bus.keys.iter_mut().zip(&keys) {
            *k = key.unwrap_or(network_key);
        }
        bus.released = false;
        if granted.iter().any(|g| !g) {
            let failed = bus.failures(&granted, |i| {
                if answered[i] {
                    FailReason::Owned
                } else {
                    FailReason::NoAnswer
                }
            });
            bus.send_control(&Message::Release, |i| granted[i]);
            bus.released = true;
            return Err(ConnectError::Acquire { failed, total: n });
        }

        let mut in_force = vec![None; n];
        let answered = bus.handshake(
            &Message::Settings(settings),
            timeout,
            &mut |i, msg| match msg {
                Message::SettingsAck(s) => {
                    in_force[i] = Some(s);
                    Some(true)
                }
                _ => None,
            },
        )?;
        let ok: Vec<bool> = in_force
            .iter()
            .map(|s| s.is_some_and(|s| same_settings(&s, &settings)))
            .collect();
        if ok.iter().any(|o| !o) {
            let failed = bus.failures(&ok, |i| match in_force[i] {
                Some(s) if answered[i] => FailReason::KeptSettings(s),
                _ => FailReason::NoAnswer,
            });
            bus.release();
            return Err(ConnectError::Settings { failed, total: n });
        }
        Ok(bus)
    }

    /// Send `request` to every module until each has answered so that `on_reply`
    /// says it is done, or `timeout` passes. `on_reply(i, msg)` returns `None` for a
    /// message that is not an answer to this request, else whether module `i` is done.
    /// Feedback arriving meanwhile is kept for the loop. Returns who is done.
    fn handshake(
        &mut self,
        request: &Message,
        timeout: Duration,
        on_reply: &mut dyn FnMut(usize, Message) -> Option<bool>,
    ) -> io::Result<Vec<bool>> {
        let mut done = vec![false; self.modules.len()];
        let resend = (timeout / 4).min(MAX_RESEND);
        let deadline = net::deadline_after(timeout);
        let mut next_send = Instant::now();
        loop {
            let now = Instant::now();
            if done.iter().all(|&d| d) || now >= deadline {
                return Ok(done);
            }
            if now >= next_send {
                self.send_control(request, |i| !done[i]);
                next_send = now + resend;
            }
            net::wait_readable(&self.socket, next_send.min(deadline) - now)?;
            self.drain(&mut |i, msg| match on_reply(i, msg) {
                None => false,
                Some(d) => {
                    done[i] |= d;
                    true
                }
            })?;
        }
    }

    fn failures(&self, ok: &[bool], reason: impl Fn(usize) -> FailReason) -> Vec<FailedModule> {
        (0..self.modules.len())
            .filter(|&i| !ok[i])
            .map(|i| FailedModule {
                name: self.modules[i].announce.name.to_string(),
                addr: self.modules[i].addr,
                reason: reason(i),
            })
            .collect()
    }
}
