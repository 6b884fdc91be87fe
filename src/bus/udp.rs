//! `UdpBus`: the loop's view of modules reached over UDP (real modules or
//! `snake-emu`), protocol v2 (`docs/protocol.md`).
//!
//! Start-up (may allocate and block): [`parse_targets`] → [`discover`] →
//! [`UdpBus::connect`] (Acquire, then Settings). Per cycle ([`Bus::send`],
//! [`Bus::receive`]): no allocation, no lock, no blocking except the lockstep wait.
//! One non-blocking socket talks to every module; a module is the address it was
//! discovered at plus its unit there, and only frames tagged under its session key
//! count as its own. The frames for modules behind one address (a gateway) travel
//! bundled: one datagram per endpoint per cycle.

mod batch;
mod clock;
mod connect;
mod counters;
mod discovery;
mod endpoints;
mod net;
mod rx;
mod targets;

#[cfg(test)]
mod fake;
#[cfg(test)]
mod tests;

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

pub use connect::{ConnectError, FailReason, FailedModule};
pub use discovery::{DiscoveryError, FoundModule, discover, discover_until, format_mac};
pub use net::default_bind;
pub use targets::{MAX_RANGE_PORTS, TargetError, parse_targets};

use super::{Bus, BusCounters, BusError, FeedbackWait, GroupFeedback};
use crate::protocol::{
    Command, Key, MAGIC, MAX_DATAGRAM, Message, MsgType, Route, Settings, VERSION, encode, open,
    peek,
};
use batch::{BATCH, RecvBatch};
pub use counters::UdpCounters;
use endpoints::Endpoints;
use rx::Slot;

/// A group of modules acquired under one session.
pub struct UdpBus {
    socket: UdpSocket,
    session: u32,
    network_key: Key,
    /// Head first.
    modules: Vec<FoundModule>,
    /// Parallel to `modules`: each module's session key (the network key until granted).
    keys: Vec<Key>,
    /// Parallel to `modules`.
    slots: Vec<Slot>,
    endpoints: Endpoints,
    settings: Settings,
    tx_buf: [u8; MAX_DATAGRAM],
    /// Taken out while draining (so frames can be handled with `&mut self`).
    batch: Option<RecvBatch>,
    /// Maps kernel receive stamps (`CLOCK_REALTIME`) to the loop's clock: the loop
    /// time and the realtime clock read together at the start of this `receive`;
    /// `None` in lockstep, where the loop's clock is simulated.
    rx_clock: Option<(u64, u64)>,
    /// Header seq of every frame the bus sends, requests and commands alike: strictly
    /// increasing, so a module can refuse anything replayed. Never wraps (u64).
    tx_seq: u64,
    /// Header seq of the last Command cycle (0 before the first: "none").
    command_seq: u64,
    /// When each of the last `SENT_RING` command cycles was sent (the loop clock of the
    /// `receive` before it), by seq modulo the ring's size.
    sent_ns: Box<[u64; SENT_RING]>,
    last_receive_ns: u64,
    /// `receive` calls so far (0: still connecting).
    receives: u64,
    counters: UdpCounters,
    released: bool,
}

impl UdpBus {
    /// Session this bus drives the modules with.
    pub fn session(&self) -> u32 {
        self.session
    }

    /// The modules, head first.
    pub fn modules(&self) -> &[FoundModule] {
        &self.modules
    }

    /// Settings every module acknowledged.
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// Local address of the bus socket (where feedback arrives).
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// Its own counters, every reason for a dropped datagram apart (the statistics
    /// see them as [`Bus::counters`]' detail).
    pub fn udp_counters(&self) -> UdpCounters {
        self.counters
    }

    /// Header seq of the last Command cycle sent (0 before the first).
    pub fn command_seq(&self) -> u64 {
        self.command_seq
    }

    fn next_seq(&mut self) -> u64 {
        self.tx_seq += 1;
        self.tx_seq
    }

    /// Send `msg` to the modules selected by `to`, bundled per endpoint, each frame
    /// tagged under the key its type calls for; failures count as send errors.
    fn send_control(&mut self, msg: &Message, to: impl Fn(usize) -> bool) {
        let seq = self.next_seq();
        let network = msg.msg_type().uses_network_key();
        let (session, keys, modules) = (self.session, &self.keys, &self.modules);
        let sent = self.endpoints.send_bundled(
            &self.socket,
            &mut self.tx_buf,
            |i| to(i).then_some(()),
            |i, (), buf| {
                let key = if network { &self.network_key } else { &keys[i] };
                let route = Route {
                    session,
                    seq,
                    unit: modules[i].unit,
                };
                encode(route, msg, key, buf)
            },
        );
        self.counters.send_errors += sent.failed_frames;
    }

    /// Receive until the socket is empty, a batch of datagrams per system call.
    /// Feedback goes to the slots; any other authenticated frame from a module is
    /// offered to `reply` (index, message), which returns whether it wanted it;
    /// unwanted ones count as unexpected.
    fn drain(&mut self, reply: &mut dyn FnMut(usize, Message) -> bool) -> io::Result<()> {
        let mut batch = self
            .batch
            .take()
            .expect("the batch is put back after each drain");
        let r = self.drain_with(&mut batch, reply);
        self.batch = Some(batch);
        r
    }

    fn drain_with(
        &mut self,
        batch: &mut RecvBatch,
        reply: &mut dyn FnMut(usize, Message) -> bool,
    ) -> io::Result<()> {
        loop {
            let n = match batch.recv(&self.socket) {
                Ok(n) => n,
                Err(e) if net::is_transient(&e) => continue,
                Err(e) => return Err(e),
            };
            for i in 0..n {
                let d = batch.get(i);
                if d.oversized {
                    self.counters.bad_length += 1;
                    continue;
                }
                let Some(src) = d.from else {
                    self.counters.unexpected += 1;
                    continue;
                };
                let rx_ns = self.arrival_ns(d.rx_realtime_ns);
                self.on_datagram(d.bytes, src, rx_ns, reply);
            }
            if n < BATCH {
                return Ok(());
            }
        }
    }

    /// When a datagram stamped `rx_realtime_ns` by the kernel arrived, on the loop's
    /// clock: never after this `receive` began, and that time itself when there is no
    /// stamp or no real clock (lockstep). `None` before the loop's first `receive`
    /// (during connect): the loop's clock is not known yet, the first `receive` counts.
    fn arrival_ns(&self, rx_realtime_ns: u64) -> Option<u64> {
        match self.rx_clock {
            Some((loop_ns, realtime_ns)) if rx_realtime_ns > 0 => {
                Some(loop_ns.saturating_sub(realtime_ns.saturating_sub(rx_realtime_ns)))
            }
            Some((loop_ns, _)) => Some(loop_ns),
            None if self.receives > 0 => Some(self.last_receive_ns),
            None => None,
        }
    }

    /// Validate every frame of one received datagram; handle feedback, hand back
    /// anything else that came authenticated from a module of the group.
    fn on_datagram(
        &mut self,
        datagram: &[u8],
        src: SocketAddr,
        rx_ns: Option<u64>,
        reply: &mut dyn FnMut(usize, Message) -> bool,
    ) {
        let mut at = 0;
        while at < datagram.len() {
            let d = &datagram[at..];
            // A Lookup is never meant for the bus, and decoding one could allocate.
            if d.len() >= 4 && d[..2] == MAGIC && d[2] == VERSION && d[3] == MsgType::Lookup as u8 {
                self.counters.unexpected += 1;
                return;
            }
            // A bad header ends the datagram: nothing after it can be framed.
            let (header, len) = match peek(d) {
                Ok(h) => h,
                Err(e) => return self.counters.count_decode_error(e),
            };
            let frame = at..at + len;
            at += len;
            let Some(i) = self.endpoints.module_at(src, header.unit) else {
                self.counters.unexpected += 1;
                continue;
            };
            let key = if header.msg_type.uses_network_key() {
                self.network_key
            } else if header.session == self.session {
                self.keys[i]
            } else {
                self.counters.wrong_session += 1;
                continue;
            };
            let msg = match open(&datagram[frame], &key) {
                Ok(m) => m,
                Err(e) => {
                    self.counters.count_decode_error(e);
                    continue;
                }
            };
            match msg {
                Message::Feedback(fb) => {
                    let on_clock = self.rx_clock.is_some();
                    self.slots[i].offer(header.seq, fb, rx_ns, on_clock, &mut self.counters);
                }
                // Replies to our own requests only.
                other if header.session == self.session => {
                    if !reply(i, other) {
                        self.counters.unexpected += 1;
                    }
                }
                _ => self.counters.wrong_session += 1,
            }
        }
    }

    /// Every module has reported feedback at or after `min_module_time_us`.
    fn all_reached(&self, min_module_time_us: u64) -> bool {
        self.slots
            .iter()
            .all(|s| s.last_seq > 0 && s.newest.module_time_us >= min_module_time_us)
    }

    /// Hand feedback that arrived since the last call to the loop, and every module's
    /// command round trip now.
    fn publish(&mut self, group: &mut GroupFeedback, now_ns: u64) {
        let (last, sent) = (self.command_seq, &*self.sent_ns);
        for (slot, state) in self.slots.iter_mut().zip(group.modules.iter_mut()) {
            if slot.pending {
                slot.pending = false;
                state.feedback = slot.newest;
                state.received_ns = Some(slot.rx_ns.map_or(now_ns, |r| r.min(now_ns)));
                state.clock_age_ns = slot.clock_age_ns;
                state.fresh = true;
            }
            state.command_age_ns =
                command_age_ns(last, sent, state.feedback.last_command_seq, now_ns);
        }
    }
}

/// Command cycles whose send times are kept (4 s at 1 kHz); a feedback reporting an
/// older one is treated as that old at least.
pub(crate) const SENT_RING: usize = 4096;

/// How long ago command cycle `seq` was sent, given the last one sent and the ring of
/// send times (`None` for 0, "none yet"). A seq beyond the ring, or ahead of the last
/// one sent (not ours), counts as very old.
fn command_age_ns(last: u64, sent: &[u64; SENT_RING], seq: u64, now_ns: u64) -> Option<u64> {
    if seq == 0 || last == 0 {
        return None;
    }
    if seq > last || last - seq >= SENT_RING as u64 {
        return Some(u64::MAX / 2);
    }
    Some(now_ns.saturating_sub(sent[seq as usize % SENT_RING]))
}

impl Bus for UdpBus {
    fn module_count(&self) -> usize {
        self.modules.len()
    }

    fn send(&mut self, commands: &[Command]) -> Result<(), BusError> {
        if commands.len() != self.modules.len() {
            return Err(BusError::WrongCount {
                expected: self.modules.len(),
                got: commands.len(),
            });
        }
        self.command_seq = self.next_seq();
        // Sent within this cycle, just after its `receive`.
        self.sent_ns[self.command_seq as usize % SENT_RING] = self.last_receive_ns;
        let (session, seq, keys, modules) =
            (self.session, self.command_seq, &self.keys, &self.modules);
        let sent = self.endpoints.send_bundled(
            &self.socket,
            &mut self.tx_buf,
            |i| Some(commands[i]),
            |i, cmd, buf| {
                let route = Route {
                    session,
                    seq,
                    unit: modules[i].unit,
                };
                // Refused for an infinite set-point (not encodable).
                encode(route, &Message::Command(cmd), &keys[i], buf)
            },
        );
        self.counters.commands_sent += sent.sent_frames;
        self.counters.send_errors += sent.failed_frames;
        Ok(())
    }

    fn receive(
        &mut self,
        group: &mut GroupFeedback,
        now_ns: u64,
        wait: FeedbackWait,
    ) -> Result<(), BusError> {
        if group.len() != self.modules.len() {
            return Err(BusError::WrongCount {
                expected: self.modules.len(),
                got: group.len(),
            });
        }
        for m in &mut group.modules {
            m.fresh = false;
        }
        self.last_receive_ns = now_ns;
        self.receives += 1;
        // Real-time pacing: the loop's clock runs with the wall clock, so kernel stamps
        // and the modules' clocks mean something against it.
        self.rx_clock = matches!(wait, FeedbackWait::None).then(|| (now_ns, batch::realtime_ns()));
        self.drain(&mut |_, _| false)?;
        if let FeedbackWait::Lockstep {
            min_module_time_us,
            timeout_ns,
        } = wait
        {
            let deadline = net::deadline_after(Duration::from_nanos(timeout_ns));
            while !self.all_reached(min_module_time_us) {
                let now = Instant::now();
                if now >= deadline {
                    self.publish(group, now_ns);
                    return Err(BusError::LockstepTimeout);
                }
                net::wait_readable(&self.socket, deadline - now)?;
                self.drain(&mut |_, _| false)?;
            }
        }
        self.publish(group, now_ns);
        Ok(())
    }

    fn counters(&self) -> BusCounters {
        self.counters.to_bus()
    }

    /// Send Release to every module (once; also done on drop). Fire and forget: a
    /// lost Release is covered by the modules' release timeout.
    fn release(&mut self) {
        if !self.released {
            self.released = true;
            self.send_control(&Message::Release, |_| true);
        }
    }
}

impl std::fmt::Debug for UdpBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UdpBus")
            .field("local_addr", &self.socket.local_addr().ok())
            .field("session", &self.session)
            .field("modules", &self.modules)
            .field("settings", &self.settings)
            .field("command_seq", &self.command_seq)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl Drop for UdpBus {
    fn drop(&mut self) {
        self.release();
    }
}
