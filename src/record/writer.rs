//! The writer thread: drains the ring, turns each item into messages on the channels
//! (file and live view alike), enforces the caps, and finishes the file.

use std::collections::{BTreeMap, BTreeSet};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use foxglove::Context;
use foxglove::schemas::Timestamp;
use serde_json::json;

use super::cycle::{CycleRecord, RecordEvent, RecordItem};
use super::encode::{
    BodyEstimateMsg, Commands, ControllerSignals, ControllerWindows, Imu, Joints, NavigationMsg,
    RecorderHealth, Stats,
};
use super::error::RecordError;
use super::file::McapFile;
use super::options::{CapReason, FileState, RecordOptions, RecordSummary, RecordingInfo};
use super::ring::Ring;
use super::scene::{BodyDrawer, world_scene};
use super::topics::{Channels, Topic};
use super::urdf::{URDF_URI, urdf};
use crate::controller_interface::catalog::{Catalog, ControllerInfo, NO_CONTROLLER};
use crate::live::{Asset, Latch, Live};
use crate::rt::stats::LoopStats;

/// How long the writer sleeps when the ring is empty. The loop never wakes it (that
/// would be a syscall on the real-time thread), so this bounds the live view's delay.
const IDLE: Duration = Duration::from_millis(2);

/// What the writer thread and the [`super::Recorder`] share.
pub(crate) struct Shared {
    pub ring: Arc<Ring>,
    pub stop: AtomicBool,
    pub items: AtomicU64,
    pub written: AtomicU64,
    pub bytes: Arc<AtomicU64>,
    /// Loop time that complete chunks in the file hold, ns.
    pub complete_ns: AtomicU64,
    /// 0: not capped, else `1 + CapReason as u8`.
    capped: AtomicU8,
    /// 0: no file, else `1 + FileState as u8`.
    file: AtomicU8,
    /// The file's path, once created.
    pub path: OnceLock<PathBuf>,
    /// Why the file failed (the unfinished file's error).
    pub error: OnceLock<String>,
    /// Items taken from the ring after a failed write stopped the file.
    pub lost: AtomicU64,
}

impl Shared {
    pub fn new(ring: Arc<Ring>) -> Self {
        Self {
            ring,
            stop: AtomicBool::new(false),
            items: AtomicU64::new(0),
            written: AtomicU64::new(0),
            bytes: Arc::new(AtomicU64::new(0)),
            complete_ns: AtomicU64::new(0),
            capped: AtomicU8::new(0),
            file: AtomicU8::new(0),
            path: OnceLock::new(),
            error: OnceLock::new(),
            lost: AtomicU64::new(0),
        }
    }

    pub fn capped(&self) -> Option<CapReason> {
        match self.capped.load(Ordering::Acquire) {
            1 => Some(CapReason::MaxBytes),
            2 => Some(CapReason::MaxDuration),
            3 => Some(CapReason::WriteError),
            _ => None,
        }
    }

    fn set_capped(&self, r: CapReason) {
        let v = match r {
            CapReason::MaxBytes => 1,
            CapReason::MaxDuration => 2,
            CapReason::WriteError => 3,
        };
        self.capped.store(v, Ordering::Release);
    }

    pub fn file(&self) -> Option<FileState> {
        match self.file.load(Ordering::Acquire) {
            1 => Some(FileState::Writing),
            2 => Some(FileState::Finished),
            3 => Some(FileState::Unfinished),
            _ => None,
        }
    }

    fn set_file(&self, f: &McapFile) {
        self.complete_ns.store(f.complete_ns(), Ordering::Relaxed);
        let v = match f.state() {
            FileState::Writing => 1,
            FileState::Finished => 2,
            FileState::Unfinished => 3,
        };
        self.file.store(v, Ordering::Release);
    }
}

/// What the thread hands back once it is set up.
pub(crate) struct Setup {
    pub live_addr: Option<SocketAddr>,
    pub latch: Option<Arc<Latch>>,
}

pub(crate) struct Writer {
    // Dropped after the channels and sinks (fields drop in order).
    channels: Channels,
    file: Option<McapFile>,
    live: Option<Live>,
    catalog: Catalog,
    /// The controller of the last cycle, looked up when its id changes.
    current: Option<(u64, Option<Arc<ControllerInfo>>)>,
    /// Controller ids whose info has been published.
    seen: BTreeSet<u64>,
    body: BodyDrawer,
    scene_period_ns: u64,
    next_scene_ns: Option<u64>,
    /// Wall-clock time the recording started; a message's log time is this plus the
    /// loop time since the first item (so a lockstep run keeps its own time base).
    start_unix_ns: u64,
    t0_ns: Option<u64>,
    items: u64,
    shared: Arc<Shared>,
    /// Also handed every cycle (the ROS 2 node).
    pub sink: Option<Box<dyn super::recorder::CycleSink>>,
    ctx: Arc<Context>,
}

fn unix_ns_now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos().min(u128::from(u64::MAX)) as u64)
}

fn timestamp(unix_ns: u64) -> Timestamp {
    let sec = (unix_ns / 1_000_000_000).min(u64::from(u32::MAX)) as u32;
    Timestamp::new(sec, (unix_ns % 1_000_000_000) as u32)
}

impl Writer {
    /// The recording's context (its channels reach the file and the live view).
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// Starts the live view, creates the file, writes the metadata and the world.
    pub fn open(
        opts: &RecordOptions,
        info: RecordingInfo,
        shared: Arc<Shared>,
    ) -> Result<(Self, Setup), RecordError> {
        let ctx = Context::new();
        let mut channels = Channels::new(&ctx).map_err(RecordError::Setup)?;
        // The server first: if it cannot start, no empty file is left behind.
        let live = opts
            .live
            .as_ref()
            .map(|l| {
                // The robot's model, for the 3-D panel's URDF layer (and anything that
                // fetches it).
                let model = Asset {
                    uri: URDF_URI,
                    body: urdf(&info.layout, &info.module_names),
                };
                Live::start(l, &ctx, info.source.clone(), model)
            })
            .transpose()?;
        let file = opts
            .mcap
            .as_ref()
            .map(|m| McapFile::create(m, &ctx, shared.bytes.clone()))
            .transpose()?;
        if let Some(f) = &file {
            tracing::info!(path = %f.path().display(), "recorder: writing MCAP");
            shared.set_file(f);
            let _ = shared.path.set(f.path().to_path_buf());
        }
        channels.file_open = file.is_some();
        channels.latch = live.as_ref().map(|l| l.latch.clone());
        let setup = Setup {
            live_addr: live.as_ref().map(Live::addr),
            latch: channels.latch.clone(),
        };
        let start_unix_ns = unix_ns_now();
        if let Some(f) = &file {
            for (name, map) in metadata(&info, start_unix_ns, opts) {
                f.write_metadata(name, map)?;
            }
        }
        if let Some(world) = &info.world {
            let scene = world_scene(world, timestamp(start_unix_ns));
            channels.log_proto_latched(Topic::SceneWorld, 0, start_unix_ns, &scene);
        }
        let w = Self {
            channels,
            file,
            live,
            catalog: info.catalog,
            current: None,
            seen: BTreeSet::new(),
            body: BodyDrawer::new(info.layout),
            scene_period_ns: (1e9 / opts.scene_rate_hz).round().max(1.0) as u64,
            next_scene_ns: None,
            start_unix_ns,
            t0_ns: None,
            items: 0,
            shared,
            sink: None,
            ctx,
        };
        Ok((w, setup))
    }

    /// Drains the ring until told to stop, then finishes.
    pub fn run(mut self) -> Result<RecordSummary, RecordError> {
        loop {
            // Read before draining: whatever was pushed before `stop` is drained below.
            let stopping = self.shared.stop.load(Ordering::Acquire);
            let mut n = 0u32;
            while let Some(item) = self.shared.ring.pop() {
                self.handle(&item);
                n += 1;
                if n.is_multiple_of(64) {
                    self.publish_status();
                }
            }
            self.publish_status();
            if stopping {
                break;
            }
            if n == 0 {
                std::thread::park_timeout(IDLE);
            }
        }
        self.finish()
    }

    fn log_time(&mut self, t_ns: u64) -> u64 {
        let t0 = *self.t0_ns.get_or_insert(t_ns);
        self.start_unix_ns.saturating_add(t_ns.saturating_sub(t0))
    }

    pub fn handle(&mut self, item: &RecordItem) {
        self.items += 1;
        if self.shared.capped() == Some(CapReason::WriteError) {
            // The live view still gets it; the file never will.
            self.shared.lost.fetch_add(1, Ordering::Relaxed);
        }
        // A chunk due is closed before this item, so it spans less than its duration.
        if let Some(file) = self.file.as_mut().filter(|f| f.is_open()) {
            let t_ns = item.t_ns();
            file.before_item(t_ns.saturating_sub(self.t0_ns.unwrap_or(t_ns)));
        }
        match item {
            RecordItem::Cycle(rec) => self.cycle(rec),
            RecordItem::Event { t_ns, event } => self.event(*t_ns, event),
            RecordItem::Stats { t_ns, stats } => self.stats(*t_ns, stats),
        }
        self.check_caps(item.t_ns());
    }

    /// The info of controller `id`, published on `/controller/info` the first time.
    fn controller(&mut self, id: u64, log_time: u64) -> Option<Arc<ControllerInfo>> {
        if id == NO_CONTROLLER {
            return None;
        }
        if let Some((cid, info)) = &self.current
            && *cid == id
        {
            return info.clone();
        }
        let info = self.catalog.get(id);
        if self.seen.insert(id) {
            match &info {
                Some(i) => {
                    self.channels
                        .log_json_latched(Topic::ControllerInfo, id, log_time, |b| {
                            serde_json::to_writer(b, &**i)
                        })
                }
                None => tracing::warn!(id, "recorder: controller id not in the catalog"),
            }
        }
        self.current = Some((id, info.clone()));
        info
    }

    fn cycle(&mut self, rec: &CycleRecord) {
        let t = self.log_time(rec.t_ns);
        if let Some(sink) = self.sink.as_mut() {
            sink.cycle(rec, t);
        }
        let info = self.controller(rec.controller_id, t);
        let info = info.as_deref();
        let ch = &mut self.channels;
        ch.log_json(Topic::Joints, t, |b| {
            serde_json::to_writer(b, &Joints::new(rec))
        });
        ch.log_json(Topic::Commands, t, |b| {
            serde_json::to_writer(b, &Commands::new(rec))
        });
        ch.log_json(Topic::Imu, t, |b| serde_json::to_writer(b, &Imu::new(rec)));
        ch.log_json(Topic::BodyEstimate, t, |b| {
            serde_json::to_writer(b, &BodyEstimateMsg::new(rec))
        });
        ch.log_json(Topic::Navigation, t, |b| {
            serde_json::to_writer(b, &NavigationMsg::new(rec))
        });
        ch.log_json(Topic::ControllerSignals, t, |b| {
            serde_json::to_writer(b, &ControllerSignals::new(rec, info))
        });
        if let Some(w) = ControllerWindows::new(rec, info) {
            ch.log_json(Topic::ControllerWindows, t, |b| {
                serde_json::to_writer(b, &w)
            });
        }
        if self.next_scene_ns.is_none_or(|n| rec.t_ns >= n) {
            self.next_scene_ns = Some(rec.t_ns.saturating_add(self.scene_period_ns));
            let ts = timestamp(t);
            if ch.wanted(Topic::Tf) {
                ch.log_proto(Topic::Tf, t, &self.body.transforms(rec, ts));
            }
            if ch.wanted(Topic::SceneBody) {
                ch.log_proto(Topic::SceneBody, t, &self.body.body_scene(rec, ts));
            }
        }
    }

    fn event(&mut self, t_ns: u64, event: &RecordEvent) {
        let t = self.log_time(t_ns);
        if let RecordEvent::Engaged { controller_id, .. } = event {
            self.controller(*controller_id, t);
        }
        let catalog = &self.catalog;
        let name = |id: u64| catalog.get(id).map(|i| i.controller);
        self.channels.log_json(Topic::Events, t, |b| {
            super::encode::write_event(b, t_ns, event, name)
        });
    }

    fn stats(&mut self, t_ns: u64, stats: &LoopStats) {
        let t = self.log_time(t_ns);
        let health = RecorderHealth {
            dropped: self.shared.ring.dropped(),
            live_clients: self.live.as_ref().map_or(0, |l| l.latch.clients()),
        };
        self.channels.log_json(Topic::Stats, t, |b| {
            serde_json::to_writer(b, &Stats::new(t_ns, stats, health))
        });
    }

    /// Notes what reached the file, then stops it at a cap or a failed write.
    fn check_caps(&mut self, t_ns: u64) {
        let Some(file) = self.file.as_mut().filter(|f| f.is_open()) else {
            return;
        };
        let recorded_ns = t_ns.saturating_sub(self.t0_ns.unwrap_or(t_ns));
        file.item_written(recorded_ns);
        self.shared.set_file(file);
        let Some(reason) = file.cap_reached(recorded_ns) else {
            return;
        };
        self.shared.set_capped(reason);
        let (path, bytes) = (file.path().display().to_string(), file.size());
        // Say what state the file was left in: finished only if its end was written.
        match self.close_file() {
            Ok(()) => tracing::warn!(
                path,
                bytes,
                ?reason,
                "recorder: cap reached; the file is finished (summary and index), \
                 later items are not written"
            ),
            Err(e) => {
                // Shown by `status` before the log says it.
                let _ = self.shared.error.set(e.to_string());
                tracing::error!(?reason, "recorder: {e}; later items are not written");
            }
        }
    }

    /// Writes the final status and closes the file (summary and index).
    fn close_file(&mut self) -> Result<(), RecordError> {
        let Some(file) = self.file.as_mut().filter(|f| f.is_open()) else {
            return Ok(());
        };
        let status = final_status(&self.channels, self.items, &self.shared);
        // A failed status write shows again (as its cause) when the file closes.
        let _ = file.write_metadata("snaked.status", status);
        self.channels.file_open = false;
        let closed = file.close();
        self.shared.set_file(file);
        self.publish_status();
        closed
    }

    fn publish_status(&self) {
        self.shared.items.store(self.items, Ordering::Relaxed);
        self.shared
            .written
            .store(self.channels.written_total(), Ordering::Relaxed);
    }

    fn finish(mut self) -> Result<RecordSummary, RecordError> {
        // A file already stopped by a failed write reports it again here.
        let closed = match self.file.as_mut() {
            Some(f) if !f.is_open() => f.close(),
            _ => self.close_file(),
        };
        if let Some(live) = &mut self.live {
            live.stop();
        }
        if let Err(e) = &closed {
            let _ = self.shared.error.set(e.to_string());
        }
        closed?;
        let per_topic = Topic::ALL
            .iter()
            .map(|t| (t.name().to_owned(), self.channels.written(*t)))
            .filter(|(_, n)| *n > 0)
            .collect();
        tracing::info!(
            items = self.items,
            messages = self.channels.written_total(),
            dropped = self.shared.ring.dropped(),
            capped = ?self.shared.capped(),
            "recorder: finished"
        );
        Ok(RecordSummary {
            path: self.file.as_ref().map(|f| f.path().to_path_buf()),
            items: self.items,
            messages_written: self.channels.written_total(),
            per_topic,
            dropped: self.shared.ring.dropped(),
            bytes: self.file.as_ref().map_or(0, McapFile::size),
            capped: self.shared.capped(),
        })
    }
}

/// The `snaked.status` metadata record written when the file closes.
fn final_status(channels: &Channels, items: u64, shared: &Shared) -> BTreeMap<String, String> {
    let per_topic: BTreeMap<&str, u64> = Topic::ALL
        .iter()
        .map(|t| (t.name(), channels.written(*t)))
        .filter(|(_, n)| *n > 0)
        .collect();
    let capped = shared.capped().map_or_else(
        || "none".to_owned(),
        |r| json!(r).as_str().unwrap_or("?").to_owned(),
    );
    BTreeMap::from([
        ("items".to_owned(), items.to_string()),
        (
            "messages_written".to_owned(),
            channels.written_total().to_string(),
        ),
        ("dropped".to_owned(), shared.ring.dropped().to_string()),
        ("capped".to_owned(), capped),
        ("per_topic".to_owned(), json!(per_topic).to_string()),
    ])
}

/// The metadata records written at the start: what the recording is of, and the
/// caller's own pairs.
fn metadata(
    info: &RecordingInfo,
    start_unix_ns: u64,
    opts: &RecordOptions,
) -> Vec<(&'static str, BTreeMap<String, String>)> {
    let l = &info.layout;
    let layout = json!({"planes": l.planes, "s": l.s, "module_length_m": l.module_length_m});
    let mut rec = BTreeMap::from([
        ("source".to_owned(), info.source.clone()),
        (
            "module_names".to_owned(),
            json!(info.module_names).to_string(),
        ),
        ("modules".to_owned(), l.len().to_string()),
        ("layout".to_owned(), layout.to_string()),
        ("start_unix_ns".to_owned(), start_unix_ns.to_string()),
        ("scene_rate_hz".to_owned(), opts.scene_rate_hz.to_string()),
        ("ring_capacity".to_owned(), opts.ring_capacity.to_string()),
        (
            "time".to_owned(),
            "log_time = start_unix_ns + (loop t_ns - first item's t_ns)".to_owned(),
        ),
        (
            "snaked_version".to_owned(),
            env!("CARGO_PKG_VERSION").to_owned(),
        ),
    ]);
    if let Some(w) = &info.world {
        rec.insert("world".to_owned(), json!(w).to_string());
    }
    let user: BTreeMap<String, String> = info.metadata.iter().cloned().collect();
    vec![("snaked.recording", rec), ("snaked.metadata", user)]
}
