//! What the operator API shares between its callers.
use crossbeam_channel::Receiver;

use super::handle::{DaemonInfo, RecordView};
use super::router::AckRouter;
use crate::controller_interface::catalog::Catalog;
use crate::gait::BodyLayout;
use crate::rt::controller_slots::Installed;
use crate::rt::telemetry::TelemetryReader;

pub(crate) struct Shared {
    pub(crate) router: AckRouter,
    pub(crate) telemetry: TelemetryReader,
    pub(crate) info: DaemonInfo,
    /// The loop's body: controllers are built for it here, off the loop.
    pub(crate) layout: BodyLayout,
    /// Controllers the loop replaced or refused; freed here.
    pub(crate) retired: Receiver<Installed>,
    /// Names and configurations of every controller built.
    pub(crate) catalog: Catalog,
    /// Held by a controller change from reading what is installed to the loop's ack,
    /// so each change builds on what the previous one left.
    pub(crate) controller_change: tokio::sync::Mutex<()>,
    /// Who drives (one operator at a time).
    pub(crate) driver: super::driver::DriverLease,
    /// The navigator's task while it runs (`navigate`).
    pub(crate) navigation: super::navigate::Navigation,
    /// The recorder's state, if there is a recorder.
    pub(crate) record: Option<RecordView>,
    /// The daemon's pose input, if it has one.
    pub(crate) pose: Option<crate::estimation::external_pose::PoseInput>,
    /// True once the daemon shuts down (long requests give up).
    pub(crate) closing: tokio::sync::watch::Receiver<bool>,
}

impl Shared {
    /// Drops the controllers the loop replaced (freeing is off the loop's thread).
    pub(crate) fn free_retired(&self) {
        while let Ok(old) = self.retired.try_recv() {
            drop(old);
        }
    }
}
