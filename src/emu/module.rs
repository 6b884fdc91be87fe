//! One emulated module's protocol state machine (protocol v2, `docs/protocol.md`).
//! Pure but for its nonces: time comes in as an argument, authenticated messages and
//! the sender's address come in, messages to send (with the key to tag them) come out.
//! The server owns sockets, faults and the plant, and checks each frame's tag under
//! the key [`Module::key_for`] names before handing it here.
//!
//! Two clocks: the **simulation** clock drives everything the module's firmware would
//! time (command lifetime, feedback schedule, `module_time_us`), so lockstep runs are
//! deterministic; the **wall** clock times the session release timeout, so a dead
//! controller frees its modules after 1 s of real time even while a lockstep world
//! stands still. In real-time mode the two run together.
//!
//! An owned module streams feedback only after the first `SettingsAck` of its session
//! (`docs/protocol.md` §5.6), and sends one at once with that ack.
//! Replies (`Announce`, `AcquireReply`, `SettingsAck`) echo the request's header seq;
//! feedback carries the module's own feedback counter (first feedback = 1, +1 per
//! feedback sent, never reset, so a receiver can count gaps).

use std::net::SocketAddr;

use crate::protocol::{
    AcquireReply, Announce, Command, ControlStrategy, Feedback, Header, Key, LookupFilter, Mac,
    Message, NO_SESSION, Name, Nonce, Settings,
};

/// Who a module is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModuleIdentity {
    pub mac: Mac,
    pub name: Name,
    pub family: Name,
    pub firmware: u32,
}

/// Firmware version the emulator reports by default (0.1.0 as major<<16 | minor<<8 | patch).
pub const EMULATOR_FIRMWARE: u32 = 0x00_01_00;

impl ModuleIdentity {
    /// Identity of emulated module `index` (0-based) of `count`: MAC
    /// `02:53:4E:00:hi:lo` with `hi:lo = index + 1`, name `module-01`, `module-02`, …
    /// (zero-padded to at least two digits, more when `count` needs them).
    pub fn emulated(index: usize, count: usize, family: Name, firmware: u32) -> Self {
        let number = index + 1;
        let width = count.max(number).to_string().len().max(2);
        let name = Name::new(&format!("module-{number:0width$}"))
            .expect("module-<number> fits the name capacity");
        let id = (number as u16).to_be_bytes();
        Self {
            mac: [0x02, 0x53, 0x4E, 0x00, id[0], id[1]],
            name,
            family,
            firmware,
        }
    }

    /// True when this module should answer a lookup with `filter`.
    pub fn matches(&self, filter: &LookupFilter) -> bool {
        match filter {
            LookupFilter::All => true,
            LookupFilter::Family(f) => *f == self.family,
            LookupFilter::Names(names) => names.contains(&self.name),
            LookupFilter::Macs(macs) => macs.contains(&self.mac),
        }
    }
}

/// Module firmware constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModuleConfig {
    /// An owner silent for longer than this can be displaced by another session, s (wall).
    pub release_timeout_s: f64,
    /// The robot's network key ([`Key::OPEN`] on an open network).
    pub network_key: Key,
}

impl Default for ModuleConfig {
    fn default() -> Self {
        Self {
            release_timeout_s: 1.0,
            network_key: Key::OPEN,
        }
    }
}

/// The two clocks a module sees (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModuleTime {
    /// Simulation time, s.
    pub sim_s: f64,
    /// Wall-clock time since the emulator started, s.
    pub wall_s: f64,
}

impl ModuleTime {
    /// Both clocks at `t_s` (real-time mode, tests).
    pub fn both(t_s: f64) -> Self {
        Self {
            sim_s: t_s,
            wall_s: t_s,
        }
    }
}

/// A message the module wants sent.
#[derive(Debug, Clone, PartialEq)]
pub struct Outgoing {
    pub dest: SocketAddr,
    pub session: u32,
    pub seq: u64,
    pub message: Message,
    /// What the frame is tagged under: the network key for replies to discovery and
    /// Acquire, the session key otherwise.
    pub key: Key,
}

/// Per-module counters, monotonically increasing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct ModuleCounters {
    pub wrong_session: u64,
    /// Authenticated frames from the owner whose seq was not newer than the newest
    /// accepted (a replay or a reordered duplicate): dropped.
    pub replayed: u64,
    /// Well-formed messages a module never accepts (announce, feedback, …).
    pub unexpected: u64,
    pub commands: u64,
    pub acquire_denied: u64,
    pub settings_refused: u64,
    /// Feedback built (each consumes one seq; faults may still drop it on the way).
    pub feedback_sent: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Owner {
    session: u32,
    addr: SocketAddr,
    last_heard_wall_s: f64,
    host_nonce: Nonce,
    module_nonce: Nonce,
    /// Derived at Acquire from the network key and both nonces.
    key: Key,
    /// Newest seq accepted from the owner: anything not newer is a replay.
    last_seq: u64,
}

/// One module's protocol state.
#[derive(Debug, Clone)]
pub struct Module {
    identity: ModuleIdentity,
    config: ModuleConfig,
    owner: Option<Owner>,
    settings: Settings,
    /// Newest command and when it arrived (sim time).
    command: Option<(Command, f64)>,
    last_command_seq: u64,
    feedback_seq: u64,
    next_feedback_s: f64,
    feedback_now: bool,
    /// Streaming starts with the first SettingsAck of a session (protocol §5.6).
    streaming: bool,
    fresh_command: bool,
    counters: ModuleCounters,
}

/// Settings a module accepts: rate 1..=2000 Hz, lifetime 0.001..=10 s, both finite.
pub fn settings_valid(s: &Settings) -> bool {
    (1.0..=2000.0).contains(&s.feedback_rate_hz) && (0.001..=10.0).contains(&s.command_lifetime_s)
}

impl Module {
    pub fn new(identity: ModuleIdentity, config: ModuleConfig) -> Self {
        Self {
            identity,
            config,
            owner: None,
            settings: Settings::default(),
            command: None,
            last_command_seq: 0,
            feedback_seq: 0,
            next_feedback_s: 0.0,
            feedback_now: false,
            streaming: false,
            fresh_command: false,
            counters: ModuleCounters::default(),
        }
    }

    pub fn identity(&self) -> &ModuleIdentity {
        &self.identity
    }
    pub fn counters(&self) -> ModuleCounters {
        self.counters
    }
    /// A frame of a session that does not own this module (its tag cannot be checked).
    pub fn count_wrong_session(&mut self) {
        self.counters.wrong_session += 1;
    }
    pub fn settings(&self) -> Settings {
        self.settings
    }
    /// The owning session, [`NO_SESSION`] when free.
    pub fn owner_session(&self) -> u32 {
        self.owner.map_or(NO_SESSION, |o| o.session)
    }
    pub fn is_owned(&self) -> bool {
        self.owner.is_some()
    }

    /// The key a frame with `header` must be tagged under: the network key for
    /// discovery and Acquire, the owner's session key for the owner's session; `None`
    /// (count it as wrong-session) for any other session.
    pub fn key_for(&self, header: &Header) -> Option<Key> {
        if header.msg_type.uses_network_key() {
            return Some(self.config.network_key);
        }
        self.owner
            .filter(|o| o.session == header.session)
            .map(|o| o.key)
    }

    /// Handle one message from `from` whose tag was checked under
    /// [`Module::key_for`]; returns the reply, if any.
    pub fn handle(
        &mut self,
        now: ModuleTime,
        from: SocketAddr,
        header: &Header,
        msg: &Message,
    ) -> Option<Outgoing> {
        let network_key = self.config.network_key;
        let reply = |session, message, key| Outgoing {
            dest: from,
            session,
            seq: header.seq,
            message,
            key,
        };
        match msg {
            Message::Lookup(filter) => self.identity.matches(filter).then(|| {
                reply(
                    NO_SESSION,
                    Message::Announce(Announce {
                        mac: self.identity.mac,
                        family: self.identity.family,
                        name: self.identity.name,
                        firmware: self.identity.firmware,
                        owned: self.is_owned(),
                    }),
                    network_key,
                )
            }),
            Message::Acquire(host_nonce) => {
                let s = header.session;
                if s == NO_SESSION {
                    self.counters.wrong_session += 1;
                    return None;
                }
                let module_nonce = self.acquire(now, from, s, host_nonce);
                if module_nonce.is_none() {
                    self.counters.acquire_denied += 1;
                }
                Some(reply(
                    s,
                    Message::AcquireReply(AcquireReply {
                        granted: module_nonce.is_some(),
                        module_nonce: module_nonce.unwrap_or_default(),
                    }),
                    network_key,
                ))
            }
            Message::Release | Message::Settings(_) | Message::Command(_) => {
                let Some(owner) = self.owner.as_mut().filter(|o| o.session == header.session)
                else {
                    self.counters.wrong_session += 1;
                    return None;
                };
                if header.seq <= owner.last_seq {
                    self.counters.replayed += 1;
                    return None;
                }
                owner.last_seq = header.seq;
                owner.last_heard_wall_s = now.wall_s;
                let (session, key) = (owner.session, owner.key);
                match msg {
                    Message::Release => {
                        self.free();
                        None
                    }
                    Message::Settings(s) => {
                        if settings_valid(s) {
                            self.settings = *s;
                            // One feedback right away (lockstep start), then the new rate.
                            self.feedback_now = true;
                            self.next_feedback_s = now.sim_s + 1.0 / f64::from(s.feedback_rate_hz);
                        } else {
                            self.counters.settings_refused += 1;
                            self.feedback_now = true;
                        }
                        self.streaming = true;
                        Some(reply(session, Message::SettingsAck(self.settings), key))
                    }
                    Message::Command(c) => {
                        self.command = Some((*c, now.sim_s));
                        self.last_command_seq = header.seq;
                        self.fresh_command = true;
                        self.counters.commands += 1;
                        None
                    }
                    _ => unreachable!("outer match admits only these three"),
                }
            }
            Message::Announce(_)
            | Message::AcquireReply(_)
            | Message::SettingsAck(_)
            | Message::Feedback(_) => {
                self.counters.unexpected += 1;
                None
            }
        }
    }

    /// Grant session `s` (returning the module's nonce) or deny it (`None`). The
    /// owner's own Acquire again (same session and nonce: a resend whose reply was
    /// lost) gets the same answer and changes nothing, not even who hears feedback, so
    /// a replayed Acquire cannot move the stream. On a new grant `from` becomes the
    /// feedback destination.
    fn acquire(
        &mut self,
        now: ModuleTime,
        from: SocketAddr,
        s: u32,
        host_nonce: &Nonce,
    ) -> Option<Nonce> {
        match self.owner {
            Some(o) if o.session == s && o.host_nonce == *host_nonce => {
                return Some(o.module_nonce);
            }
            Some(o) if now.wall_s - o.last_heard_wall_s <= self.config.release_timeout_s => {
                return None;
            }
            _ => {}
        }
        // A new owner starts from a clean slate.
        self.free();
        self.next_feedback_s = now.sim_s;
        let module_nonce: Nonce = rand::random();
        let key =
            self.config
                .network_key
                .session_key(s, &self.identity.mac, host_nonce, &module_nonce);
        self.owner = Some(Owner {
            session: s,
            addr: from,
            last_heard_wall_s: now.wall_s,
            host_nonce: *host_nonce,
            module_nonce,
            key,
            last_seq: 0,
        });
        Some(module_nonce)
    }

    fn free(&mut self) {
        self.owner = None;
        self.settings = Settings::default();
        self.command = None;
        self.last_command_seq = 0;
        self.fresh_command = false;
        self.feedback_now = false;
        self.streaming = false;
    }

    /// What the plant should drive now: the newest command while it is younger than
    /// the lifetime, LIMP otherwise (also when free or the strategy is Off).
    pub fn applied_command(&self, sim_s: f64) -> Command {
        match self.command {
            Some((c, at_s))
                if self.owner.is_some()
                    && self.settings.strategy != ControlStrategy::Off
                    && sim_s - at_s < f64::from(self.settings.command_lifetime_s) =>
            {
                c
            }
            _ => Command::LIMP,
        }
    }

    /// True when a command arrived since the last [`Module::clear_fresh_command`].
    pub fn has_fresh_command(&self) -> bool {
        self.fresh_command
    }
    /// Lockstep: the world stepped with this module's command.
    pub fn clear_fresh_command(&mut self) {
        self.fresh_command = false;
    }

    /// True when settings were just acknowledged and one feedback should go out at
    /// once (lockstep sends nothing else outside a step).
    pub fn feedback_requested(&self) -> bool {
        self.is_streaming() && self.feedback_now
    }

    /// Owned and configured: the module sends feedback to its owner (protocol §5.6).
    pub fn is_streaming(&self) -> bool {
        self.owner.is_some() && self.streaming
    }

    /// True when an owned module should send feedback now (its rate schedule is due,
    /// or settings were just acknowledged).
    pub fn feedback_due(&self, sim_s: f64) -> bool {
        // A nanosecond of slack absorbs rounding of the accumulated schedule.
        self.is_streaming() && (self.feedback_now || sim_s + 1e-9 >= self.next_feedback_s)
    }

    /// Build the next feedback to the owner from the plant's sample and advance the
    /// counter and the schedule; `None` unless the module is streaming.
    pub fn make_feedback(&mut self, sim_s: f64, sample: Feedback) -> Option<Outgoing> {
        if !self.streaming {
            return None;
        }
        let owner = self.owner?;
        let period_s = 1.0 / f64::from(self.settings.feedback_rate_hz);
        if self.feedback_now {
            self.feedback_now = false;
        } else {
            self.next_feedback_s += period_s;
            if self.next_feedback_s + 1e-9 < sim_s {
                // Fell behind (a stall): resume the schedule from now, do not burst.
                self.next_feedback_s = sim_s + period_s;
            }
        }
        self.feedback_seq += 1;
        self.counters.feedback_sent += 1;
        Some(Outgoing {
            dest: owner.addr,
            session: owner.session,
            seq: self.feedback_seq,
            key: owner.key,
            message: Message::Feedback(Feedback {
                last_command_seq: self.last_command_seq,
                ..sample
            }),
        })
    }
}

#[cfg(test)]
#[path = "module_tests.rs"]
mod tests;
