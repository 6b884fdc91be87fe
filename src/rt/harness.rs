//! A loop over an `EchoBus` in lockstep, stepped by hand: for tests, benchmarks
//! and the allocation check. Same `ControlLoop` as the daemon runs.
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64};

use crossbeam_channel::{Receiver, Sender};

use crate::bus::echo::{EchoBus, EchoFaults};
use crate::controller_interface::catalog::Catalog;
use crate::controller_interface::registry::{self, BuildContext, Selection};
use crate::controllers::REGISTRY;
use crate::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use crate::module::MODULE_LENGTH_M;
use crate::rt::control_loop::{ControlLoop, LoopParts};
use crate::rt::controller_slots::Installed;
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
    /// Controllers the loop replaced (drain and drop them off the loop).
    pub retired: Receiver<Installed>,
    /// The body the gaits (and controllers built for this loop) use.
    pub layout: BodyLayout,
    /// Names of the controllers installed (every gait starts on `open_loop`, as the
    /// daemon's default configuration does).
    pub catalog: Catalog,
}

/// `sel` built for `gait` of `layout` with `table`'s parameters, recorded in `catalog`.
///
/// # Panics
/// If the selection does not build (a test's mistake).
pub fn build_installed(
    catalog: &Catalog,
    layout: &BodyLayout,
    table: &GaitTable,
    gait: GaitKind,
    sel: &Selection,
) -> Installed {
    let ctx = BuildContext {
        gait,
        layout,
        params: table.get(gait),
    };
    let built = registry::build(REGISTRY, sel, &ctx).expect("the test's controller builds");
    let info = catalog.insert(built.info);
    Installed {
        id: info.id,
        controller: built.controller,
    }
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
    echo_harness_on(bus, GaitTable::default(), gait, hold_at_start, failsafe)
}

/// A loop over `bus` (e.g. with scripted torques) with gait parameters `table`.
pub fn echo_harness_on(
    bus: EchoBus,
    table: GaitTable,
    gait: GaitKind,
    hold_at_start: bool,
    failsafe: FailsafeConfig,
) -> Harness {
    echo_harness_sized(bus, table, gait, hold_at_start, failsafe, 16)
}

/// [`echo_harness_on`] with request and ack channels of `capacity`, as the daemon
/// sizes them from `control.channel_capacity`.
pub fn echo_harness_sized(
    bus: EchoBus,
    table: GaitTable,
    gait: GaitKind,
    hold_at_start: bool,
    failsafe: FailsafeConfig,
    capacity: usize,
) -> Harness {
    let faults = bus.faults();
    let pacer = Box::new(LockstepPacer::new(PERIOD_NS, 1_000_000_000));
    let mut h = harness_on_bus(
        Box::new(bus),
        pacer,
        table,
        gait,
        hold_at_start,
        failsafe,
        capacity,
    );
    h.faults = faults;
    h
}

/// A loop over any `bus` paced by `pacer` (e.g. the HEBI bus in real time); the
/// harness's `faults` are inert then.
pub fn harness_on_bus(
    bus: Box<dyn crate::bus::Bus>,
    pacer: Box<dyn crate::rt::pacer::Pacer>,
    table: GaitTable,
    gait: GaitKind,
    hold_at_start: bool,
    failsafe: FailsafeConfig,
    capacity: usize,
) -> Harness {
    let n = bus.module_count();
    let faults = EchoBus::new(n, PERIOD_NS).faults();
    let layout = BodyLayout::alternating(n, Plane::Lateral, MODULE_LENGTH_M);
    let estimators = crate::estimation::standard_estimators(&layout);
    let (control_ends, loop_ends) = super::channels::loop_channels(capacity);
    let (writer, reader) = telemetry::channel(Snapshot::new(n, gait, table, 2.0));
    let stop = Arc::new(AtomicBool::new(false));
    let catalog = Catalog::default();
    let open_loop = Selection::named("open_loop");
    let controllers = GaitKind::ALL
        .into_iter()
        .map(|g| (g, build_installed(&catalog, &layout, &table, g, &open_loop)))
        .collect();
    let control = ControlLoop::new(LoopParts {
        bus,
        pacer,
        selector: GaitSelector::new(
            layout.clone(),
            table,
            gait,
            2.0,
            crate::module::MODULE_MAX_SPEED_RAD_S,
        ),
        failsafe: Failsafe::new(failsafe),
        requests: loop_ends.requests,
        acks: loop_ends.acks,
        telemetry: writer,
        heartbeat: Arc::new(AtomicU64::new(0)),
        stop: stop.clone(),
        velocity_feedforward: true,
        hold_at_start,
        retired: loop_ends.retired,
        controllers,
        estimators,
        observer: None,
    });
    Harness {
        control,
        requests: control_ends.requests,
        acks: control_ends.acks,
        telemetry: reader,
        stop,
        faults,
        retired: control_ends.retired,
        layout,
        catalog,
    }
}
