//! The in-process bus and the joint-space plant allocate nothing per cycle.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use snaked::bus::sim::{SimBus, SimBusConfig};
use snaked::bus::{Bus, FeedbackWait, GroupFeedback};
use snaked::emu::plant::{JointSpacePlant, Obstacle, ObstacleSide, PlantConfig, ScriptedTorque};
use snaked::protocol::Command;

struct Counting;
static ALLOCS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards to the system allocator; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn sim_bus_cycle_does_not_allocate() {
    let mut config = PlantConfig::new(18);
    config.torques.push(ScriptedTorque {
        joint: 3,
        torque_nm: 1.0,
        start_s: 0.0,
        end_s: 1.0,
    });
    config.obstacles.push(Obstacle {
        joint: 4,
        angle_rad: 0.1,
        side: ObstacleSide::Positive,
        stiffness_nm_per_rad: 50.0,
        damping_nm_s_per_rad: 0.1,
    });
    let plant = JointSpacePlant::new(config).unwrap();
    let mut bus = SimBus::new(Box::new(plant), SimBusConfig::default());
    let mut group = GroupFeedback::new(18);
    let commands = vec![Command::position(0.3); 18];
    // Warm up outside the measurement.
    bus.send(&commands).unwrap();
    bus.receive(&mut group, 0, FeedbackWait::None).unwrap();
    let before = ALLOCS.load(Ordering::Relaxed);
    for k in 1..200 {
        bus.send(&commands).unwrap();
        bus.receive(&mut group, k, FeedbackWait::None).unwrap();
    }
    let after = ALLOCS.load(Ordering::Relaxed);
    assert_eq!(after - before, 0, "allocations in the cycle");
    assert!(group.modules.iter().all(|m| m.fresh));
}
