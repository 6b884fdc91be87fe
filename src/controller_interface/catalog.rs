//! Who is who among built controllers: every controller gets an id when it is built
//! (off the loop), and its [`ControllerInfo`] (gait, name, preset, configuration,
//! the names and units of its report) goes into the [`Catalog`]. The loop only ever
//! handles the id; the socket, the recorder and the live view look the names up here.
//! The catalog's lock is never taken by the loop thread.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, RwLock};

use serde::Serialize;

use super::report::ReportSpec;
use crate::gait::GaitKind;

/// Id 0 is "no controller".
pub const NO_CONTROLLER: u64 = 0;

/// Entries kept; the oldest are forgotten (an id in old telemetry then shows unnamed).
const KEEP: usize = 256;

/// What a built controller is.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ControllerInfo {
    pub id: u64,
    pub gait: GaitKind,
    /// The controller's registry name.
    pub controller: &'static str,
    /// The preset it was built from.
    pub preset: &'static str,
    /// Its whole configuration, preset with overrides merged (as JSON).
    pub config: serde_json::Value,
    /// Names and units of its report.
    pub report: ReportSpec,
}

/// Shared map from id to info (cheap to clone).
#[derive(Debug, Clone, Default)]
pub struct Catalog {
    inner: Arc<RwLock<BTreeMap<u64, Arc<ControllerInfo>>>>,
}

static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A fresh controller id (never [`NO_CONTROLLER`], unique in the process).
pub fn next_id() -> u64 {
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

impl Catalog {
    pub fn insert(&self, info: ControllerInfo) -> Arc<ControllerInfo> {
        let info = Arc::new(info);
        let mut map = self.inner.write().unwrap_or_else(|e| e.into_inner());
        map.insert(info.id, info.clone());
        while map.len() > KEEP {
            map.pop_first();
        }
        info
    }

    pub fn get(&self, id: u64) -> Option<Arc<ControllerInfo>> {
        let map = self.inner.read().unwrap_or_else(|e| e.into_inner());
        map.get(&id).cloned()
    }
}
