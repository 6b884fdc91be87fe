//! The loop's view of the module network. `UdpBus` talks to real or emulated
//! modules over UDP; `SimBus` steps an in-process emulator. The loop and the
//! controllers cannot tell them apart.

pub mod echo;
pub mod sim;
pub mod udp;

use crate::protocol::{Command, Feedback};

/// Newest feedback of one module as the loop sees it.
#[derive(Debug, Clone, Copy, Default)]
pub struct ModuleState {
    pub feedback: Feedback,
    /// When the newest feedback arrived, ns on the loop's clock (over UDP, the kernel's
    /// receive stamp); `None` before the first.
    pub received_ns: Option<u64>,
    /// How late it already was on arrival by the module's own clock: its
    /// `module_time_us` against the host's clock, offset and drift tracked per module
    /// (`bus::udp::clock`). `None` when not measured (lockstep, in-process buses).
    pub clock_age_ns: Option<u64>,
    /// True when new feedback arrived during the last `receive` call.
    pub fresh: bool,
    /// How long ago, ns on the loop's clock, the daemon sent the command this feedback
    /// says the module had applied (`last_command_seq`): the round trip, an upper bound
    /// on how old the data are, which a delay anywhere on the path shows (the receive
    /// time alone does not). `None` before the first command or on an in-process bus.
    pub command_age_ns: Option<u64>,
}

/// Feedback of the whole group, sized once at start-up; index 0 is the head.
#[derive(Debug, Clone)]
pub struct GroupFeedback {
    pub modules: Vec<ModuleState>,
}

impl GroupFeedback {
    pub fn new(n: usize) -> Self {
        Self {
            modules: vec![ModuleState::default(); n],
        }
    }
    pub fn len(&self) -> usize {
        self.modules.len()
    }
    pub fn is_empty(&self) -> bool {
        self.modules.is_empty()
    }
}

/// Counters a bus keeps for the statistics; monotonically increasing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct BusCounters {
    pub feedback_received: u64,
    /// Feedback sequence gaps (datagrams the network lost).
    pub feedback_lost: u64,
    /// Authenticated feedback not newer than the newest held (replayed or reordered).
    pub feedback_replayed: u64,
    pub commands_sent: u64,
    /// Send calls that failed (socket full, unreachable).
    pub send_errors: u64,
    /// Datagrams dropped, by reason.
    pub bad_truncated: u64,
    pub bad_magic: u64,
    pub bad_version: u64,
    /// Datagrams of protocol v1 (an old module or emulator): refused.
    pub v1_refused: u64,
    pub bad_type: u64,
    pub bad_length: u64,
    /// Frames whose tag did not verify: corrupted, forged, or of another session.
    pub bad_tag: u64,
    pub bad_malformed: u64,
    pub wrong_session: u64,
    /// Well-formed datagrams from an address that is not in the group, or of a type
    /// the loop does not expect.
    pub unexpected: u64,
}

/// How `receive` waits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FeedbackWait {
    /// Take what has arrived and return at once (real-time pacing).
    None,
    /// Lockstep: block until every module has reported feedback with
    /// `module_time_us >= min_module_time_us`, or until `timeout_ns` elapses.
    Lockstep {
        min_module_time_us: u64,
        timeout_ns: u64,
    },
}

#[derive(Debug, thiserror::Error)]
pub enum BusError {
    #[error("bus I/O error: {0}")]
    Io(#[from] std::io::Error),
    #[error("lockstep feedback did not arrive in time")]
    LockstepTimeout,
    #[error("expected {expected} commands, got {got}")]
    WrongCount { expected: usize, got: usize },
}

/// The module network as the loop uses it. Implementations never allocate in
/// `send` or `receive` and never block in them except as `FeedbackWait` allows.
pub trait Bus: Send {
    /// Number of modules in the group.
    fn module_count(&self) -> usize;
    /// Send one command per module, head first.
    fn send(&mut self, commands: &[Command]) -> Result<(), BusError>;
    /// Update `group` with feedback that arrived since the last call (newest per
    /// module; `fresh` set for modules that reported). `now_ns` is the loop's clock.
    fn receive(
        &mut self,
        group: &mut GroupFeedback,
        now_ns: u64,
        wait: FeedbackWait,
    ) -> Result<(), BusError>;
    fn counters(&self) -> BusCounters;
    /// Hand the modules back (release the session). Called once at shutdown.
    fn release(&mut self) {}
    /// The simulated plant behind an in-process bus, for ground truth (the lab's
    /// metrics, the recorder's 3-D scene); `None` for real modules.
    fn plant(&self) -> Option<&dyn crate::emu::Plant> {
        None
    }
}
