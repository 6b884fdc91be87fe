//! The UDP module emulator, protocol v2, with a [`Plant`] behind it, served by one
//! thread. Two layouts of endpoints:
//! - **per module** (the default, like modules with their own network ports): module
//!   `i` is the non-blocking UDP endpoint `bind_ip:base_port + i`, unit 0;
//! - **gateway** (`gateway: true`, like a tether hub): one endpoint on `base_port`
//!   serves module `i` as unit `i`, and the frames to one destination travel bundled
//!   in as few datagrams as fit (one command datagram and one feedback datagram per
//!   cycle for an 18-module snake).
//!
//! - **Real time**: physics at `1 / physics_dt_s` on absolute deadlines
//!   (`clock_nanosleep(TIMER_ABSTIME)`); each tick drains every socket, steps the
//!   plant, sends the feedback that is due and releases delayed feedback. When the
//!   loop falls more than 20 periods behind it resynchronises instead of bursting.
//! - **Lockstep**: waits in `poll(2)` until every owned (and not silenced) module has
//!   received a command since the last step, or `lockstep_timeout_s` passed since it;
//!   then steps once and every owned (configured) module sends exactly one feedback.
//!   Feedback delay does not apply in lockstep (the simulated clock stands still while
//!   waiting).
//!
//! Replies (announce, acquire reply, settings ack) are never subject to faults.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use super::Plant;
use super::faults::{DelayQueue, FaultConfig, FaultError, Faults};
use super::module::{
    EMULATOR_FIRMWARE, Module, ModuleConfig, ModuleIdentity, ModuleTime, Outgoing,
};
use super::pose_csv::PoseCsv;
use super::truth_csv::{CsvError, TruthCsv};
use crate::protocol::{
    Command, DecodeError, Feedback, Key, MAX_DATAGRAM, Message, Name, VERSION_1,
};
use crate::rt::sys;

mod datagrams;
mod io;

/// How the emulator paces its world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    Realtime,
    Lockstep,
}

/// Everything the UDP emulator needs besides its plant.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    pub bind_ip: IpAddr,
    /// Module `i` binds `base_port + i` (the gateway binds `base_port`); 0 lets the OS
    /// pick free ports (read them back with [`Server::local_addrs`]).
    pub base_port: u16,
    /// One endpoint for every module (units 0..n) instead of one each.
    pub gateway: bool,
    pub mode: Mode,
    /// Physics step, s.
    pub physics_dt_s: f64,
    /// Lockstep: step anyway when no complete command round came for this long, s (wall).
    pub lockstep_timeout_s: f64,
    pub family: String,
    pub firmware: u32,
    pub module: ModuleConfig,
    pub faults: FaultConfig,
    /// Ground-truth CSV (see [`super::truth_csv`]).
    pub record: Option<PathBuf>,
    /// Body poses and contacts CSV (see [`super::pose_csv`]).
    pub record_poses: Option<PathBuf>,
    /// Stop after this much simulated time, s.
    pub duration_s: Option<f64>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            bind_ip: IpAddr::V4(Ipv4Addr::LOCALHOST),
            base_port: 7000,
            gateway: false,
            mode: Mode::Realtime,
            physics_dt_s: 1e-3,
            lockstep_timeout_s: 1.0,
            family: "SEA".to_owned(),
            firmware: EMULATOR_FIRMWARE,
            module: ModuleConfig::default(),
            faults: FaultConfig::default(),
            record: None,
            record_poses: None,
            duration_s: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum EmuServerError {
    #[error("cannot bind module {module} to {addr}: {source}")]
    Bind {
        module: usize,
        addr: SocketAddr,
        #[source]
        source: std::io::Error,
    },
    #[error("socket error: {0}")]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Record(#[from] CsvError),
    #[error(transparent)]
    Faults(#[from] FaultError),
    #[error("invalid configuration: {0}")]
    Config(&'static str),
}

/// What the emulator saw and did; monotonically increasing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct ServerCounters {
    /// Datagrams received (before faults and decoding).
    pub received: u64,
    pub bad_truncated: u64,
    pub bad_magic: u64,
    pub bad_version: u64,
    pub bad_type: u64,
    pub bad_length: u64,
    /// Frames whose tag did not verify: corrupted, forged, or of another session.
    pub bad_tag: u64,
    pub bad_malformed: u64,
    /// Datagrams of protocol version 1, which this emulator no longer speaks.
    pub v1_refused: u64,
    /// Frames for a unit the endpoint does not serve.
    pub bad_unit: u64,
    pub wrong_session: u64,
    /// Authenticated frames whose seq was not newer than the newest accepted.
    pub replayed: u64,
    /// Well-formed messages a module never accepts.
    pub unexpected: u64,
    pub commands: u64,
    /// Datagrams sent (replies and feedback).
    pub sent: u64,
    pub send_errors: u64,
    pub recv_errors: u64,
    pub dropped_feedback_loss: u64,
    pub dropped_command_loss: u64,
    /// Datagrams to or from a silenced module.
    pub dropped_silent: u64,
    pub dropped_delay_full: u64,
    pub steps: u64,
    pub lockstep_timeouts: u64,
    /// Real time: times the loop fell too far behind and resynchronised.
    pub overruns: u64,
}

impl ServerCounters {
    fn count_decode_error(&mut self, e: DecodeError) {
        let c = match e {
            DecodeError::Truncated => &mut self.bad_truncated,
            DecodeError::BadMagic => &mut self.bad_magic,
            DecodeError::WrongVersion(VERSION_1) => &mut self.v1_refused,
            DecodeError::WrongVersion(_) => &mut self.bad_version,
            DecodeError::UnknownType(_) => &mut self.bad_type,
            DecodeError::BadLength => &mut self.bad_length,
            DecodeError::BadTag => &mut self.bad_tag,
            DecodeError::Malformed(_) => &mut self.bad_malformed,
        };
        *c += 1;
    }
}

/// Feedback held back by the delay fault.
#[derive(Debug, Clone, Copy)]
struct Delayed {
    module: usize,
    dest: SocketAddr,
    session: u32,
    seq: u64,
    key: Key,
    feedback: Feedback,
}

/// Frames waiting to leave one endpoint, bundled per destination.
struct Outbox {
    buf: Vec<u8>,
    len: usize,
    dest: Option<SocketAddr>,
}

/// The UDP emulator (see the module docs).
pub struct Server {
    config: ServerConfig,
    sockets: Vec<UdpSocket>,
    poll: io::PollSet,
    modules: Vec<Module>,
    plant: Box<dyn Plant>,
    faults: Faults,
    delayed: DelayQueue<Delayed>,
    applied: Vec<Command>,
    truth_csv: Option<TruthCsv>,
    pose_csv: Option<PoseCsv>,
    counters: ServerCounters,
    recv_buf: Vec<u8>,
    /// One per endpoint.
    outboxes: Vec<Outbox>,
    start_ns: u64,
}

impl Server {
    /// Bind one socket per plant module and set everything up; nothing runs yet.
    pub fn new(config: ServerConfig, plant: Box<dyn Plant>) -> Result<Self, EmuServerError> {
        if !(config.physics_dt_s.is_finite() && config.physics_dt_s > 0.0) {
            return Err(EmuServerError::Config("physics_dt_s must be > 0"));
        }
        if !(config.lockstep_timeout_s.is_finite() && config.lockstep_timeout_s > 0.0) {
            return Err(EmuServerError::Config("lockstep_timeout_s must be > 0"));
        }
        let n = plant.module_count();
        if n == 0 {
            return Err(EmuServerError::Config("the plant has no modules"));
        }
        let endpoints = if config.gateway { 1 } else { n };
        if config.base_port != 0
            && usize::from(config.base_port) + endpoints - 1 > usize::from(u16::MAX)
        {
            return Err(EmuServerError::Config("base_port + modules exceeds 65535"));
        }
        if n > usize::from(u16::MAX) + 1 {
            return Err(EmuServerError::Config("more modules than units"));
        }
        let family = Name::new(&config.family)
            .map_err(|_| EmuServerError::Config("family name too long"))?;
        let faults = Faults::new(config.faults.clone(), n)?;
        let mut sockets = Vec::with_capacity(endpoints);
        for i in 0..endpoints {
            let port = if config.base_port == 0 {
                0
            } else {
                config.base_port + i as u16
            };
            let addr = SocketAddr::new(config.bind_ip, port);
            let bind_err = |source| EmuServerError::Bind {
                module: i,
                addr,
                source,
            };
            let sock = UdpSocket::bind(addr).map_err(bind_err)?;
            sock.set_nonblocking(true).map_err(bind_err)?;
            sockets.push(sock);
        }
        let modules = (0..n)
            .map(|i| {
                Module::new(
                    ModuleIdentity::emulated(i, n, family, config.firmware),
                    config.module,
                )
            })
            .collect();
        let truth_csv = match &config.record {
            Some(path) => Some(TruthCsv::create(path, n)?),
            None => None,
        };
        let pose_csv = match &config.record_poses {
            Some(path) => Some(PoseCsv::create(path, plant.link_count())?),
            None => None,
        };
        Ok(Self {
            poll: io::PollSet::new(&sockets),
            delayed: DelayQueue::with_capacity(config.faults.delay_capacity),
            applied: vec![Command::LIMP; n],
            config,
            sockets,
            modules,
            plant,
            faults,
            truth_csv,
            pose_csv,
            counters: ServerCounters::default(),
            recv_buf: vec![0; 2 * MAX_DATAGRAM],
            outboxes: (0..endpoints)
                .map(|_| Outbox {
                    buf: vec![0; MAX_DATAGRAM],
                    len: 0,
                    dest: None,
                })
                .collect(),
            start_ns: sys::monotonic_ns(),
        })
    }

    /// Address of each endpoint: one per module, module 0 first, or the gateway's.
    pub fn local_addrs(&self) -> Result<Vec<SocketAddr>, EmuServerError> {
        Ok(self
            .sockets
            .iter()
            .map(|s| s.local_addr())
            .collect::<Result<_, _>>()?)
    }

    pub fn module_count(&self) -> usize {
        self.modules.len()
    }

    /// Simulated time, s.
    pub fn time_s(&self) -> f64 {
        self.plant.time_s()
    }

    /// Counters so far, including the modules' own (wrong session, unexpected, commands).
    pub fn counters(&self) -> ServerCounters {
        let mut c = self.counters;
        for m in &self.modules {
            let mc = m.counters();
            c.wrong_session += mc.wrong_session;
            c.replayed += mc.replayed;
            c.unexpected += mc.unexpected;
            c.commands += mc.commands;
        }
        c
    }

    /// Serve until `stop` is set or `duration_s` of simulated time has passed; flushes
    /// the recording on the way out and returns the counters.
    pub fn run(&mut self, stop: &AtomicBool) -> Result<ServerCounters, EmuServerError> {
        self.start_ns = sys::monotonic_ns();
        let result = match self.config.mode {
            Mode::Realtime => self.run_realtime(stop),
            Mode::Lockstep => self.run_lockstep(stop),
        };
        if let Some(r) = self.truth_csv.as_mut() {
            r.flush()?;
        }
        if let Some(r) = self.pose_csv.as_mut() {
            r.flush()?;
        }
        result.map(|()| self.counters())
    }

    fn done(&self, stop: &AtomicBool) -> bool {
        stop.load(Ordering::Relaxed)
            || self
                .config
                .duration_s
                .is_some_and(|d| self.plant.time_s() >= d - 1e-9)
    }

    fn now(&self) -> ModuleTime {
        ModuleTime {
            sim_s: self.plant.time_s(),
            wall_s: self.wall_s(),
        }
    }

    fn wall_s(&self) -> f64 {
        sys::monotonic_ns().saturating_sub(self.start_ns) as f64 * 1e-9
    }

    fn run_realtime(&mut self, stop: &AtomicBool) -> Result<(), EmuServerError> {
        let period_ns = (self.config.physics_dt_s * 1e9).round() as u64;
        let mut deadline_ns = sys::monotonic_ns();
        while !self.done(stop) {
            self.drain_all();
            self.step()?;
            let t = self.plant.time_s();
            for i in 0..self.modules.len() {
                if self.modules[i].feedback_due(t) {
                    self.send_feedback(i, true);
                }
            }
            self.release_delayed();
            self.flush_all();
            deadline_ns += period_ns;
            let now_ns = sys::monotonic_ns();
            if now_ns > deadline_ns + 20 * period_ns {
                self.counters.overruns += 1;
                deadline_ns = now_ns;
            } else {
                sys::sleep_until_ns(deadline_ns);
            }
        }
        Ok(())
    }

    fn run_lockstep(&mut self, stop: &AtomicBool) -> Result<(), EmuServerError> {
        let timeout_s = self.config.lockstep_timeout_s;
        let mut last_step_wall_s = self.wall_s();
        while !self.done(stop) {
            let waited_s = self.wall_s() - last_step_wall_s;
            // Wake at least every 50 ms to look at the stop flag.
            let wait_ms = ((timeout_s - waited_s) * 1e3).clamp(0.0, 50.0).ceil() as i32;
            self.poll.wait(wait_ms)?;
            self.drain_all();
            // Settings just acknowledged: one feedback at the current time.
            let t = self.plant.time_s();
            for i in 0..self.modules.len() {
                if self.modules[i].feedback_requested() {
                    self.send_feedback(i, false);
                }
            }
            self.flush_all();
            let mut any_owned = false;
            let mut all_fresh = true;
            for (i, m) in self.modules.iter().enumerate() {
                if m.is_owned() && !self.faults.is_silent(i, t) {
                    any_owned = true;
                    all_fresh &= m.has_fresh_command();
                }
            }
            let ready = any_owned && all_fresh;
            let timed_out = self.wall_s() - last_step_wall_s >= timeout_s;
            if !(ready || timed_out) {
                continue;
            }
            if !ready {
                self.counters.lockstep_timeouts += 1;
            }
            self.step()?;
            last_step_wall_s = self.wall_s();
            for i in 0..self.modules.len() {
                self.modules[i].clear_fresh_command();
                if self.modules[i].is_streaming() {
                    self.send_feedback(i, false);
                }
            }
            self.flush_all();
        }
        Ok(())
    }

    /// One physics step with the commands each module applies right now.
    fn step(&mut self) -> Result<(), EmuServerError> {
        let t = self.plant.time_s();
        for (c, m) in self.applied.iter_mut().zip(&self.modules) {
            *c = m.applied_command(t);
        }
        self.plant.step(self.config.physics_dt_s, &self.applied);
        self.counters.steps += 1;
        if let Some(r) = self.truth_csv.as_mut() {
            r.row(self.plant.as_ref(), &self.applied)?;
        }
        if let Some(r) = self.pose_csv.as_mut() {
            r.row(self.plant.as_ref())?;
        }
        Ok(())
    }

    /// Build module `i`'s next feedback and send it through the faults.
    fn send_feedback(&mut self, i: usize, may_delay: bool) {
        let t = self.plant.time_s();
        if self.faults.is_silent(i, t) {
            self.counters.dropped_silent += 1;
            return;
        }
        let mut sample = self.plant.feedback(i);
        if self.config.mode == Mode::Realtime {
            // A module's clock is its own crystal, not the physics: when the world
            // stalls (an overloaded machine) the clock runs on, as on a real module.
            sample.module_time_us = (self.wall_s() * 1e6) as u64;
        }
        let Some(out) = self.modules[i].make_feedback(t, sample) else {
            return;
        };
        if self.faults.lose() {
            self.counters.dropped_feedback_loss += 1;
            return;
        }
        let delay_s = self.faults.delay_s();
        if may_delay && delay_s > 0.0 {
            if let Message::Feedback(feedback) = out.message {
                let d = Delayed {
                    module: i,
                    dest: out.dest,
                    session: out.session,
                    seq: out.seq,
                    key: out.key,
                    feedback,
                };
                if self.delayed.push(t + delay_s, d).is_err() {
                    self.counters.dropped_delay_full += 1;
                }
            }
            return;
        }
        self.send(i, &out);
    }

    fn release_delayed(&mut self) {
        let t = self.plant.time_s();
        while let Some(d) = self.delayed.pop_due(t + 1e-9) {
            let out = Outgoing {
                dest: d.dest,
                session: d.session,
                seq: d.seq,
                message: Message::Feedback(d.feedback),
                key: d.key,
            };
            self.send(d.module, &out);
        }
    }
}
