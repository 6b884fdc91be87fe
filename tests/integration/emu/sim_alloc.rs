//! The in-process bus and the joint-space plant allocate nothing per cycle.

use snaked::bus::{Bus, FeedbackWait, GroupFeedback};
use snaked::emu::plant::{JointSpacePlant, Obstacle, ObstacleSide, PlantConfig, ScriptedTorque};
use snaked::emu::sim_bus::{SimBus, SimBusConfig};
use snaked::protocol::Command;

use crate::support::counting_alloc;
use counting_alloc::allocations;

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
    let before = allocations();
    for k in 1..200 {
        bus.send(&commands).unwrap();
        bus.receive(&mut group, k, FeedbackWait::None).unwrap();
    }
    let after = allocations();
    assert_eq!(after - before, 0, "allocations in the cycle");
    assert!(group.modules.iter().all(|m| m.fresh));
}
