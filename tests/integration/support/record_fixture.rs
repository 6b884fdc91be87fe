//! Synthetic recordings for the recorder's tests: a fake controller in a catalog, a
//! scripted run of cycles, events and stats with known per-channel counts, and a reader
//! (the `mcap` crate) that counts what a file holds.

use std::collections::BTreeMap;
use std::path::Path;

use snaked::controller_interface::catalog::{Catalog, ControllerInfo, next_id};
use snaked::emu::world::{Peg, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, Plane};
use snaked::record::{
    CycleRecord, RecordEvent, RecordItem, RecordOptions, RecordTx, RecordingInfo,
};
use snaked::rt::messages::{LoopRequest, Refusal, Rejection};
use snaked::rt::stats::LoopStats;
use snaked::safety::failsafe::{Mode, Reason};

pub const MODULES: usize = 6;
/// Loop period of the synthetic run, ns (1 kHz).
pub const PERIOD_NS: u64 = 1_000_000;

/// A catalog holding one compliant-looking controller; its id.
pub fn catalog() -> (Catalog, u64) {
    let catalog = Catalog::default();
    let id = next_id();
    catalog.insert(ControllerInfo {
        id,
        gait: GaitKind::Slithering,
        controller: "fake_compliant",
        preset: "test",
        config: serde_json::json!({"gain": 0.5}),
        report: snaked::controller_interface::testing::sample_report_spec(),
    });
    (catalog, id)
}

pub fn info(catalog: Catalog, world: bool) -> RecordingInfo {
    RecordingInfo {
        source: "snake-lab".into(),
        module_names: (0..MODULES).map(|i| format!("m{i}")).collect(),
        layout: BodyLayout::alternating(MODULES, Plane::Lateral, 0.064),
        world: world.then(|| WorldSpec {
            pegs: vec![Peg {
                x_m: 0.5,
                y_m: 0.2,
                diameter_m: 0.1,
                height_m: 0.3,
            }],
            ..WorldSpec::default()
        }),
        catalog,
        metadata: vec![("scenario".into(), "test".into())],
    }
}

/// Cycle `k` of the scripted run: controller set from k = 50, engaged for
/// 100 ≤ k < 250, ground-truth links when `links`.
pub fn cycle(k: u64, controller_id: u64, links: bool) -> RecordItem {
    let mut r = CycleRecord::EMPTY;
    r.cycle = k;
    r.t_ns = k * PERIOD_NS;
    r.mode = Mode::Running;
    r.reason = Reason::Operator;
    r.modules = MODULES;
    for (i, j) in r.joints[..MODULES].iter_mut().enumerate() {
        let a = 0.3 * ((k as f32) * 0.01 + i as f32).sin();
        j.position_rad = a;
        j.velocity_rad_s = 0.1;
        j.torque_nm = -0.2;
        j.cmd_position_rad = a;
        j.cmd_velocity_rad_s = f32::NAN;
        j.accel_m_s2 = [0.0, 0.0, 9.81];
    }
    if k >= 50 {
        r.controller_id = controller_id;
    }
    r.engaged = (100..250).contains(&k);
    if k >= 200 {
        // The navigator runs from 200 ms on.
        r.navigator = snaked::navigation::state::NavigatorState {
            active: true,
            travel_rad: 0.25,
            choice: Some(snaked::navigation::navigator::Choice::Sidewind),
            why: Some(snaked::navigation::navigator::Why::Start),
            switches: 0,
            stopped: None,
            goal_m: Some([2.0, 0.5]),
            by_position: true,
            distance_m: 1.5,
            cross_track_m: 0.1,
        };
    }
    if r.engaged {
        r.report.signals[0] = 0.4;
        r.report.signals[1] = 2.0;
        let f = &mut r.report.fields[0];
        f.count = 2;
        f.a[..2].copy_from_slice(&[f64::NEG_INFINITY, 0.5]);
        f.b[..2].copy_from_slice(&[0.5, f64::INFINITY]);
    }
    if links {
        r.links = MODULES + 1;
        for (n, p) in r.link_poses[..MODULES + 1].iter_mut().enumerate() {
            p.position_m = [k as f64 * 1e-4 - 0.064 * n as f64, 0.0, 0.0255];
        }
    }
    RecordItem::Cycle(r)
}

fn event(k: u64, event: RecordEvent) -> RecordItem {
    RecordItem::Event {
        t_ns: k * PERIOD_NS,
        event,
    }
}

/// Events of the scripted run at cycle `k` (every kind once, a request both ways).
pub fn events_at(k: u64, controller_id: u64) -> Vec<RecordItem> {
    let gait = GaitKind::Slithering;
    match k {
        0 => vec![event(
            k,
            RecordEvent::Mode {
                mode: Mode::Running,
                reason: Reason::Operator,
            },
        )],
        10 => vec![event(
            k,
            RecordEvent::Request {
                ticket: 1,
                request: LoopRequest::SetGait { gait },
                result: Ok(None),
            },
        )],
        20 => vec![event(
            k,
            RecordEvent::Request {
                ticket: 2,
                request: LoopRequest::Arm,
                result: Err(Rejection::Failsafe(Refusal::FeedbackUnhealthy)),
            },
        )],
        100 => vec![event(
            k,
            RecordEvent::Engaged {
                gait,
                controller_id,
            },
        )],
        200 => vec![event(
            k,
            RecordEvent::SetpointFault {
                joint: 3,
                controller_id,
            },
        )],
        250 => vec![event(
            k,
            RecordEvent::Released {
                gait,
                controller_id,
            },
        )],
        _ => Vec::new(),
    }
}

/// Stats of the scripted run at cycle `k` (every 100 cycles).
pub fn stats_at(k: u64) -> Option<RecordItem> {
    k.is_multiple_of(100).then(|| {
        let mut stats = LoopStats::default();
        stats.cycles = k;
        RecordItem::Stats {
            t_ns: k * PERIOD_NS,
            stats,
        }
    })
}

/// Every item of the first `cycles` cycles of the scripted run, in time order.
pub fn run(cycles: u64, controller_id: u64, links: bool) -> Vec<RecordItem> {
    let mut items = Vec::new();
    for k in 0..cycles {
        items.extend(events_at(k, controller_id));
        items.extend(stats_at(k));
        items.push(cycle(k, controller_id, links));
    }
    items
}

/// Messages per topic of the full 300-cycle run (with links and a world).
pub fn expected_counts_300() -> BTreeMap<String, u64> {
    [
        ("/joints", 300),
        ("/commands", 300),
        ("/imu", 300),
        ("/body/estimate", 300),
        ("/navigation", 300),
        ("/controller/signals", 300),
        ("/controller/windows", 150),
        ("/controller/info", 1),
        ("/events", 6),
        ("/stats", 3),
        // 50 Hz over 0..300 ms: t = 0, 20, ..., 280 ms.
        ("/tf", 15),
        ("/scene/body", 15),
        ("/scene/world", 1),
    ]
    .into_iter()
    .map(|(t, n)| (t.to_owned(), n))
    .collect()
}

/// Options big enough that nothing of the scripted run is dropped.
pub fn options(items: usize) -> RecordOptions {
    RecordOptions {
        ring_capacity: items + 16,
        ..RecordOptions::default()
    }
}

/// Pushes every item, asserting the ring took it.
pub fn push_all(tx: &RecordTx, items: &[RecordItem]) {
    for (n, item) in items.iter().enumerate() {
        assert!(tx.push(item), "item {n} refused");
    }
}

/// Pushes every item, waiting while the ring is full (nothing is dropped).
pub fn push_all_waiting(tx: &RecordTx, items: &[RecordItem]) {
    for (n, item) in items.iter().enumerate() {
        assert!(
            tx.push_wait(item),
            "item {n} refused: the recorder finished"
        );
    }
}

/// What an MCAP file holds, read with the `mcap` crate.
pub struct FileReport {
    /// Messages per topic (from reading every message).
    pub counts: BTreeMap<String, u64>,
    /// Topic → (schema name, schema encoding, message encoding).
    pub channels: BTreeMap<String, (String, String, String)>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Message count in the summary's statistics.
    pub summary_messages: u64,
    /// The first message of each topic.
    pub first: BTreeMap<String, Vec<u8>>,
    /// The last message of each topic.
    pub last: BTreeMap<String, Vec<u8>>,
}

pub fn read_mcap(path: &Path) -> FileReport {
    let bytes = std::fs::read(path).expect("read the recording");
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable summary")
        .expect("the file has a summary (it was finished)");
    let mut channels = BTreeMap::new();
    for c in summary.channels.values() {
        let s = c.schema.as_ref().expect("every channel has a schema");
        channels.insert(
            c.topic.clone(),
            (
                s.name.clone(),
                s.encoding.clone(),
                c.message_encoding.clone(),
            ),
        );
    }
    let mut counts = BTreeMap::new();
    let mut first = BTreeMap::new();
    let mut last = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("a message stream") {
        let m = m.expect("a valid message");
        *counts.entry(m.channel.topic.clone()).or_insert(0) += 1;
        first
            .entry(m.channel.topic.clone())
            .or_insert_with(|| m.data.to_vec());
        last.insert(m.channel.topic.clone(), m.data.to_vec());
    }
    let metadata = summary
        .metadata_indexes
        .iter()
        .map(|i| {
            let m = mcap::read::metadata(&bytes, i).expect("a metadata record");
            (m.name, m.metadata)
        })
        .collect();
    FileReport {
        counts,
        channels,
        metadata,
        summary_messages: summary.stats.map_or(0, |s| s.message_count),
        first,
        last,
    }
}
