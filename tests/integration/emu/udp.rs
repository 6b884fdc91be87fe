//! The UDP emulator end to end over loopback, spoken to with the protocol codec.
//! Servers bind OS-chosen ports (base_port 0), so parallel tests never collide.

use std::time::{Duration, Instant};

use snaked::emu::plant::{NoiseConfig, Obstacle, ObstacleSide, PlantConfig};
use snaked::emu::server::{Mode, ServerConfig};
use snaked::protocol::{Command, ControlStrategy, LookupFilter, Message, Name, Settings};

use crate::support::emu_client;
use emu_client::{Client, Running, S};

fn exact_plant(n: usize) -> PlantConfig {
    PlantConfig {
        noise: NoiseConfig::NONE,
        ..PlantConfig::new(n)
    }
}

#[test]
fn realtime_protocol_end_to_end() {
    let mut plant = exact_plant(3);
    // An obstacle past 0.2 rad on joint 1: holding 0.3 shows torque, limp shows none.
    plant.obstacles.push(Obstacle {
        joint: 1,
        angle_rad: 0.2,
        side: ObstacleSide::Positive,
        stiffness_nm_per_rad: 20.0,
        damping_nm_s_per_rad: 0.2,
    });
    let config = ServerConfig {
        base_port: 0,
        mode: Mode::Realtime,
        ..ServerConfig::default()
    };
    let emu = Running::start(config, plant);
    let mut c = Client::new();
    let m1 = emu.addrs[1];

    // Lookup → announce; a filter that does not match gets no answer.
    c.send(m1, 0, &Message::Lookup(LookupFilter::All));
    let (_, _, msg) = c.reply().expect("announce");
    let Message::Announce(a) = msg else {
        panic!("{msg:?}")
    };
    assert_eq!(a.name.as_str(), "module-02");
    assert_eq!(a.family.as_str(), "SEA");
    assert!(!a.owned);
    c.send(
        m1,
        0,
        &Message::Lookup(LookupFilter::Family(Name::new("X5").unwrap())),
    );
    assert!(c.recv(Duration::from_millis(200)).is_none());

    // Acquire and configure.
    c.acquire(m1);
    let settings = Settings {
        feedback_rate_hz: 200.0,
        command_lifetime_s: 0.1,
        strategy: ControlStrategy::Cascaded,
    };
    c.settings(m1, settings);

    // Commands move the joint; feedback echoes the command seq.
    let mut last_seq = 0;
    // 2 s: the servo's slow position integral (docs/emulator.md, "The servo loop") takes
    // the obstacle's 2 N·m off the position error with a time constant of about 1.7 s.
    let end = Instant::now() + Duration::from_millis(2000);
    while Instant::now() < end {
        last_seq = c.send(m1, S, &Message::Command(Command::position(0.3)));
        // Paces the loop and drains the feedback stream so what follows is fresh.
        let _ = c.feedback_from(m1, Duration::from_millis(10));
    }
    let held = c.feedback_from(m1, Duration::from_millis(30));
    let (_, f) = *held.last().expect("feedback while commanded");
    assert!((f.position_rad - 0.3).abs() < 0.02, "{}", f.position_rad);
    assert!(
        f.torque_nm > 1.5,
        "holding against the obstacle: {}",
        f.torque_nm
    );
    assert!(
        f.last_command_seq + 2 >= last_seq,
        "{} vs {last_seq}",
        f.last_command_seq
    );

    // Stop commanding: after the lifetime the module goes limp and the obstacle wins.
    let after = c.feedback_from(m1, Duration::from_millis(400));
    assert!(after.len() > 20, "{} feedbacks", after.len());
    let (_, f) = after.last().unwrap();
    assert!(f.torque_nm.abs() < 0.1, "limp: {}", f.torque_nm);
    assert!(f.position_rad < 0.21, "{}", f.position_rad);
    // Seq increments by exactly one per feedback (loopback loses nothing here).
    for w in after.windows(2) {
        assert_eq!(w[1].0.seq, w[0].0.seq + 1);
        assert_eq!(w[1].0.session, S);
        assert!(w[1].1.module_time_us > w[0].1.module_time_us);
    }

    // A stranger's command is dropped and counted; garbage is counted by kind.
    c.send(m1, 0xBAD, &Message::Command(Command::position(-0.3)));
    c.sock
        .send_to(b"XX not a datagram at all............", m1)
        .unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let counters = emu.stop();
    assert_eq!(counters.wrong_session, 1);
    assert_eq!(counters.bad_magic, 1);
    assert!(counters.commands > 40, "{}", counters.commands);
    assert!(counters.steps > 500);
}

#[test]
fn lockstep_advances_one_step_per_command_round() {
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("truth.csv");
    let config = ServerConfig {
        base_port: 0,
        mode: Mode::Lockstep,
        record: Some(record.clone()),
        // Long enough that no step in this test comes from the timeout.
        lockstep_timeout_s: 30.0,
        ..ServerConfig::default()
    };
    let emu = Running::start(config, exact_plant(2));
    let mut c = Client::new();
    let [a, b] = [emu.addrs[0], emu.addrs[1]];
    for m in [a, b] {
        c.acquire(m);
    }
    // Settings ack is followed by one feedback at the current time (t = 0).
    let s = Settings::default();
    for m in [a, b] {
        c.send(m, S, &Message::Settings(s));
    }
    let mut acks = 0;
    let mut initial = Vec::new();
    while acks < 2 || initial.len() < 2 {
        match c
            .recv(Duration::from_secs(2))
            .expect("ack and initial feedback")
        {
            (_, _, Message::SettingsAck(got)) => {
                assert_eq!(got, s);
                acks += 1;
            }
            (from, _, Message::Feedback(f)) => initial.push((from, f.module_time_us)),
            other => panic!("{other:?}"),
        }
    }
    assert!(initial.iter().all(|&(_, t)| t == 0), "{initial:?}");

    for round in 1..=5u64 {
        c.send(a, S, &Message::Command(Command::position(0.1)));
        if round == 3 {
            // Half a round: the world must not move.
            assert!(c.recv(Duration::from_millis(150)).is_none());
        }
        c.send(b, S, &Message::Command(Command::position(0.1)));
        let mut got = Vec::new();
        while got.len() < 2 {
            let (from, _, msg) = c
                .recv(Duration::from_secs(2))
                .expect("feedback after the round");
            let Message::Feedback(f) = msg else {
                panic!("{msg:?}")
            };
            got.push((from, f.module_time_us));
        }
        got.sort();
        let mut want = vec![(a, round * 1000), (b, round * 1000)];
        want.sort();
        assert_eq!(got, want, "round {round}");
    }
    // Nothing more: exactly one feedback per module per round.
    assert!(c.recv(Duration::from_millis(100)).is_none());
    let counters = emu.stop();
    assert_eq!(counters.steps, 5);
    assert_eq!(counters.lockstep_timeouts, 0);
    // The ground truth has one row per step with the applied set-points.
    let text = std::fs::read_to_string(&record).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows[0], "t_s,cmd_0,cmd_1,pos_0,pos_1,torque_0,torque_1");
    assert_eq!(rows.len(), 6);
    assert!(rows[5].starts_with("0.005000,0.1,0.1,"), "{}", rows[5]);
}

#[test]
fn lockstep_steps_on_timeout_without_a_controller() {
    let config = ServerConfig {
        base_port: 0,
        mode: Mode::Lockstep,
        lockstep_timeout_s: 0.02,
        ..ServerConfig::default()
    };
    let emu = Running::start(config, exact_plant(1));
    let mut c = Client::new();
    c.acquire(emu.addrs[0]);
    c.settings(emu.addrs[0], Settings::default());
    // Owned but never commanded: the world still creeps on, one step per timeout.
    let fb = c.feedback_from(emu.addrs[0], Duration::from_millis(300));
    assert!(fb.len() >= 2, "{}", fb.len());
    assert!(
        fb.windows(2)
            .all(|w| w[1].1.module_time_us == w[0].1.module_time_us + 1000)
    );
    let counters = emu.stop();
    assert!(counters.lockstep_timeouts >= 2);
    assert_eq!(counters.lockstep_timeouts, counters.steps);
}

#[test]
fn silenced_module_answers_nothing_and_loss_drops_feedback() {
    let config = ServerConfig {
        base_port: 0,
        mode: Mode::Realtime,
        faults: snaked::emu::faults::FaultConfig {
            silences: vec!["0@0".parse().unwrap()],
            loss_pct: 100.0,
            ..Default::default()
        },
        ..ServerConfig::default()
    };
    let emu = Running::start(config, exact_plant(2));
    let mut c = Client::new();
    c.send(emu.addrs[0], 0, &Message::Lookup(LookupFilter::All));
    assert!(
        c.recv(Duration::from_millis(200)).is_none(),
        "silent module answered"
    );
    // Module 1 answers (replies are never dropped) but all its feedback is lost.
    c.acquire(emu.addrs[1]);
    c.settings(emu.addrs[1], Settings::default());
    assert!(
        c.recv(Duration::from_millis(200)).is_none(),
        "feedback got through"
    );
    let counters = emu.stop();
    assert_eq!(counters.dropped_silent, 1);
    assert!(
        counters.dropped_feedback_loss > 50,
        "{}",
        counters.dropped_feedback_loss
    );
}

#[test]
fn delayed_feedback_still_arrives_complete_and_in_order() {
    let config = ServerConfig {
        base_port: 0,
        mode: Mode::Realtime,
        faults: snaked::emu::faults::FaultConfig {
            delay_s: 0.02,
            ..Default::default()
        },
        ..ServerConfig::default()
    };
    let emu = Running::start(config, exact_plant(1));
    let mut c = Client::new();
    c.acquire(emu.addrs[0]);
    c.settings(emu.addrs[0], Settings::default());
    let fb = c.feedback_from(emu.addrs[0], Duration::from_millis(300));
    assert!(fb.len() > 100, "{}", fb.len());
    assert!(fb.windows(2).all(|w| w[1].0.seq == w[0].0.seq + 1));
    let counters = emu.stop();
    assert_eq!(counters.dropped_delay_full, 0);
}
