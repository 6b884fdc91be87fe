//! `navigate`: the navigator (`navigation::navigator`) run on the control side. A task
//! reads the loop's snapshot every 50 ms and carries each decision out as an
//! operator's requests would be carried out (`controller.set` built here, `gait.set`,
//! then `controller.heading` once the chosen controller drives), so the selector's
//! blend, the takeover, the slew limit and the failsafe apply to it as to anyone. It
//! tells the loop what it does (`LoopRequest::Navigation`) at each change, so `status`,
//! telemetry, the recording and the live view report it.
//!
//! Given a goal point it steers by the outside position while that is valid
//! (`navigation::steering`), and stops the gait when it arrives.
//!
//! It stops, and says why in `status.navigator.stopped`: when it arrives, when the operator turns it off
//! or sends a request that drives the robot (theirs wins: [`TAKES_OVER`]), when the
//! pose estimate stays invalid (it steers by it), when the loop stops running the gait,
//! or when the loop refuses one of its requests.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::act::{Act, Done};
use super::controllers;
use super::error::{OperatorError, code};
use super::navigator_runner::{NavigatorRunner, RunnerView};
use super::shared::Shared;
use crate::controller_interface::Selection;
use crate::controller_interface::registry;
use crate::controllers::REGISTRY;
use crate::gait::GaitKind;
use crate::navigation::navigator::{NavView, Navigator, NavigatorConfig, Target};
use crate::navigation::state::{NavigatorState, StopReason};
use crate::navigation::steering::PositionView;
use crate::rt::controller_slots::Engagement;
use crate::rt::messages::LoopRequest;
use crate::rt::telemetry::Snapshot;
use crate::safety::failsafe::Mode;

/// How often the runner looks at the loop.
const STEP: Duration = Duration::from_millis(50);

/// How long the pose estimate may stay invalid before navigation stops, loop s.
pub const ESTIMATE_GRACE_S: f64 = 1.0;

/// The running navigation task, if any.
#[derive(Default)]
pub(crate) struct Navigation {
    task: Mutex<Option<tokio::task::AbortHandle>>,
}

impl Navigation {
    /// Aborts the task; true if one was running.
    fn abort(&self) -> bool {
        let mut task = self.task.lock().unwrap_or_else(|e| e.into_inner());
        match task.take() {
            Some(t) => {
                let was_running = !t.is_finished();
                t.abort();
                was_running
            }
            None => false,
        }
    }

    fn set(&self, handle: tokio::task::AbortHandle) {
        *self.task.lock().unwrap_or_else(|e| e.into_inner()) = Some(handle);
    }
}

/// Before a request that drives the robot: stop navigating (at once; the loop hears why
/// in the background, so an e-stop is not delayed by it).
pub(crate) fn operator_takes_over(shared: &Arc<Shared>) {
    if shared.navigation.abort() {
        let shared = shared.clone();
        tokio::spawn(async move {
            let mut state = shared.telemetry.latest().navigator;
            state.active = false;
            state.stopped = Some(StopReason::Operator);
            let _ = report(&shared, state).await;
        });
    }
}

/// Stops navigating; whether it was.
pub(crate) async fn stop(shared: &Arc<Shared>) -> Result<Done, OperatorError> {
    let was = shared.navigation.abort();
    let mut state = shared.telemetry.latest().navigator;
    if was || state.active {
        state.active = false;
        state.stopped = Some(StopReason::Off);
        report(shared, state).await?;
    }
    Ok(Done::NavigationOff {
        was_navigating: was,
    })
}

/// Starts navigating to `target` (or restarts towards a new one).
pub(crate) async fn start(
    shared: &Arc<Shared>,
    target: Target,
    config: NavigatorConfig,
) -> Result<Done, OperatorError> {
    config
        .check()
        .map_err(|e| OperatorError::invalid_params(format!("config: {e}")))?;
    let s = shared.telemetry.latest();
    if s.mode != Mode::Running {
        return Err(OperatorError::new(
            code::REFUSED,
            format!(
                "refused: the loop is not running a gait (mode {}): arm it or set a gait first",
                serde_json::to_value(s.mode)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_owned))
                    .unwrap_or_default()
            ),
        ));
    }
    if !s.body.valid {
        return Err(OperatorError::new(
            code::REFUSED,
            "refused: the pose estimate is not valid (docs/estimation.md), and the navigator \
             steers by it: wait until `status.body.valid` is true",
        ));
    }
    let nav = match target {
        Target::Heading(travel_rad) => Navigator::new(config, travel_rad),
        Target::Goal(goal_m) => {
            let Some(p) = position(&s) else {
                return Err(OperatorError::new(
                    code::REFUSED,
                    format!(
                        "refused: no valid position to steer to a goal by (status.world.state \
                         is {}): send fixes with `pose.external` (docs/estimation.md, \
                         \"Where the body is\"), or navigate by `heading_rad`",
                        serde_json::to_value(s.body.world.state)
                            .ok()
                            .and_then(|v| v.as_str().map(str::to_owned))
                            .unwrap_or_default()
                    ),
                ));
            };
            let to = [goal_m[0] - p.position_m[0], goal_m[1] - p.position_m[1]];
            let travel_rad = to[1].atan2(to[0]) - p.yaw_offset_rad;
            Navigator::to_goal(config, goal_m, travel_rad)
        }
    };
    shared.navigation.abort();
    let travel = nav.travel_rad();
    report(shared, NavigatorState::of(&nav, true, None)).await?;
    let task = tokio::spawn(run(shared.clone(), nav));
    shared.navigation.set(task.abort_handle());
    Ok(Done::Navigating {
        travel_rad: travel,
        goal_m: match target {
            Target::Goal(g) => Some(g),
            Target::Heading(_) => None,
        },
        config,
    })
}

/// The position the navigator steers by, while the outside source's is valid.
fn position(s: &Snapshot) -> Option<PositionView> {
    PositionView::of(&s.body.world)
}

/// Tells the loop what the navigator does.
async fn report(shared: &Shared, state: NavigatorState) -> Result<(), OperatorError> {
    shared
        .router
        .call(LoopRequest::Navigation { state })
        .await
        .map(|_| ())
}

async fn run(shared: Arc<Shared>, nav: Navigator) {
    let catalog = shared.catalog.clone();
    let installed = shared.telemetry.latest().controller.installed;
    // What runs each gait, against what a choice names, both resolved by the registry
    // (its controller and preset), not compared as strings.
    let mut runner = NavigatorRunner::new(nav, |gait, name| {
        let wanted = registry::resolve(REGISTRY, gait, &Selection::named(name));
        let running = catalog.get(installed[gait.index()]);
        match (wanted, running) {
            (Ok((family, preset)), Some(i)) => i.controller == family.name() && i.preset == preset,
            _ => false,
        }
    });
    let why = drive(&shared, &mut runner).await;
    tracing::info!(reason = ?why, "navigation stopped: {}", why.explain());
    let state = NavigatorState::of(runner.navigator(), false, Some(why));
    let _ = report(&shared, state).await;
}

/// Steps the runner until something stops it; returns why. Its acts are carried out
/// as the operator API carries out anyone's (the drive lease aside: the navigator
/// drives for whoever started it, and stops when another operator acts).
async fn drive(shared: &Shared, runner: &mut NavigatorRunner) -> StopReason {
    let mut tick = tokio::time::interval(STEP);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut invalid_since: Option<f64> = None;
    let mut acts = Vec::new();
    loop {
        tick.tick().await;
        let s = shared.telemetry.latest();
        if s.mode != Mode::Running {
            return StopReason::NotRunning;
        }
        if !s.body.valid {
            let since = *invalid_since.get_or_insert(s.t_s);
            if s.t_s - since > ESTIMATE_GRACE_S {
                return StopReason::EstimateInvalid;
            }
            continue;
        }
        invalid_since = None;
        let view = RunnerView {
            t_s: s.t_s,
            nav: NavView {
                running: true,
                estimate_valid: true,
                heading_rad: s.body.heading_rad,
                progress: s.progress,
                position: position(&s),
            },
            gait: s.gait,
            driving: driving(&s),
        };
        acts.clear();
        let decided = runner.step(&view, &mut acts);
        for act in acts.drain(..) {
            if carry_out(shared, act).await.is_err() {
                return StopReason::Refused;
            }
        }
        if runner.arrived() {
            return StopReason::Arrived;
        }
        if decided && report(shared, runner.state(true)).await.is_err() {
            return StopReason::Refused;
        }
    }
}

/// The gait whose controller drives the joints now.
fn driving(s: &Snapshot) -> Option<GaitKind> {
    let c = &s.controller;
    (c.active_id == c.installed[s.gait.index()] && c.engagement == Engagement::Engaged)
        .then_some(s.gait)
}

/// One of the runner's acts, carried out without the operator's drive lease.
async fn carry_out(shared: &Shared, act: Act) -> Result<Done, OperatorError> {
    match act {
        Act::SetController {
            gait,
            selection,
            patch,
        } => controllers::set(shared, gait, &selection, patch).await,
        Act::SetHeading { gait, heading_rad } => {
            controllers::set_heading(shared, gait, heading_rad).await
        }
        Act::SetGait { gait } => {
            shared.router.call(LoopRequest::SetGait { gait }).await?;
            Ok(Done::Gait { gait })
        }
        Act::StopGait { within_s } => {
            shared
                .router
                .call(LoopRequest::StopGait { within_s })
                .await?;
            Ok(Done::Motion {
                stopping: true,
                within_s,
            })
        }
        other => unreachable!("the runner makes no {}", other.method()),
    }
}
