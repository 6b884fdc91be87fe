//! The loop's view of the module network, whatever carries it. `UdpBus` talks to
//! real or emulated modules over UDP (protocol v2); `emu::sim_bus::SimBus` steps an
//! in-process emulator. The loop and the controllers cannot tell them apart; what a
//! bus knows beyond [`Bus`] (the UDP bus's reasons for dropping datagrams, the
//! simulated bus's ground truth) is reached through the bus's own type.

mod counters;
pub mod echo;
pub mod hebi;
pub mod udp;

use std::any::Any;

pub use counters::{BusCounters, CounterSet, MAX_DETAIL};

use crate::module::{Command, Feedback};

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
/// `Any`: a caller that built a particular bus reaches its own methods through
/// `&dyn Any` (e.g. `SimBus::of`).
pub trait Bus: Send + Any {
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
}
