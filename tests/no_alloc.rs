//! The real-time path allocates nothing: a counting global allocator watches whole
//! control cycles (feedback, requests, failsafe, gait blend, commands, telemetry).
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use snaked::gait::{GaitKind, ParamPatch};
use snaked::rt::harness::echo_harness;
use snaked::rt::messages::{Envelope, LoopRequest};
use snaked::safety::failsafe::FailsafeConfig;

struct Counting;
static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn control_cycles_allocate_nothing() {
    let mut h = echo_harness(
        18,
        None,
        GaitKind::Sidewinding,
        false,
        FailsafeConfig::default(),
    );
    for _ in 0..100 {
        h.control.step();
    }
    let reqs = [
        LoopRequest::SetGait(GaitKind::Slithering),
        LoopRequest::SetParams(
            GaitKind::Slithering,
            ParamPatch {
                temporal_freq_rad_s: Some(1.0),
                ..Default::default()
            },
        ),
        LoopRequest::Hold,
        LoopRequest::Arm,
        LoopRequest::SetGait(GaitKind::RollingHelix),
    ];
    COUNTING.store(true, Ordering::SeqCst);
    for (k, r) in reqs.iter().enumerate() {
        h.requests
            .try_send(Envelope {
                ticket: k as u64,
                request: *r,
            })
            .unwrap();
        for _ in 0..700 {
            h.control.step();
        }
        let _ = h.acks.try_recv();
    }
    h.faults.set_silent(3, true);
    for _ in 0..1000 {
        h.control.step();
    }
    COUNTING.store(false, Ordering::SeqCst);
    let n = ALLOCS.load(Ordering::SeqCst);
    assert_eq!(n, 0, "{n} allocations in the real-time path");
    // The loop really did go through those states.
    assert!(h.telemetry.latest().cycle > 4000);
}
