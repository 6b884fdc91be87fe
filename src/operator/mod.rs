//! The operator API: one typed, in-process path for everything an operator asks of the
//! robot and reads from it. The control socket (JSON lines), the Foxglove station
//! (services, teleop, the Parameters panel), the navigator and a ROS 2 node are thin
//! adapters over it: each turns its input into an [`Act`], calls [`Operator::act`] as
//! the client it serves, and presents the [`Done`] or the [`OperatorError`] (one type,
//! one table of codes: [`code`]) in its own terms. Reads are typed too: the loop's
//! [`Snapshot`], subscribed to at a rate ([`Operator::subscribe`]) or taken
//! ([`Operator::snapshot`]),
//! and the catalog of controllers.
//!
//! Every act meets the same rules whoever sends it: one operator drives at a time
//! ([`driver`]), a driving act stops the navigator first, a stop is never refused;
//! then it is validated and carried to the loop through its queue ([`router`]).
//!
//! - [`act`]: the typed requests and answers.
//! - [`error`]: the error and its codes.
//! - [`driver`]: who drives.
//! - `controllers`: building, installing, calibrating controllers, their headings.
//! - `navigate`: the navigator's task, carried out as an operator's acts.
//! - `router`: tickets and acks between callers and the loop.

pub mod act;
pub(crate) mod controllers;
pub mod driver;
pub mod error;
pub mod handle;
pub(crate) mod navigate;
pub mod navigator_runner;
pub mod parameters;
pub(crate) mod router;
pub(crate) mod shared;

use std::sync::Arc;
use std::time::{Duration, Instant};

pub use act::{Act, Calibrated, Calibration, Done};
pub use controllers::{CALIBRATION_DEFAULT_CYCLES, CALIBRATION_MAX_S};
pub use error::{OperatorError, code};

use crate::controller_interface::catalog::{Catalog, ControllerInfo};
use crate::estimation::external_pose::{ExternalFix, PoseCounters, PoseInput};
use crate::gait::{BodyLayout, GaitKind};
use crate::rt::messages::LoopRequest;
use crate::rt::telemetry::Snapshot;
use handle::{DaemonInfo, LoopHandle, RecordView};
use router::AckRouter;
use shared::Shared;

/// The API (cheap to clone). Its async methods run on the runtime that made it.
#[derive(Clone)]
pub struct Operator {
    shared: Arc<Shared>,
    runtime: tokio::runtime::Handle,
}

/// How the operator API treats its callers.
#[derive(Debug, Clone)]
pub struct OperatorConfig {
    /// How long an act waits for the loop's ack before `LOOP_TIMEOUT`.
    pub ack_timeout: Duration,
    /// A driver that sends no driving act for this long no longer holds the drive.
    pub driver_timeout: Duration,
    /// The recorder's state (`None`: no recorder).
    pub record: Option<RecordView>,
    /// The daemon's pose input (`None`: external fixes are refused).
    pub pose: Option<PoseInput>,
}

impl Operator {
    /// On the loop's channels; acts give up when `closing` turns true (the daemon's
    /// shutdown). Call within the tokio runtime its methods will run on.
    pub fn start(
        handle: LoopHandle,
        config: OperatorConfig,
        closing: tokio::sync::watch::Receiver<bool>,
    ) -> std::io::Result<Self> {
        let router = AckRouter::start(handle.requests, handle.acks, config.ack_timeout)?;
        let shared = Arc::new(Shared {
            router,
            telemetry: handle.telemetry,
            info: handle.info,
            layout: handle.layout,
            retired: handle.retired,
            catalog: handle.catalog,
            controller_change: tokio::sync::Mutex::new(()),
            navigation: Default::default(),
            driver: driver::DriverLease::new(config.driver_timeout),
            record: config.record,
            pose: config.pose,
            closing,
        });
        Ok(Self {
            shared,
            runtime: tokio::runtime::Handle::current(),
        })
    }

    /// Carries `act` out for the client `who` (the drive lease and the logs name it).
    /// Runs on the API's runtime, whichever runtime awaits it.
    pub async fn act(&self, who: &str, act: Act) -> Result<Done, OperatorError> {
        let (shared, who) = (self.shared.clone(), who.to_owned());
        let task = self
            .runtime
            .spawn(async move { carry_out(&shared, &who, act).await });
        task.await.unwrap_or_else(|_| {
            Err(OperatorError::new(
                code::NOT_READY,
                "the operator API stopped",
            ))
        })
    }

    /// `who` is about to drive: it holds the drive or takes a free one; refused while
    /// another operator drives.
    pub fn claim_drive(&self, who: &str) -> Result<(), OperatorError> {
        self.shared.driver.claim(who, Instant::now())
    }

    /// `who` has gone: it no longer drives.
    pub fn release_drive(&self, who: &str) {
        self.shared.driver.release(who);
    }

    /// Who drives now.
    pub fn driver(&self) -> Option<driver::Driver> {
        self.shared.driver.driver(Instant::now())
    }

    /// The loop's latest snapshot.
    pub fn snapshot(&self) -> Snapshot {
        self.shared.telemetry.latest()
    }

    /// The loop's snapshots as they come, at most one every `period`: the receiver
    /// sees the newest (`changed().await`); it ends with the API or when dropped.
    pub fn subscribe(&self, period: Duration) -> tokio::sync::watch::Receiver<Arc<Snapshot>> {
        let (tx, rx) = tokio::sync::watch::channel(Arc::new(self.snapshot()));
        let shared = self.shared.clone();
        self.runtime.spawn(async move {
            let mut tick = tokio::time::interval(period);
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            let mut closing = shared.closing.clone();
            let mut last = u64::MAX;
            loop {
                tokio::select! {
                    _ = tick.tick() => {}
                    () = tx.closed() => return,
                    _ = closing.wait_for(|c| *c) => return,
                }
                let s = shared.telemetry.latest();
                if s.cycle != last {
                    last = s.cycle;
                    tx.send_replace(Arc::new(s));
                }
            }
        });
        rx
    }

    /// Names and configurations of every controller built.
    pub fn catalog(&self) -> &Catalog {
        &self.shared.catalog
    }

    /// What `gait` runs now, if a controller.
    pub fn installed(&self, gait: GaitKind) -> Option<Arc<ControllerInfo>> {
        let id = self.snapshot().controller.installed[gait.index()];
        self.shared.catalog.get(id)
    }

    /// The loop's body.
    pub fn layout(&self) -> &BodyLayout {
        &self.shared.layout
    }

    /// Static facts about the daemon.
    pub fn info(&self) -> &DaemonInfo {
        &self.shared.info
    }

    /// The recorder's state as JSON (`{"state": "off"}` without one).
    pub fn record(&self) -> serde_json::Value {
        RecordView::read(self.shared.record.as_ref())
    }

    /// An external fix (`pose.external`, ROS 2's pose topic) into the pose estimate:
    /// its loop time and how old it was on arrival, s. Not an act: a source is no
    /// driver, and the loop never waits for it.
    pub fn external_pose(&self, fix: &ExternalFix) -> Result<(f64, f64), OperatorError> {
        let input =
            self.shared.pose.as_ref().ok_or_else(|| {
                OperatorError::new(code::REFUSED, "this daemon has no pose input")
            })?;
        input.write(fix).map_err(|why| {
            OperatorError::invalid_params(format!("external pose from {}: {why}", fix.source))
        })
    }

    /// What the pose input counts (`None`: no pose input).
    pub fn pose_counters(&self) -> Option<&Arc<PoseCounters>> {
        self.shared.pose.as_ref().map(PoseInput::counters)
    }

    /// Stops the ack thread (the daemon's shutdown).
    pub fn stop(&self) {
        self.shared.router.stop();
    }
}

/// The rules every act meets, then the act.
async fn carry_out(shared: &Arc<Shared>, who: &str, act: Act) -> Result<Done, OperatorError> {
    let now = Instant::now();
    if act.drives() {
        shared.driver.claim(who, now)?;
    }
    if act.takes_over_navigation() {
        navigate::operator_takes_over(shared);
    }
    if act.stops() {
        // Whoever stops the robot frees the drive; the stop itself is never refused.
        shared.driver.stopped();
    }
    let call = |request| async move { shared.router.call(request).await };
    match act {
        Act::SetGait { gait } => {
            call(LoopRequest::SetGait { gait }).await?;
            Ok(Done::Gait { gait })
        }
        Act::StopGait { within_s } | Act::ResumeGait { within_s } => {
            let stopping = matches!(act, Act::StopGait { .. });
            let request = if stopping {
                LoopRequest::StopGait { within_s }
            } else {
                LoopRequest::ResumeGait { within_s }
            };
            call(request).await?;
            Ok(Done::Motion { stopping, within_s })
        }
        Act::SetParams { gait, patch } => {
            // Validated against the table the loop published last; the loop checks
            // again, also against the gait's controller.
            let current = *shared.telemetry.latest().params.get(gait);
            let params = current
                .patched_for(gait, &patch, shared.layout.module_length_m)
                .map_err(|e| OperatorError::invalid_params(format!("{}: {e}", gait.name())))?;
            let continuity = call(LoopRequest::SetParams { gait, patch }).await?;
            Ok(Done::Params {
                gait,
                params,
                continuity,
            })
        }
        Act::SetBlendTime { blend_time_s } => {
            call(LoopRequest::SetBlendTime { blend_time_s }).await?;
            Ok(Done::BlendTime { blend_time_s })
        }
        Act::SetController {
            gait,
            selection,
            patch,
        } => controllers::set(shared, gait, &selection, patch).await,
        Act::Calibrate { gait, what } => controllers::calibrate(shared, gait, what).await,
        Act::SetHeading { gait, heading_rad } => {
            controllers::set_heading(shared, gait, heading_rad).await
        }
        Act::Navigate { target, config } => navigate::start(shared, target, config).await,
        Act::NavigateOff => navigate::stop(shared).await,
        Act::TakeOver => {
            let from = shared.driver.take_over(who, now);
            if let Some(from) = &from {
                tracing::warn!("{who} took the drive over from {from}");
            }
            Ok(Done::TookOver {
                driver: who.to_owned(),
                taken_from: from,
            })
        }
        Act::Hold | Act::Limp | Act::EStop | Act::Arm => {
            let request = match act {
                Act::Hold => LoopRequest::Hold,
                Act::Limp => LoopRequest::Limp,
                Act::EStop => LoopRequest::EStop,
                _ => LoopRequest::Arm,
            };
            call(request).await?;
            Ok(Done::Ok)
        }
    }
}
