//! Runs the navigator in a lab trial as the daemon does: the same runner
//! (`operator::navigator_runner`), its typed acts carried out on the trial's loop queue
//! (the controller built off the loop, `SetController`, `SetGait`, the heading once the
//! controller drives), and the navigator's state reported at each decision.

use crossbeam_channel::Sender;

use super::LabError;
use crate::controller_interface::ControllerCommand;
use crate::controller_interface::registry;
use crate::controllers::REGISTRY;
use crate::gait::{BodyLayout, GaitTable};
use crate::navigation::navigator::{Choice, NavView, Navigator, NavigatorConfig};
use crate::navigation::state::{NavigatorState, StopReason};
use crate::navigation::steering::PositionView;
use crate::operator::Act;
use crate::operator::navigator_runner::{NavigatorRunner, RunnerView};
use crate::rt::control_loop::ControlLoop;
use crate::rt::controller_slots::Installed;
use crate::rt::messages::{Envelope, LoopRequest};
use crate::safety::failsafe::Mode;

/// The signal of a navigator's trial: its choice as the loop reports it
/// ([`crate::navigation::state::NavigatorState::choice_code`], 0 none).
pub const CHOICE_SIGNAL: &str = "navigator_choice";

/// With a pose source, also: the fused position's error against the truth (NaN while
/// not valid), and the cross-track error as the navigator reports it (NaN while not
/// steering by position).
pub const POSITION_SIGNALS: [&str; 2] = ["position_error_mm", "cross_track_m"];

/// Tickets of the navigator's requests (apart from the trial's own).
const TICKETS: u64 = 3 << 32;

/// The runner and what it needs to carry its acts out.
pub struct TrialNavigator {
    runner: NavigatorRunner,
    layout: BodyLayout,
    table: GaitTable,
    ticket: u64,
    acts: Vec<Act>,
}

impl TrialNavigator {
    /// For travel `travel_rad` in the estimate's world, or to `goal_m` in the true world
    /// (the simulated source's) by position while it is valid; the trial's controller
    /// being `first`'s.
    pub fn new(
        config: NavigatorConfig,
        travel_rad: f64,
        goal_m: Option<[f64; 2]>,
        layout: BodyLayout,
        table: GaitTable,
        first: Choice,
    ) -> Self {
        let nav = match goal_m {
            Some(g) => Navigator::to_goal(config, g, travel_rad),
            None => Navigator::new(config, travel_rad),
        };
        let runner = NavigatorRunner::new(nav, |gait, name| {
            gait == first.gait() && name == first.controller()
        });
        Self {
            runner,
            layout,
            table,
            ticket: TICKETS,
            acts: Vec::new(),
        }
    }

    pub fn switches(&self) -> u32 {
        self.runner.navigator().switches()
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
        let view = RunnerView {
            t_s,
            nav: NavView {
                running: lp.mode() == Mode::Running,
                estimate_valid: lp.body().valid,
                heading_rad: lp.body().heading_rad,
                progress: lp.progress(),
                position: PositionView::of(&lp.body().world),
            },
            gait: lp.gait(),
            driving: lp.controllers().engaged(),
        };
        let mut acts = std::mem::take(&mut self.acts);
        acts.clear();
        let decided = self.runner.step(&view, &mut acts);
        for act in acts.drain(..) {
            self.carry_out(act, tx)?;
        }
        self.acts = acts;
        if self.runner.arrived() {
            let state =
                NavigatorState::of(self.runner.navigator(), false, Some(StopReason::Arrived));
            self.send(tx, LoopRequest::Navigation { state }, None);
        } else if decided {
            let state: NavigatorState = self.runner.state(true);
            self.send(tx, LoopRequest::Navigation { state }, None);
        }
        Ok(())
    }

    /// It reached its goal (and stopped the gait): it is not stepped again.
    pub fn arrived(&self) -> bool {
        self.runner.arrived()
    }

    /// One of the runner's acts, on the trial's queue.
    fn carry_out(&mut self, act: Act, tx: &Sender<Envelope>) -> Result<(), LabError> {
        match act {
            Act::SetController {
                gait, selection, ..
            } => {
                let ctx = registry::BuildContext {
                    gait,
                    layout: &self.layout,
                    params: self.table.get(gait),
                };
                let built = registry::build(REGISTRY, &selection, &ctx).map_err(|e| {
                    LabError::BadValue(format!("controller {}: {e}", selection.controller))
                })?;
                let installed = Installed {
                    id: built.info.id,
                    controller: built.controller,
                };
                self.send(tx, LoopRequest::SetController { gait }, Some(installed));
            }
            Act::SetGait { gait } => self.send(tx, LoopRequest::SetGait { gait }, None),
            Act::StopGait { within_s } => self.send(tx, LoopRequest::StopGait { within_s }, None),
            Act::SetHeading {
                gait: Some(gait),
                heading_rad,
            } => {
                let command = ControllerCommand::SetHeading { heading_rad };
                self.send(tx, LoopRequest::ControllerCommand { gait, command }, None);
            }
            other => unreachable!("the runner makes no {}", other.method()),
        }
        Ok(())
    }
}
