//! The navigator's runner: what the navigator's decisions ask of the robot, as the
//! operator API's typed acts (install the choice's controller, set its gait, and once
//! that controller drives, its nominal heading). Pure: the daemon (`navigate`) and the
//! lab (`lab::trial_navigator`) run the same runner, each carrying its acts out its own
//! way (the daemon through [`super::Operator`]'s rules, the lab on its trial's queue).

use super::Act;
use crate::controller_interface::Selection;
use crate::gait::{GaitKind, ParamPatch};
use crate::navigation::navigator::{Choice, NavView, Navigator};
use crate::navigation::state::NavigatorState;

const KINDS: usize = GaitKind::ALL.len();

/// What the runner reads of the loop at a step.
#[derive(Debug, Clone, Copy)]
pub struct RunnerView {
    pub t_s: f64,
    pub nav: NavView,
    /// The gait the loop runs, and the gait whose controller drives now.
    pub gait: GaitKind,
    pub driving: Option<GaitKind>,
}

/// See the module's documentation.
#[derive(Debug, Clone)]
pub struct NavigatorRunner {
    nav: Navigator,
    /// The controller (registry name) installed for each gait, as far as it knows.
    installed: [Option<&'static str>; KINDS],
    /// A heading to set once its gait's controller drives.
    pending: Option<(GaitKind, f64)>,
    /// When it last asked to report its state, loop s.
    reported_s: f64,
    /// It has reached the goal and asked the gait to stop.
    stopped_at_goal: bool,
}

/// While steering by position, the state (distance, cross-track) is reported this often
/// even without a decision, s.
const REPORT_EVERY_S: f64 = 1.0;

/// On arrival the gait comes to rest within this, s.
pub const ARRIVAL_STOP_S: f64 = 2.0;

impl NavigatorRunner {
    /// Runs `nav`; `installed(gait, name)` says whether the controller named `name`
    /// (a choice's) already runs `gait`.
    pub fn new(nav: Navigator, installed: impl Fn(GaitKind, &str) -> bool) -> Self {
        let mut known = [None; KINDS];
        for c in [
            Choice::Sidewind,
            Choice::BackOff,
            Choice::Slither,
            Choice::Turn,
        ] {
            if known[c.gait().index()].is_none() && installed(c.gait(), c.controller()) {
                known[c.gait().index()] = Some(c.controller());
            }
        }
        Self {
            nav,
            installed: known,
            pending: None,
            reported_s: f64::NEG_INFINITY,
            stopped_at_goal: false,
        }
    }

    /// It has reached the goal: the gait was asked to stop, and navigation ends.
    pub fn arrived(&self) -> bool {
        self.stopped_at_goal
    }

    pub fn navigator(&self) -> &Navigator {
        &self.nav
    }

    /// What the navigator does now, for the loop's reports.
    pub fn state(&self, active: bool) -> NavigatorState {
        NavigatorState::of(&self.nav, active, None)
    }

    /// One step: the acts to carry out, in order, into `out`; true when its state is to
    /// be reported (a decision, steering by position begun or ended, or a second gone by
    /// while steering by position).
    pub fn step(&mut self, view: &RunnerView, out: &mut Vec<Act>) -> bool {
        let by_position = self.nav.course().is_some();
        let decided = self.decide(view, out);
        if self.nav.arrived() && !self.stopped_at_goal {
            self.stopped_at_goal = true;
            self.pending = None;
            out.push(Act::StopGait {
                within_s: ARRIVAL_STOP_S,
            });
            return true;
        }
        let report = decided
            || by_position != self.nav.course().is_some()
            || (self.nav.course().is_some() && view.t_s - self.reported_s >= REPORT_EVERY_S);
        if report {
            self.reported_s = view.t_s;
        }
        report
    }

    fn decide(&mut self, view: &RunnerView, out: &mut Vec<Act>) -> bool {
        if let Some((gait, h)) = self.pending
            && view.driving == Some(gait)
        {
            self.pending = None;
            out.push(Act::SetHeading {
                gait: Some(gait),
                heading_rad: Some(h),
            });
        }
        let Some(d) = self.nav.step(view.t_s, &view.nav) else {
            return false;
        };
        let gait = d.choice.gait();
        let name = d.choice.controller();
        if self.installed[gait.index()] != Some(name) {
            out.push(Act::SetController {
                gait,
                selection: Selection::named(name),
                patch: ParamPatch::default(),
            });
            self.installed[gait.index()] = Some(name);
        }
        if view.gait != gait {
            out.push(Act::SetGait { gait });
        }
        self.pending = Some((gait, d.heading_rad));
        true
    }
}
