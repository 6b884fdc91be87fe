//! A loop over an `EchoBus` in lockstep, stepped by hand: for tests, benchmarks
//! and the allocation check. Same `ControlLoop` as the daemon runs.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64};

use crossbeam_channel::{Receiver, Sender};

use crate::bus::echo::{EchoBus, EchoFaults};
use crate::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use crate::rt::control_loop::{ControlLoop, LoopParts};
use crate::rt::messages::{Ack, Envelope};
use crate::rt::pacer::LockstepPacer;
use crate::rt::telemetry::{self, Snapshot, TelemetryReader};
use crate::safety::failsafe::{Failsafe, FailsafeConfig};

pub const PERIOD_NS: u64 = 1_000_000;

pub struct Harness {
    pub control: ControlLoop,
    pub requests: Sender<Envelope>,
    pub acks: Receiver<Ack>,
    pub telemetry: TelemetryReader,
    pub stop: Arc<AtomicBool>,
    pub faults: Arc<EchoFaults>,
}

/// `n` modules starting at `pose` (or straight), running `gait`.
pub fn echo_harness(
    n: usize,
    pose: Option<&[f32]>,
    gait: GaitKind,
    hold_at_start: bool,
    failsafe: FailsafeConfig,
) -> Harness {
    let mut bus = EchoBus::new(n, PERIOD_NS);
    if let Some(p) = pose {
        bus = bus.with_positions(p);
    }
    let faults = bus.faults();
    let table = GaitTable::default();
    let layout = BodyLayout::alternating(n, Plane::Lateral, 0.064);
    let (req_tx, req_rx) = crossbeam_channel::bounded(16);
    let (ack_tx, ack_rx) = crossbeam_channel::bounded(16);
    let (writer, reader) = telemetry::channel(Snapshot::new(n, gait, table, 2.0));
    let stop = Arc::new(AtomicBool::new(false));
    let control = ControlLoop::new(LoopParts {
        bus: Box::new(bus),
        pacer: Box::new(LockstepPacer::new(PERIOD_NS, 1_000_000_000)),
        selector: GaitSelector::new(layout, table, gait, 2.0, 3.46),
        failsafe: Failsafe::new(failsafe),
        requests: req_rx,
        acks: ack_tx,
        telemetry: writer,
        heartbeat: Arc::new(AtomicU64::new(0)),
        stop: stop.clone(),
        velocity_feedforward: true,
        hold_at_start,
    });
    Harness {
        control,
        requests: req_tx,
        acks: ack_rx,
        telemetry: reader,
        stop,
        faults,
    }
}
