//! The loop's side of the controller seam: one slot per gait. The selector is the
//! open-loop base and the blender; the active gait's controller takes over once the
//! selector has finished blending into that gait, and hands the joints back when the
//! gait changes, its parameters change, the loop holds, or the controller is replaced.
//!
//! - **Takeover without a jump.** The controller is engaged with the selector's phase
//!   and set-points of this cycle (a [`Handover`]) and the gait's nominal parameters;
//!   one that makes its own way into its gait (`takes_over_at_switch`) is engaged at
//!   the blend's first cycle instead of its end.
//! - **Continuity.** A change of the gait's parameters or of the controller's
//!   configuration while it drives is taken in place where the controller can
//!   ([`Controller::follow`], [`Controller::reconfigure`]): it keeps driving and
//!   keeps what it has learnt. The answer says which ([`Continuity`]). A controller
//!   waiting for its gait's blend while only that gait's parameters blend takes over
//!   from where the blend is and follows the rest (`GaitSelector::same_gait_blend`).
//! - **Hand back.** The selector's output continues from the set-points sent last
//!   cycle: their difference from the selector's own fades out over the blend time
//!   while the gait keeps moving; the controller takes over again after that.
//! - **Nothing allocates or frees.** Controllers are built on the control side; the one
//!   replaced is sent back through a bounded channel to be dropped there.
//! - This module knows no concrete controller: only `dyn Controller` and its id.
use crossbeam_channel::{Sender, TrySendError};
use serde::Serialize;

use crate::controller_interface::catalog::NO_CONTROLLER;
use crate::controller_interface::report::ControllerReport;
use crate::controller_interface::{
    CannotFollow, Capabilities, Controller, ControllerCommand, Handover, NominalMismatch,
    Observation, TickClock,
};
use crate::gait::{GaitKind, GaitParams, GaitSelector};
use crate::rt::messages::Rejection;

const KINDS: usize = GaitKind::ALL.len();

/// A built controller on its way to (or back from) the loop.
pub struct Installed {
    /// Its [`crate::controller_interface::catalog`] id.
    pub id: u64,
    pub controller: Box<dyn Controller>,
}

impl std::fmt::Debug for Installed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Installed({})", self.id)
    }
}

/// What became of a change for the gait's controller (the operator's answer says it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "continuity", rename_all = "snake_case")]
pub enum Continuity {
    /// No controller drove the gait: the selector blends into the change, and the
    /// gait's controller (if any) takes over when the blend ends.
    Blended,
    /// The driving controller follows the new parameters, keeping what it learnt.
    Followed,
    /// The driving controller took the new configuration in place, keeping what it
    /// learnt.
    Reconfigured,
    /// The driving controller could not take the change in place (`why`): the
    /// selector blends into it and the controller takes over afresh at the blend's end.
    HandedBack { why: &'static str },
    /// A new controller is installed (another kind, or a change its predecessor could
    /// not take in place: `why`); it takes over when the selector's blend ends.
    Installed { why: &'static str },
}

/// Whether the active gait's controller drives the joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Engagement {
    /// The gait has no controller: the selector's serpenoid runs it.
    Off,
    /// The selector drives: a blend into the gait is running, or the loop holds.
    Waiting,
    /// The controller drives.
    Engaged,
}

/// What the loop publishes about the controllers every cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerTelemetry {
    /// Each gait's controller id (0: none), by `GaitKind::index`.
    pub installed: [u64; KINDS],
    /// The active gait's controller and whether it drives.
    pub active_id: u64,
    pub engagement: Engagement,
    /// Its report after its last step (cleared unless engaged).
    pub report: ControllerReport,
    /// What it offers the operator (none unless engaged).
    pub capabilities: Capabilities,
    /// Times the active gait's controller took over since it was installed.
    pub takeovers: u64,
    /// Replaced controllers the loop had to free itself because the retired channel was
    /// full (an allocator call in the loop; stays 0 while the control side drains it).
    pub freed_in_loop: u64,
}

impl Default for ControllerTelemetry {
    fn default() -> Self {
        Self {
            installed: [NO_CONTROLLER; KINDS],
            active_id: NO_CONTROLLER,
            engagement: Engagement::Off,
            report: ControllerReport::EMPTY,
            capabilities: Capabilities::default(),
            takeovers: 0,
            freed_in_loop: 0,
        }
    }
}

/// The slots (see the module docs).
pub struct ControllerSlots {
    slots: [Option<Installed>; KINDS],
    takeovers: [u64; KINDS],
    /// The gait whose controller drives, if one does.
    engaged: Option<GaitKind>,
    /// The engaged controller's ticks (restarted at each engagement).
    clock: TickClock,
    retired: Sender<Installed>,
    report: ControllerReport,
    capabilities: Capabilities,
    freed_in_loop: u64,
}

impl ControllerSlots {
    /// No controllers yet; replaced ones go to `retired`.
    pub fn new(retired: Sender<Installed>) -> Self {
        Self {
            slots: std::array::from_fn(|_| None),
            takeovers: [0; KINDS],
            engaged: None,
            clock: TickClock::default(),
            retired,
            report: ControllerReport::EMPTY,
            capabilities: Capabilities::default(),
            freed_in_loop: 0,
        }
    }

    /// Whether `gait`'s controller (if any) can follow `params`.
    pub fn accepts(&self, gait: GaitKind, params: &GaitParams) -> Result<(), NominalMismatch> {
        match &self.slots[gait.index()] {
            Some(c) => c.controller.accepts(params),
            None => Ok(()),
        }
    }

    /// Installs `new` for `gait` at a cycle boundary. Where `gait`'s controller drives
    /// and can take `new`'s configuration in place ([`Controller::reconfigure`]) it
    /// does, keeps its state, drives on and takes `new`'s id; `new` is retired.
    /// Otherwise, if the old controller was driving, the joints go back to the
    /// selector first (from `commanded`, the set-points sent last cycle); `new` takes
    /// over when the selector's blend ends, and the old one is retired.
    pub fn install(
        &mut self,
        gait: GaitKind,
        mut new: Installed,
        selector: &mut GaitSelector,
        commanded: &[f64],
        t_s: f64,
    ) -> Continuity {
        let driving = self.engaged == Some(gait);
        let why = match self.slots[gait.index()].as_mut() {
            // A controller that does not drive starts afresh at its takeover anyway.
            _ if !driving => "the gait's controller was not driving",
            None => "no controller before",
            Some(old) => match old.controller.reconfigure(new.controller.as_mut()) {
                Ok(()) => {
                    old.id = new.id;
                    self.retire(new);
                    return Continuity::Reconfigured;
                }
                Err(CannotFollow(why)) => why,
            },
        };
        if driving {
            self.hand_back(selector, commanded, t_s);
        }
        self.takeovers[gait.index()] = 0;
        if let Some(old) = self.slots[gait.index()].replace(new) {
            self.retire(old);
        }
        Continuity::Installed { why }
    }

    /// The gait's parameters changed to `params` at `t_s` (the selector has them):
    /// a driving controller follows them where it can ([`Controller::follow`]), else
    /// hands the joints back (see [`ControllerSlots::hand_back`]).
    pub fn follow(
        &mut self,
        gait: GaitKind,
        params: &GaitParams,
        selector: &mut GaitSelector,
        commanded: &[f64],
        t_s: f64,
    ) -> Continuity {
        if self.engaged != Some(gait) {
            return Continuity::Blended;
        }
        let Some(slot) = self.slots[gait.index()].as_mut() else {
            return Continuity::Blended;
        };
        match slot.controller.follow(t_s, params) {
            Ok(()) => Continuity::Followed,
            Err(CannotFollow(why)) => {
                self.hand_back(selector, commanded, t_s);
                Continuity::HandedBack { why }
            }
        }
    }

    /// Passes an operator's command to `gait`'s controller (installed, driving or not).
    pub fn command(&mut self, gait: GaitKind, command: ControllerCommand) -> Result<(), Rejection> {
        let slot = self.slots[gait.index()]
            .as_mut()
            .ok_or(Rejection::NoControllerInstalled)?;
        slot.controller
            .command(command)
            .map_err(Rejection::CommandRefused)
    }

    /// Sends a controller that was not installed back unused.
    pub fn refuse(&mut self, c: Installed) {
        self.retire(c);
    }

    fn retire(&mut self, c: Installed) {
        match self.retired.try_send(c) {
            Ok(()) => {}
            // Only when the control side stopped draining: freeing here is an
            // allocator call in the loop, counted so it shows.
            Err(TrySendError::Full(c) | TrySendError::Disconnected(c)) => {
                self.freed_in_loop += 1;
                drop(c);
            }
        }
    }

    /// If a controller drives, gives the joints back to the selector: its output
    /// continues from `commanded` and the controller's deviation fades out over the
    /// blend time (`GaitSelector::hand_back`). Call after changing the selector's gait
    /// or parameters.
    pub fn hand_back(&mut self, selector: &mut GaitSelector, commanded: &[f64], t_s: f64) {
        if self.engaged.take().is_some() {
            selector.hand_back(commanded, t_s);
        }
    }

    /// The loop does not run the gait this cycle (hold, limp) or restarts it from the
    /// measured pose: the controller stops driving and takes over again (engaged
    /// afresh) once the selector has blended back.
    pub fn pause(&mut self) {
        self.engaged = None;
    }

    /// Called after the selector's update with its set-points in `pos`: replaces them
    /// with the controller's when the active gait's controller drives, taking over
    /// first when the selector has just finished blending into the gait. Returns
    /// whether the controller drove.
    pub fn drive(
        &mut self,
        t_s: f64,
        selector: &GaitSelector,
        obs: &Observation<'_>,
        pos: &mut [f64],
    ) -> bool {
        let gait = selector.active();
        debug_assert!(
            self.engaged.is_none_or(|g| g == gait),
            "a gait change hands back first"
        );
        let Some(slot) = self.slots[gait.index()].as_mut() else {
            return false;
        };
        let ready = selector.blend_progress() >= 1.0 || slot.controller.takes_over_at_switch();
        // Only the gait's own parameters blending: take over from where the blend is and
        // follow the rest (an operator changing speed often is not kept waiting).
        let mid_blend = match (self.engaged, ready) {
            (None, false) => selector.same_gait_blend(),
            _ => None,
        };
        if self.engaged.is_none() && (ready || mid_blend.is_some()) {
            let target = selector.table().get(gait);
            slot.controller.engage(&Handover {
                t_s,
                phase_rad: selector.phase(),
                set_points_rad: pos,
                params: mid_blend.as_ref().unwrap_or(target),
                layout: selector.layout(),
            });
            if mid_blend.is_some() && slot.controller.follow(t_s, target).is_err() {
                return false; // It cannot: it takes over when the blend ends.
            }
            self.engaged = Some(gait);
            self.clock.restart();
            self.takeovers[gait.index()] += 1;
        }
        if self.engaged.is_none() {
            return false;
        }
        slot.controller.step(self.clock.tick(t_s), obs, pos);
        slot.controller.report(&mut self.report);
        self.capabilities = slot.controller.capabilities();
        true
    }

    /// The driving controller's id and report after its last step, if one drives.
    pub fn report(&self) -> Option<(u64, &ControllerReport)> {
        let g = self.engaged?;
        Some((self.id(g), &self.report))
    }

    /// The gait whose controller drives, if any.
    pub fn engaged(&self) -> Option<GaitKind> {
        self.engaged
    }

    /// The id of `gait`'s controller (0: none).
    pub fn id(&self, gait: GaitKind) -> u64 {
        self.slots[gait.index()]
            .as_ref()
            .map_or(NO_CONTROLLER, |c| c.id)
    }

    /// Fills the telemetry's controller part for the active gait `active`.
    pub fn publish(&self, active: GaitKind, out: &mut ControllerTelemetry) {
        for g in GaitKind::ALL {
            out.installed[g.index()] = self.id(g);
        }
        out.active_id = self.id(active);
        out.engagement = match (self.engaged, out.active_id) {
            (Some(_), _) => Engagement::Engaged,
            (None, NO_CONTROLLER) => Engagement::Off,
            (None, _) => Engagement::Waiting,
        };
        if self.engaged.is_some() {
            out.report = self.report;
            out.capabilities = self.capabilities;
        } else {
            out.report.clear();
            out.capabilities = Capabilities::default();
        }
        out.takeovers = self.takeovers[active.index()];
        out.freed_in_loop = self.freed_in_loop;
    }
}

#[cfg(test)]
#[path = "controller_slots_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "controller_slots_continuity_tests.rs"]
mod continuity_tests;
