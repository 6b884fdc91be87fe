//! Runs the navigator (`navigation::navigator`) in a lab trial as the daemon's control
//! side does: every sample it reads the loop, and carries a decision out as an
//! operator's requests through the loop's queue (`controller.set` with the controller
//! built off the loop, `gait.set`, then `controller.heading` once the controller drives).

use crossbeam_channel::Sender;

use super::LabError;
use super::aim::PendingHeading;
use super::compared::LabController;
use crate::gait::{BodyLayout, GaitTable};
use crate::navigation::navigator::{Choice, NavView, Navigator, NavigatorConfig};
use crate::navigation::state::NavigatorState;
use crate::rt::control_loop::ControlLoop;
use crate::rt::controller_slots::Installed;
use crate::rt::messages::{Envelope, LoopRequest};
use crate::safety::failsafe::Mode;

/// The signal of a navigator's trial: its choice as the loop reports it
/// ([`crate::navigation::state::NavigatorState::choice_code`], 0 none).
pub const CHOICE_SIGNAL: &str = "navigator_choice";

/// Tickets of the navigator's requests (apart from the trial's own).
const TICKETS: u64 = 3 << 32;

/// The navigator and what it has asked the loop for.
pub struct TrialNavigator {
    nav: Navigator,
    layout: BodyLayout,
    table: GaitTable,
    /// The choice whose controller is installed (at the start: the trial's controller).
    installed: Choice,
    /// A heading to send once its gait's controller drives.
    pending_heading: PendingHeading,
    ticket: u64,
}

impl TrialNavigator {
    /// For travel `travel_rad` in the estimate's world, the trial's controller being
    /// `first`'s.
    pub fn new(
        config: NavigatorConfig,
        travel_rad: f64,
        layout: BodyLayout,
        table: GaitTable,
        first: Choice,
    ) -> Self {
        Self {
            nav: Navigator::new(config, travel_rad),
            layout,
            table,
            installed: first,
            pending_heading: PendingHeading::default(),
            ticket: TICKETS,
        }
    }

    pub fn switches(&self) -> u32 {
        self.nav.switches()
    }

    fn send(&mut self, tx: &Sender<Envelope>, request: LoopRequest, c: Option<Installed>) {
        self.ticket += 1;
        let env = Envelope {
            ticket: self.ticket,
            request,
            controller: c,
        };
        // The queue holds a few; a full one would be a bug in the trial's sizing.
        let _ = tx.try_send(env);
    }

    /// One step at loop time `t_s`.
    pub fn step(
        &mut self,
        t_s: f64,
        lp: &ControlLoop,
        tx: &Sender<Envelope>,
    ) -> Result<(), LabError> {
        if self
            .pending_heading
            .send_when_engaged(lp, tx, self.ticket + 1)
        {
            self.ticket += 1;
        }
        let view = NavView {
            running: lp.mode() == Mode::Running,
            estimate_valid: lp.body().valid,
            heading_rad: lp.body().heading_rad,
            progress: lp.progress(),
        };
        let Some(d) = self.nav.step(t_s, &view) else {
            return Ok(());
        };
        let gait = d.choice.gait();
        if d.choice.controller() != self.installed.controller() {
            let c = LabController::named(gait, d.choice.controller())?;
            let built = c.build(&self.layout, self.table.get(gait))?;
            let installed = Installed {
                id: built.info.id,
                controller: built.controller,
            };
            self.send(tx, LoopRequest::SetController { gait }, Some(installed));
            self.send(tx, LoopRequest::SetGait { gait }, None);
            self.installed = d.choice;
        }
        self.pending_heading = PendingHeading::new(gait, Some(d.heading_rad));
        let state = NavigatorState::of(&self.nav, true, None);
        self.send(tx, LoopRequest::Navigation { state }, None);
        Ok(())
    }
}
