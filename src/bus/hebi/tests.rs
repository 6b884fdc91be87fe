//! The HEBI bus over the fake group (what imitation cannot show) and over HEBI's own
//! imitation group (the library in the loop).

use std::sync::atomic::Ordering::Relaxed;
use std::time::Duration;

use super::fake::FakeGroup;
use super::gains::ModuleSettings;
use super::lookup::{Source, Spec};
use super::mailbox::{self, mailbox};
use super::*;
use crate::bus::GroupFeedback;

pub(crate) fn fake_bus(n: usize, order: Vec<usize>) -> (HebiBus, Arc<fake::FakeControl>) {
    assert_eq!(order.len(), n);
    let (writer, output) = mailbox(order);
    let counters = writer.counters();
    let (group, control) = FakeGroup::new(writer);
    let start = Start {
        feedback_rate_hz: 1000.0,
        command_lifetime_ms: 50,
        settings: (0..n)
            .map(|i| ModuleSettings {
                strategy: Some(3),
                floats: vec![(2, i as f32)],
            })
            .collect(),
    };
    let bus = HebiBus::start(Box::new(group), output, counters, &start).unwrap();
    (bus, control)
}

#[test]
fn start_sets_lifetime_rate_and_gains_and_release_commands_limp() {
    let (mut bus, control) = fake_bus(4, vec![0, 1, 2, 3]);
    assert_eq!(control.lifetime_ms.load(Relaxed), 50);
    assert_eq!(control.feedback_rate_hz.load(Relaxed), 1000);
    let settings = control.log.lock().unwrap().settings.clone();
    assert_eq!(settings.len(), 4);
    assert_eq!(settings[3].floats, vec![(2, 3.0)]);
    bus.send(&[Command::position(0.1); 4]).unwrap();
    assert!(control.acting(mailbox::monotonic_ns()));
    bus.release();
    let log = control.log.lock().unwrap().clone();
    assert!(log.released);
    assert_eq!(
        log.limp_commands, 1,
        "an explicit limp command before letting go"
    );
    assert!(log.last_commands.iter().all(Command::is_limp));
}

#[test]
fn a_dead_daemons_modules_stop_after_the_lifetime() {
    let (mut bus, control) = fake_bus(2, vec![0, 1]);
    bus.send(&[Command::position(0.3); 2]).unwrap();
    let sent = control.log.lock().unwrap().last_command_ns;
    std::mem::forget(bus); // killed: no release, no limp command
    assert!(control.acting(sent + 49_000_000));
    assert!(!control.acting(sent + 51_000_000));
}

#[test]
fn feedback_arrives_in_body_order_with_imu_and_counts() {
    let (mut bus, control) = fake_bus(3, vec![2, 0, 1]);
    let mut g = GroupFeedback::new(3);
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert!(
        g.modules
            .iter()
            .all(|m| !m.fresh && m.received_ns.is_none())
    );
    // Body position i is group module order[i]: the fake echoes in group order.
    bus.send(&[0.1, 0.2, 0.3].map(Command::position)).unwrap();
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    let pos: Vec<f32> = g.modules.iter().map(|m| m.feedback.position_rad).collect();
    assert_eq!(pos, vec![0.1, 0.2, 0.3]);
    assert!(g.modules.iter().all(|m| m.fresh));
    assert_eq!(g.modules[0].feedback.accel_m_s2, [0.0, 0.0, 9.81]);
    // Nothing new: not fresh, kept.
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert!(
        g.modules
            .iter()
            .all(|m| !m.fresh && m.feedback.position_rad > 0.0)
    );
    // A lost module stays at its last feedback and is counted.
    control.lost[1].store(true, Relaxed);
    bus.send(&[0.4, 0.5, 0.6].map(Command::position)).unwrap();
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert!(g.modules[0].fresh && !g.modules[1].fresh && g.modules[2].fresh);
    assert_eq!(g.modules[1].feedback.position_rad, 0.2);
    let c = bus.counters();
    assert_eq!(c.feedback_lost, 1);
    assert_eq!(c.detail.get("absent"), Some(1));
    assert_eq!(c.feedback_received, 5);
    assert_eq!(c.commands_sent, 2);
    // Two group feedbacks before a receive: the older is superseded.
    bus.send(&[0.0; 3].map(Command::position)).unwrap();
    bus.send(&[0.0; 3].map(Command::position)).unwrap();
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert_eq!(bus.counters().detail.get("superseded"), Some(1));
    // A missing IMU reads NaN, never a number.
    control.no_imu[0].store(true, Relaxed);
    bus.send(&[0.0; 3].map(Command::position)).unwrap();
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert!(g.modules[0].feedback.accel_m_s2.iter().all(|v| v.is_nan()));
    assert!(g.modules[0].feedback.gyro_rad_s.iter().all(|v| v.is_nan()));
}

#[test]
fn a_stalled_stream_leaves_every_module_unfresh() {
    let (mut bus, control) = fake_bus(2, vec![0, 1]);
    let mut g = GroupFeedback::new(2);
    bus.send(&[Command::position(0.0); 2]).unwrap();
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    let arrived = g.modules[0].received_ns;
    control.stalled.store(true, Relaxed);
    for _ in 0..5 {
        bus.send(&[Command::position(0.0); 2]).unwrap();
        bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
        assert!(g.modules.iter().all(|m| !m.fresh));
    }
    assert_eq!(
        g.modules[0].received_ns, arrived,
        "age grows from the last arrival"
    );
}

#[test]
fn wrong_command_count_is_refused() {
    let (mut bus, _) = fake_bus(2, vec![0, 1]);
    assert!(matches!(
        bus.send(&[Command::LIMP; 3]),
        Err(BusError::WrongCount {
            expected: 2,
            got: 3
        })
    ));
}

/// libhebi for the tests: found as the daemon finds it, else fetched by
/// scripts/fetch-libhebi.sh (pinned, checksummed). Missing is a failure, not a skip.
pub fn test_library() -> &'static library::Api {
    let path = library::find(None).unwrap_or_else(|_| {
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/fetch-libhebi.sh");
        let out = std::process::Command::new(script)
            .output()
            .expect("running scripts/fetch-libhebi.sh");
        assert!(
            out.status.success(),
            "libhebi is needed by the HEBI tests and scripts/fetch-libhebi.sh failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::path::PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
    });
    library::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

pub(crate) fn imitation_bus(n: usize) -> HebiBus {
    let api = test_library();
    let spec = Spec {
        interfaces: vec!["127.0.0.1".into()],
        source: Source::Imitation(n),
        order: vec![],
        timeout: Duration::from_millis(100),
    };
    let o = lookup::open(api, &spec).unwrap();
    let (writer, output) = mailbox(o.order.clone());
    let counters = writer.counters();
    // SAFETY: a live group of n modules from `open`.
    let group =
        unsafe { group::LibGroup::new(api, o.group, o.lookup, &o.order, o.imitation, writer) }
            .unwrap();
    let start = Start {
        feedback_rate_hz: 1000.0,
        command_lifetime_ms: 50,
        settings: vec![],
    };
    HebiBus::start(Box::new(group), output, counters, &start).unwrap()
}

fn wait_fresh(bus: &mut HebiBus, g: &mut GroupFeedback) {
    for _ in 0..200 {
        std::thread::sleep(Duration::from_millis(2));
        bus.receive(g, 0, FeedbackWait::None).unwrap();
        if g.modules.iter().all(|m| m.fresh) {
            return;
        }
    }
    panic!("no group feedback from the imitation group in 400 ms");
}

#[test]
fn imitation_group_echoes_the_commands_through_libhebi() {
    let api = test_library();
    assert_eq!(api.version.0, 2);
    let mut bus = imitation_bus(18);
    assert_eq!(bus.module_count(), 18);
    let mut g = GroupFeedback::new(18);
    let cmds: Vec<Command> = (0..18)
        .map(|i| Command {
            position_rad: 0.1 * i as f32 - 0.9 + 6.5,
            velocity_rad_s: 0.5,
            torque_nm: f32::NAN,
        })
        .collect();
    bus.send(&cmds).unwrap();
    // The imitation echoes the last command at the next feedback request; one requested
    // before the command reached libhebi may still arrive after it (seen under nextest's
    // parallel processes), so wait for a feedback with the echo, up to 400 ms.
    for _ in 0..20 {
        wait_fresh(&mut bus, &mut g);
        if g.modules[0].feedback.velocity_rad_s == 0.5 {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    for (m, c) in g.modules.iter().zip(&cmds) {
        let f = m.feedback;
        assert!((f.position_rad - c.position_rad).abs() < 1e-5, "{f:?}");
        assert_eq!(f.velocity_rad_s, 0.5);
        // An imitation group echoes only what was commanded: the bus commands an
        // unset effort as 0 there, so the echo is a number.
        assert_eq!(f.torque_nm, 0.0);
        assert!(
            f.accel_m_s2
                .iter()
                .chain(&f.gyro_rad_s)
                .all(|v| v.is_finite())
        );
    }
    let c = bus.counters();
    assert!(c.feedback_received >= 18 && c.commands_sent == 1, "{c:?}");
    assert!(c.detail.get("group_feedbacks").unwrap() >= 1);
    // Stopping the stream (feedback frequency 0) leaves the modules unfresh.
    bus.set_feedback_rate_hz(0.0).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    bus.receive(&mut g, 0, FeedbackWait::None).unwrap();
    assert!(g.modules.iter().all(|m| !m.fresh));
    bus.release();
}
