//! The seam below the HEBI bus: a group of modules that takes one command per module
//! and delivers group feedback into a [`FeedbackWriter`] on its own thread. [`LibGroup`]
//! is libhebi's group (from a lookup, or an imitation group); `super::fake::FakeGroup`
//! covers what an imitation group does not model (IMU, lost modules, lifetime, gains).

use std::ffi::c_void;

use super::ffi::{GroupCommandPtr, GroupFeedbackPtr, GroupPtr, MessageRef, STATUS_SUCCESS};
use super::gains::ModuleSettings;
use super::library::Api;
use super::mailbox::FeedbackWriter;
use super::message::{self, Sample};
use crate::module::Command;

/// What the bus needs of a group. Commands are head first (body order).
pub trait Group: Send {
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Sends one group command; false when the library refused it. Never blocks.
    fn send(&mut self, commands: &[Command]) -> bool;
    /// How long a module keeps acting on a command, ms (0 = until the next).
    fn set_command_lifetime_ms(&mut self, ms: i32) -> Result<(), String>;
    /// How often the group's feedback is requested (0 stops the stream).
    fn set_feedback_rate_hz(&mut self, hz: f32) -> Result<(), String>;
    /// Sends gains and strategy, one entry per module head first, and waits for the
    /// acknowledgement (start-up only).
    fn configure(&mut self, settings: &[ModuleSettings]) -> Result<(), String>;
    /// Stops the feedback and lets the group go.
    fn release(&mut self);
}

/// What the library's feedback thread holds.
struct Handler {
    api: &'static Api,
    writer: FeedbackWriter,
}

/// libhebi's feedback callback: reads the group feedback into the mailbox.
unsafe extern "C" fn on_feedback(fbk: GroupFeedbackPtr, user: *mut c_void) {
    // SAFETY: `user` is the `Handler` registered with this callback; the library calls
    // it from one thread and LibGroup frees it only after clearing the handler.
    let h = unsafe { &mut *(user as *mut Handler) };
    let api = h.api;
    // SAFETY: `fbk` is live for the duration of the call.
    let size = unsafe { (api.f.group_feedback_get_size)(fbk) };
    let arrival_ns = super::mailbox::monotonic_ns();
    h.writer.publish(arrival_ns, |g| {
        if g >= size {
            return Sample::default();
        }
        // SAFETY: g < size; the reference is filled by the library for that message.
        unsafe {
            let m = (api.f.group_feedback_get_module_feedback)(fbk, g);
            if m.is_null() {
                return Sample::default();
            }
            let mut r = MessageRef::NULL;
            (api.f.feedback_get_reference)(m, &mut r);
            if r.message_bitfield.is_null() {
                return Sample::default();
            }
            message::read_feedback(&r, &api.feedback)
        }
    });
}

/// A libhebi group; `order[i]` is the group index of body position `i`.
pub struct LibGroup {
    api: &'static Api,
    group: GroupPtr,
    /// Released with the group (a group from a lookup may need it alive).
    lookup: super::ffi::LookupPtr,
    command: GroupCommandPtr,
    /// Each body position's command message reference (head first).
    refs: Vec<MessageRef>,
    /// For an imitation group, which echoes only what was commanded, each module's
    /// last commanded position (`message::write_command`); `None` for real modules.
    imitation: Option<Vec<f32>>,
    handler: *mut Handler,
}

// SAFETY: the handles are used from one thread at a time (the loop's); the handler's
// state is only touched by the library's thread until `release`.
unsafe impl Send for LibGroup {}

impl LibGroup {
    /// Takes `group` (and the `lookup` it came from, or null) and starts its feedback
    /// into `writer`, which is in body order `order`.
    ///
    /// # Safety
    /// `group` is a live group of `order.len()` modules; ownership passes here.
    pub unsafe fn new(
        api: &'static Api,
        group: GroupPtr,
        lookup: super::ffi::LookupPtr,
        order: &[usize],
        imitation: bool,
        writer: FeedbackWriter,
    ) -> Result<Self, String> {
        // SAFETY: live group (caller).
        let size = unsafe { (api.f.group_get_size)(group) };
        if size != order.len() || order.iter().any(|&g| g >= size) {
            // SAFETY: ours to release (caller).
            unsafe {
                (api.f.group_release)(group);
                if !lookup.is_null() {
                    (api.f.lookup_release)(lookup);
                }
            }
            return Err(format!(
                "the group has {size} modules, the body {}",
                order.len()
            ));
        }
        let command = unsafe { (api.f.group_command_create)(size) };
        let mut refs = Vec::with_capacity(order.len());
        for &g in order {
            let mut r = MessageRef::NULL;
            // SAFETY: g < size (order is a permutation of 0..size, checked by callers).
            unsafe {
                let c = (api.f.group_command_get_module_command)(command, g);
                (api.f.command_get_reference)(c, &mut r);
            }
            refs.push(r);
        }
        let handler = Box::into_raw(Box::new(Handler { api, writer }));
        let mut me = Self {
            api,
            group,
            lookup,
            command,
            imitation: imitation.then(|| vec![0.0; refs.len()]),
            refs,
            handler,
        };
        // SAFETY: the handler and its state stay valid until `release` clears it.
        let status = unsafe {
            (api.f.group_register_feedback_handler)(group, on_feedback, handler as *mut c_void)
        };
        if status != STATUS_SUCCESS {
            let why = format!("registering the feedback handler: {}", api.last_error());
            me.release();
            return Err(why);
        }
        Ok(me)
    }

    fn status(&self, what: &str, status: i32) -> Result<(), String> {
        if status == STATUS_SUCCESS {
            Ok(())
        } else {
            Err(format!(
                "{what}: status {status}: {}",
                self.api.last_error()
            ))
        }
    }
}

impl Group for LibGroup {
    fn len(&self) -> usize {
        self.refs.len()
    }

    fn send(&mut self, commands: &[Command]) -> bool {
        for (i, (r, c)) in self.refs.iter().zip(commands).enumerate() {
            let last = self.imitation.as_mut().map(|p| {
                if c.position_rad.is_finite() {
                    p[i] = c.position_rad;
                }
                p[i]
            });
            // SAFETY: a live command message of ours, laid out by the loaded library.
            unsafe { message::write_command(r, &self.api.command, c, last) };
        }
        // SAFETY: live group and command; this call only queues the datagram.
        unsafe { (self.api.f.group_send_command)(self.group, self.command) == STATUS_SUCCESS }
    }

    fn set_command_lifetime_ms(&mut self, ms: i32) -> Result<(), String> {
        // SAFETY: live group.
        let s = unsafe { (self.api.f.group_set_command_lifetime)(self.group, ms) };
        self.status("setting the command lifetime", s)
    }

    fn set_feedback_rate_hz(&mut self, hz: f32) -> Result<(), String> {
        // SAFETY: live group.
        let s = unsafe { (self.api.f.group_set_feedback_frequency_hz)(self.group, hz) };
        self.status("setting the feedback frequency", s)
    }

    fn configure(&mut self, settings: &[ModuleSettings]) -> Result<(), String> {
        if settings
            .iter()
            .all(|s| s.strategy.is_none() && s.floats.is_empty())
        {
            return Ok(());
        }
        let m = &self.api.command;
        // SAFETY: our own command; cleared before and after so no gain rides along
        // with the set-points later.
        unsafe { (self.api.f.group_command_clear)(self.command) };
        for (r, s) in self.refs.iter().zip(settings) {
            // SAFETY: indices from `gains::field_of`, below the counts checked at load.
            unsafe {
                if let Some(k) = s.strategy {
                    message::write_enum(r, m, super::ffi::field::CMD_CONTROL_STRATEGY, k);
                }
                for &(f, v) in &s.floats {
                    message::write_float(r, m, f, v);
                }
            }
        }
        // SAFETY: live group and command; blocks up to 500 ms (start-up, not the loop).
        let s = unsafe {
            (self.api.f.group_send_command_with_acknowledgement)(self.group, self.command, 500)
        };
        unsafe { (self.api.f.group_command_clear)(self.command) };
        self.status("sending the gains (no acknowledgement in 500 ms)", s)
    }

    fn release(&mut self) {
        if self.group.is_null() {
            return;
        }
        // SAFETY: live handles, released once; the handler's state is freed only after
        // the library stopped calling it.
        unsafe {
            (self.api.f.group_set_feedback_frequency_hz)(self.group, 0.0);
            (self.api.f.group_clear_feedback_handlers)(self.group);
            (self.api.f.group_release)(self.group);
            (self.api.f.group_command_release)(self.command);
            if !self.lookup.is_null() {
                (self.api.f.lookup_release)(self.lookup);
            }
            drop(Box::from_raw(self.handler));
        }
        self.group = std::ptr::null_mut();
        self.lookup = std::ptr::null_mut();
    }
}

impl Drop for LibGroup {
    fn drop(&mut self) {
        self.release();
    }
}
