//! The controller requests: build a selection off the loop and install it, calibrate,
//! set a nominal heading; and what is installed.

use std::sync::Arc;

use super::act::{Calibrated, Calibration, Done};
use super::error::{OperatorError, code};
use super::shared::Shared;
use crate::controller_interface::catalog::ControllerInfo;
use crate::controller_interface::registry::{self, BuildContext, Selection};
use crate::controller_interface::{CalibrationState, ControllerCommand};
use crate::controllers::REGISTRY;
use crate::gait::{GaitKind, GaitParams, ParamPatch};
use crate::rt::controller_slots::{Engagement, Installed};
use crate::rt::messages::{LoopRequest, Refusal, Rejection};
use crate::rt::telemetry::Snapshot;
use crate::safety::failsafe::Reason;

/// Longest calibration an operator starts, s.
pub const CALIBRATION_MAX_S: f64 = 600.0;
/// Default calibration length, in the gait's nominal cycles (SPEC §8: "a few").
pub const CALIBRATION_DEFAULT_CYCLES: f64 = 3.0;

/// Builds `sel` for `gait` on `params` (off the loop) and records it in the catalog.
fn build(
    shared: &Shared,
    gait: GaitKind,
    params: &GaitParams,
    sel: &Selection,
) -> Result<(Installed, ControllerInfo), OperatorError> {
    let ctx = BuildContext {
        gait,
        layout: &shared.layout,
        params,
    };
    let built = registry::build(REGISTRY, sel, &ctx)
        .map_err(|e| OperatorError::invalid_params(format!("{}: {e}", gait.name())))?;
    let info = shared.catalog.insert(built.info);
    let installed = Installed {
        id: info.id,
        controller: built.controller,
    };
    Ok((installed, (*info).clone()))
}

/// Builds `sel` for `gait` on its parameters after `patch` and installs it with them.
pub(crate) async fn set(
    shared: &Shared,
    gait: GaitKind,
    sel: &Selection,
    patch: ParamPatch,
) -> Result<Done, OperatorError> {
    let _one_at_a_time = shared.controller_change.lock().await;
    shared.free_retired();
    let snap = shared.telemetry.latest();
    let changes = patch != ParamPatch::default();
    let params = if changes {
        snap.params
            .get(gait)
            .patched_for(gait, &patch, shared.layout.module_length_m)
            .map_err(|e| OperatorError::invalid_params(format!("{}: {e}", gait.name())))?
    } else {
        *snap.params.get(gait)
    };
    let (installed, info) = build(shared, gait, &params, sel)?;
    let request = if changes {
        LoopRequest::SetParams { gait, patch }
    } else {
        LoopRequest::SetController { gait }
    };
    let result = shared.router.call_with(request, Some(installed)).await;
    shared.free_retired();
    let continuity = result?;
    Ok(Done::Controller {
        gait,
        info: Box::new(info),
        params: changes.then_some(params),
        continuity,
    })
}

/// The latest snapshot, `gait` (the running one by default), its installed
/// controller's id and info; an error naming the gait when it has none.
pub(crate) fn installed_controller(
    shared: &Shared,
    gait: Option<GaitKind>,
) -> Result<(Snapshot, GaitKind, u64, Arc<ControllerInfo>), OperatorError> {
    let snap = shared.telemetry.latest();
    let gait = gait.unwrap_or(snap.gait);
    let id = snap.controller.installed[gait.index()];
    let info = shared.catalog.get(id).ok_or_else(|| {
        OperatorError::invalid_params(format!(
            "{} has no controller installed: controller.set one first",
            gait.name()
        ))
    })?;
    Ok((snap, gait, id, info))
}

/// Starts `gait`'s controller's calibration and answers when it has finished (its
/// declared calibration reads calibrated) with the controller's report, or clears it.
/// The controller measures only while it drives, so the gait must be the one running;
/// the answer says so when it is not, and when the daemon shuts down meanwhile.
pub(crate) async fn calibrate(
    shared: &Shared,
    gait: Option<GaitKind>,
    what: Calibration,
) -> Result<Done, OperatorError> {
    let (snap, gait, id, info) = installed_controller(shared, gait)?;
    let done = |outcome| Done::Calibration {
        gait,
        controller: info.controller,
        outcome,
    };
    let seconds = match what {
        Calibration::Clear => {
            let cmd = LoopRequest::ControllerCommand {
                gait,
                command: ControllerCommand::ClearCalibration,
            };
            shared.router.call(cmd).await?;
            return Ok(done(Calibrated::Cleared));
        }
        Calibration::Run(Some(s)) => s,
        Calibration::Run(None) => {
            let w = snap.params.get(gait).temporal_freq_rad_s.abs();
            if w < 1e-6 {
                return Err(OperatorError::invalid_params(
                    "the gait does not move (temporal_freq_rad_s = 0): give `seconds`",
                ));
            }
            (CALIBRATION_DEFAULT_CYCLES * std::f64::consts::TAU / w).min(CALIBRATION_MAX_S)
        }
    };
    let cmd = ControllerCommand::Calibrate {
        duration_s: seconds,
    };
    shared
        .router
        .call(LoopRequest::ControllerCommand { gait, command: cmd })
        .await?;
    // Whether it reports a calibration to wait for: its declared capabilities.
    let declared = shared.telemetry.latest().controller;
    let driving = declared.active_id == id && declared.engagement == Engagement::Engaged;
    if driving && declared.capabilities.calibration.is_none() {
        return Ok(done(Calibrated::Started { seconds }));
    }
    // Wall time: the loop runs in real time; a held loop or another gait makes no progress.
    let deadline =
        tokio::time::Instant::now() + std::time::Duration::from_secs_f64(seconds * 1.5 + 5.0);
    let shutting_down = || {
        OperatorError::new(
            code::REFUSED,
            format!(
                "refused: {} (the calibration of {} did not finish)",
                Rejection::Failsafe(Refusal::ShuttingDown),
                gait.name()
            ),
        )
    };
    let mut closing = shared.closing.clone();
    loop {
        tokio::select! {
            () = tokio::time::sleep(std::time::Duration::from_millis(50)) => {}
            _ = closing.wait_for(|c| *c) => return Err(shutting_down()),
        }
        let snap = shared.telemetry.latest();
        if snap.reason == Reason::Shutdown {
            return Err(shutting_down());
        }
        let c = &snap.controller;
        if c.installed[gait.index()] != id {
            return Err(OperatorError::new(
                code::REFUSED,
                "the controller was replaced during its calibration",
            ));
        }
        let driving = c.active_id == id && c.engagement == Engagement::Engaged;
        if driving && c.capabilities.calibration == Some(CalibrationState::Calibrated) {
            return Ok(done(Calibrated::Finished {
                seconds,
                controller: Box::new(*c),
            }));
        }
        if tokio::time::Instant::now() >= deadline {
            let why = if driving {
                "it did not finish in time"
            } else {
                "the controller is not driving (its gait must be running, not held)"
            };
            return Err(OperatorError::new(
                code::LOOP_TIMEOUT,
                format!("calibration of {} not finished: {why}", gait.name()),
            ));
        }
    }
}

/// The nominal heading of `gait`'s controller (the running gait's by default), rad in
/// the pose estimate's world, or (`None`) the heading now. The loop refuses it, saying
/// why, when that controller does not steer by a heading.
pub(crate) async fn set_heading(
    shared: &Shared,
    gait: Option<GaitKind>,
    heading_rad: Option<f64>,
) -> Result<Done, OperatorError> {
    let (_, gait, _, info) = installed_controller(shared, gait)?;
    let cmd = ControllerCommand::SetHeading { heading_rad };
    shared
        .router
        .call(LoopRequest::ControllerCommand { gait, command: cmd })
        .await?;
    Ok(Done::Heading {
        gait,
        controller: info.controller,
        heading_rad,
    })
}
