//! `HebiBus`: modules driven through HEBI's C library (`libhebi`), loaded at run time.
//! The library's thread delivers group feedback into a triple buffer ([`mailbox`]); the
//! loop takes the newest whole group feedback each cycle without waiting, and sends
//! each cycle's set-points as one group command. Below the bus, a [`group::Group`] is
//! libhebi's group ([`group::LibGroup`], from a lookup or an imitation group) or the
//! test fake ([`fake::FakeGroup`]). docs/hebi.md is the operator's page.

pub mod fake;
pub mod ffi;
pub mod gains;
pub mod group;
pub mod library;
pub mod lookup;
pub mod mailbox;
pub mod message;
#[cfg(test)]
pub(crate) mod tests;

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use crate::bus::{Bus, BusCounters, BusError, CounterSet, FeedbackWait, GroupFeedback};
use crate::module::Command;
use group::Group;
use mailbox::{GroupSample, WriterCounters};

/// The bus's own counters (`stats.bus.detail`).
const DETAIL: &[&str] = &["group_feedbacks", "superseded", "absent", "repeated"];

pub struct HebiBus {
    group: Box<dyn Group>,
    feedback: triple_buffer::Output<GroupSample>,
    writer: Arc<WriterCounters>,
    last_number: u64,
    /// Each module's last library receive time: a repeat is old data.
    last_receive_us: Vec<Option<u64>>,
    counters: BusCounters,
    repeated: u64,
    released: bool,
    /// A feedback rate asked for from another thread (f32 bits; `NO_REQUEST` = none).
    rate_request: Arc<AtomicU32>,
}

const NO_REQUEST: u32 = u32::MAX;

/// Changes the group's feedback rate from another thread, at the bus's next send
/// (0 Hz stops the stream: how the tests stall a live group).
#[derive(Clone)]
pub struct FeedbackSwitch(Arc<AtomicU32>);

impl FeedbackSwitch {
    pub fn set_rate_hz(&self, hz: f32) {
        self.0.store(hz.to_bits(), Relaxed);
    }
}

/// How the bus sets up its group at start.
#[derive(Debug, Clone, Default)]
pub struct Start {
    pub feedback_rate_hz: f32,
    pub command_lifetime_ms: i32,
    /// Gains and strategy per module, head first (empty: leave the modules' own).
    pub settings: Vec<gains::ModuleSettings>,
}

impl HebiBus {
    /// Takes `group` (whose feedback goes to `feedback`, written by a writer whose
    /// counters are `writer`), sends the settings and starts the feedback.
    pub fn start(
        mut group: Box<dyn Group>,
        feedback: triple_buffer::Output<GroupSample>,
        writer: Arc<WriterCounters>,
        start: &Start,
    ) -> Result<Self, String> {
        let n = group.len();
        if !start.settings.is_empty() {
            group.configure(&start.settings)?;
        }
        group.set_command_lifetime_ms(start.command_lifetime_ms)?;
        group.set_feedback_rate_hz(start.feedback_rate_hz)?;
        Ok(Self {
            group,
            feedback,
            writer,
            last_number: 0,
            last_receive_us: vec![None; n],
            counters: BusCounters {
                detail: CounterSet::new(DETAIL),
                ..BusCounters::default()
            },
            repeated: 0,
            released: false,
            rate_request: Arc::new(AtomicU32::new(NO_REQUEST)),
        })
    }

    /// Stops (hz = 0) or restarts the group's feedback stream.
    pub fn set_feedback_rate_hz(&mut self, hz: f32) -> Result<(), String> {
        self.group.set_feedback_rate_hz(hz)
    }

    /// A handle that changes the feedback rate while the loop owns the bus.
    pub fn feedback_switch(&self) -> FeedbackSwitch {
        FeedbackSwitch(self.rate_request.clone())
    }
}

impl Bus for HebiBus {
    fn module_count(&self) -> usize {
        self.group.len()
    }

    fn send(&mut self, commands: &[Command]) -> Result<(), BusError> {
        let n = self.group.len();
        if commands.len() != n {
            return Err(BusError::WrongCount {
                expected: n,
                got: commands.len(),
            });
        }
        let asked = self.rate_request.swap(NO_REQUEST, Relaxed);
        if asked != NO_REQUEST
            && self
                .group
                .set_feedback_rate_hz(f32::from_bits(asked))
                .is_err()
        {
            self.counters.send_errors += 1;
        }
        if self.group.send(commands) {
            self.counters.commands_sent += 1;
        } else {
            self.counters.send_errors += 1;
        }
        Ok(())
    }

    fn receive(
        &mut self,
        group: &mut GroupFeedback,
        now_ns: u64,
        wait: FeedbackWait,
    ) -> Result<(), BusError> {
        // The library paces its own feedback: lockstep is refused at --check-config.
        debug_assert_eq!(wait, FeedbackWait::None);
        if group.len() != self.last_receive_us.len() {
            return Err(BusError::WrongCount {
                expected: self.last_receive_us.len(),
                got: group.len(),
            });
        }
        for m in &mut group.modules {
            m.fresh = false;
        }
        self.feedback.update();
        let s = self.feedback.output_buffer();
        if s.number == self.last_number {
            return Ok(());
        }
        self.last_number = s.number;
        // Arrival on the loop's clock: `now_ns` less how long ago (monotonic) it came.
        let ago_ns = mailbox::monotonic_ns().saturating_sub(s.arrival_ns);
        let arrived_ns = now_ns.saturating_sub(ago_ns);
        for ((m, smp), last) in group
            .modules
            .iter_mut()
            .zip(&s.modules)
            .zip(&mut self.last_receive_us)
        {
            if !smp.present {
                continue;
            }
            if smp.receive_time_us.is_some() && smp.receive_time_us == *last {
                self.repeated += 1;
                continue;
            }
            *last = smp.receive_time_us;
            m.feedback = smp.feedback;
            m.received_ns = Some(arrived_ns);
            m.fresh = true;
            self.counters.feedback_received += 1;
        }
        Ok(())
    }

    fn counters(&self) -> BusCounters {
        let mut c = self.counters;
        let w = &self.writer;
        let absent = w.absent.load(Relaxed);
        c.feedback_lost = absent;
        c.feedback_replayed = self.repeated;
        for (i, v) in [
            w.group_feedbacks.load(Relaxed),
            w.superseded.load(Relaxed),
            absent,
            self.repeated,
        ]
        .into_iter()
        .enumerate()
        {
            c.detail.set(i, v);
        }
        c
    }

    /// Commands every module limp explicitly, then lets the group go.
    fn release(&mut self) {
        if self.released {
            return;
        }
        self.released = true;
        let limp = vec![Command::LIMP; self.group.len()];
        self.group.send(&limp);
        self.group.release();
    }
}

impl Drop for HebiBus {
    fn drop(&mut self) {
        self.release();
    }
}
