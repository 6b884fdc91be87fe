use super::*;
use crate::protocol::MsgType;

const S: u32 = 0xABCD;
const OTHER: u32 = 0x1234;

fn addr(port: u16) -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], port))
}

fn module() -> Module {
    let family = Name::new("SEA").unwrap();
    Module::new(
        ModuleIdentity::emulated(2, 18, family, EMULATOR_FIRMWARE),
        ModuleConfig::default(),
    )
}

const NONCE: Nonce = [5; 16];

fn hdr(msg: &Message, session: u32, seq: u64) -> Header {
    Header {
        msg_type: msg.msg_type(),
        session,
        seq,
        unit: 0,
    }
}

fn send(
    m: &mut Module,
    t: f64,
    from: u16,
    session: u32,
    seq: u64,
    msg: Message,
) -> Option<Outgoing> {
    m.handle(
        ModuleTime::both(t),
        addr(from),
        &hdr(&msg, session, seq),
        &msg,
    )
}

fn acquired(t: f64) -> Module {
    let mut m = module();
    let r = send(&mut m, t, 9000, S, 1, Message::Acquire(NONCE)).unwrap();
    assert!(matches!(
        r.message,
        Message::AcquireReply(AcquireReply { granted: true, .. })
    ));
    m
}

fn settings(rate: f32, lifetime: f32) -> Settings {
    Settings {
        feedback_rate_hz: rate,
        command_lifetime_s: lifetime,
        strategy: ControlStrategy::Cascaded,
    }
}

#[test]
fn emulated_identity() {
    let m = module();
    let id = m.identity();
    assert_eq!(id.mac, [0x02, 0x53, 0x4E, 0x00, 0x00, 0x03]);
    assert_eq!(id.name.as_str(), "module-03");
    assert_eq!(id.family.as_str(), "SEA");
    let big = ModuleIdentity::emulated(4, 120, id.family, 1);
    assert_eq!(big.name.as_str(), "module-005");
    assert_eq!(big.mac[4..], [0, 5]);
}

#[test]
fn lookup_filters() {
    let mut m = module();
    let id = *m.identity();
    let yes = [
        LookupFilter::All,
        LookupFilter::Family(Name::new("SEA").unwrap()),
        LookupFilter::Names(vec![Name::new("x").unwrap(), id.name]),
        LookupFilter::Macs(vec![id.mac]),
    ];
    for f in yes {
        let r = send(&mut m, 0.0, 5555, NO_SESSION, 9, Message::Lookup(f.clone()));
        let r = r.unwrap_or_else(|| panic!("{f:?} did not answer"));
        assert_eq!(r.dest, addr(5555));
        assert_eq!(r.seq, 9);
        let Message::Announce(a) = r.message else {
            panic!()
        };
        assert_eq!(a.name, id.name);
        assert!(!a.owned);
    }
    let no = [
        LookupFilter::Family(Name::new("X5").unwrap()),
        LookupFilter::Names(vec![Name::new("module-04").unwrap()]),
        LookupFilter::Macs(vec![[0; 6]]),
    ];
    for f in no {
        assert!(send(&mut m, 0.0, 5555, NO_SESSION, 9, Message::Lookup(f)).is_none());
    }
}

#[test]
fn announce_reports_owner() {
    let mut m = acquired(0.0);
    let r = send(
        &mut m,
        0.1,
        5555,
        NO_SESSION,
        1,
        Message::Lookup(LookupFilter::All),
    )
    .unwrap();
    let Message::Announce(a) = r.message else {
        panic!()
    };
    assert!(a.owned);
}

#[test]
fn acquire_rules() {
    let mut m = acquired(0.0);
    assert_eq!(m.owner_session(), S);
    let granted = |r: &Outgoing| match r.message {
        Message::AcquireReply(a) => a.granted.then_some(a.module_nonce),
        _ => panic!("not an acquire reply: {r:?}"),
    };
    // The owner's own Acquire again (a resend): the same answer, nothing changes,
    // not even where feedback goes.
    let first = granted(&send(&mut m, 0.4, 9000, S, 2, Message::Acquire(NONCE)).unwrap());
    let again = send(&mut m, 0.5, 9005, S, 3, Message::Acquire(NONCE)).unwrap();
    assert_eq!(again.dest, addr(9005));
    assert_eq!(granted(&again), first);
    // The same session with another nonce is someone else: denied, and told nothing.
    let r = send(&mut m, 0.5, 9006, S, 4, Message::Acquire([6; 16])).unwrap();
    assert_eq!(granted(&r), None);
    assert_eq!(
        r.message,
        Message::AcquireReply(AcquireReply {
            granted: false,
            module_nonce: [0; 16]
        })
    );
    // Another session while the owner is alive: denied.
    let r = send(&mut m, 0.9, 9001, OTHER, 1, Message::Acquire(NONCE)).unwrap();
    assert_eq!(r.session, OTHER);
    assert_eq!(granted(&r), None);
    assert_eq!(m.counters().acquire_denied, 2);
    // Owner silent for more than 1 s (last heard at 0.0: Acquires do not count): taken
    // over, with a fresh nonce.
    let r = send(&mut m, 1.1, 9001, OTHER, 2, Message::Acquire(NONCE)).unwrap();
    assert_ne!(granted(&r), first);
    assert!(granted(&r).is_some());
    assert_eq!(m.owner_session(), OTHER);
    // Session 0 can never own a module.
    assert!(send(&mut m, 1.7, 9002, NO_SESSION, 1, Message::Acquire(NONCE)).is_none());
    assert_eq!(m.counters().wrong_session, 1);
}

#[test]
fn session_frames_need_the_session_key_and_a_newer_seq() {
    let mut m = acquired(0.0);
    let h = |session, msg: &Message| hdr(msg, session, 1);
    let cmd = Message::Command(Command::position(0.2));
    // Handshake frames: the network key; the owner's frames: its session key; any
    // other session: no key at all (so nothing it sends can be checked or accepted).
    assert_eq!(
        m.key_for(&h(OTHER, &Message::Acquire(NONCE))),
        Some(Key::OPEN)
    );
    let key = m.key_for(&h(S, &cmd)).expect("the owner's key");
    assert_ne!(key, Key::OPEN);
    assert_eq!(m.key_for(&h(OTHER, &cmd)), None);
    assert_eq!(m.key_for(&h(OTHER, &Message::Release)), None);
    // Replays: a seq not newer than the newest accepted is dropped.
    send(&mut m, 0.1, 9000, S, 10, cmd.clone());
    send(&mut m, 0.2, 9000, S, 10, cmd.clone());
    send(&mut m, 0.3, 9000, S, 9, Message::Release);
    assert_eq!(m.counters().replayed, 2);
    assert_eq!(m.counters().commands, 1);
    assert!(m.is_owned());
}

#[test]
fn commands_keep_the_session_alive() {
    let mut m = acquired(0.0);
    for i in 1..=30 {
        send(
            &mut m,
            f64::from(i) * 0.1,
            9000,
            S,
            i as u64,
            Message::Command(Command::position(0.1)),
        );
    }
    let r = send(&mut m, 3.05, 9001, OTHER, 1, Message::Acquire(NONCE)).unwrap();
    assert!(matches!(
        r.message,
        Message::AcquireReply(AcquireReply { granted: false, .. })
    ));
}

#[test]
fn release_timeout_uses_the_wall_clock() {
    let mut m = acquired(0.0);
    let late_wall = ModuleTime {
        sim_s: 0.001,
        wall_s: 2.0,
    };
    let msg = Message::Acquire(NONCE);
    let r = m
        .handle(late_wall, addr(9001), &hdr(&msg, OTHER, 1), &msg)
        .unwrap();
    assert!(matches!(
        r.message,
        Message::AcquireReply(AcquireReply { granted: true, .. })
    ));
}

#[test]
fn no_feedback_before_the_first_settings_ack() {
    let mut m = acquired(0.0);
    assert!(!m.is_streaming());
    assert!(!m.feedback_due(0.5));
    assert!(m.make_feedback(0.5, Feedback::default()).is_none());
    // Even a refused settings request starts the stream (the ack says what is in force).
    send(
        &mut m,
        0.5,
        9000,
        S,
        2,
        Message::Settings(settings(0.0, 0.2)),
    );
    assert!(m.is_streaming());
    assert!(m.feedback_requested());
}

#[test]
fn feedback_goes_to_the_acquirer() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(Settings::default()),
    );
    assert!(m.feedback_due(0.0));
    let fb = m.make_feedback(0.0, Feedback::default()).unwrap();
    assert_eq!(fb.dest, addr(9000));
    assert_eq!(fb.session, S);
    assert_eq!(fb.seq, 1);
}

#[test]
fn release_frees_stops_streaming_and_goes_limp() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        1,
        Message::Settings(Settings::default()),
    );
    assert!(m.feedback_due(0.0));
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Command(Command::position(0.3)),
    );
    assert!(!m.applied_command(0.001).is_limp());
    // A stranger cannot release it.
    assert!(send(&mut m, 0.001, 9001, OTHER, 1, Message::Release).is_none());
    assert_eq!(m.counters().wrong_session, 1);
    assert!(m.is_owned());
    assert!(send(&mut m, 0.002, 9000, S, 3, Message::Release).is_none());
    assert!(!m.is_owned());
    assert!(m.applied_command(0.003).is_limp());
    assert!(!m.feedback_due(0.01));
    assert!(m.make_feedback(0.01, Feedback::default()).is_none());
}

#[test]
fn settings_validated_and_acknowledged() {
    let mut m = acquired(0.0);
    let good = settings(500.0, 0.2);
    let r = send(&mut m, 0.0, 9000, S, 5, Message::Settings(good)).unwrap();
    assert_eq!(r.message, Message::SettingsAck(good));
    assert_eq!((r.session, r.seq), (S, 5));
    for (bad, seq) in [
        settings(0.5, 0.2),
        settings(2001.0, 0.2),
        settings(100.0, 0.0005),
        settings(100.0, 10.5),
        settings(f32::NAN, 0.2),
    ]
    .into_iter()
    .zip(6..)
    {
        let r = send(&mut m, 0.0, 9000, S, seq, Message::Settings(bad)).unwrap();
        assert_eq!(r.message, Message::SettingsAck(good), "{bad:?} accepted");
    }
    assert_eq!(m.counters().settings_refused, 5);
    for (edge, seq) in [settings(1.0, 0.001), settings(2000.0, 10.0)]
        .into_iter()
        .zip(20..)
    {
        let r = send(&mut m, 0.0, 9000, S, seq, Message::Settings(edge)).unwrap();
        assert_eq!(r.message, Message::SettingsAck(edge));
    }
    // Wrong session: dropped, counted, nothing changes.
    assert!(send(&mut m, 0.0, 9001, OTHER, 1, Message::Settings(good)).is_none());
    assert_eq!(m.counters().wrong_session, 1);
    assert_eq!(m.settings(), settings(2000.0, 10.0));
}

#[test]
fn settings_ack_is_followed_by_one_feedback_at_once() {
    let mut m = acquired(0.0);
    // Not streaming before the first settings.
    assert!(!m.feedback_due(0.0));
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(settings(10.0, 0.5)),
    );
    assert!(m.feedback_due(0.0));
    m.make_feedback(0.0, Feedback::default()).unwrap();
    assert!(!m.feedback_due(0.05));
    assert!(m.feedback_due(0.1));
}

#[test]
fn command_is_applied_with_its_seq_until_its_lifetime_ends() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(settings(1000.0, 0.05)),
    );
    assert!(m.applied_command(0.0).is_limp(), "no command yet");
    let c = Command::position(0.25);
    send(&mut m, 1.0, 9000, S, 77, Message::Command(c));
    assert_eq!(m.applied_command(1.0).position_rad, 0.25);
    assert_eq!(m.applied_command(1.049).position_rad, 0.25);
    assert!(m.applied_command(1.0501).is_limp());
    let fb = m.make_feedback(1.0, Feedback::default()).unwrap();
    let Message::Feedback(f) = fb.message else {
        panic!()
    };
    assert_eq!(f.last_command_seq, 77);
    // A fresh command drives again.
    send(&mut m, 2.0, 9000, S, 78, Message::Command(c));
    assert_eq!(m.applied_command(2.01).position_rad, 0.25);
}

#[test]
fn strategy_off_is_limp() {
    let mut m = acquired(0.0);
    let off = Settings {
        strategy: ControlStrategy::Off,
        ..settings(100.0, 1.0)
    };
    send(&mut m, 0.0, 9000, S, 2, Message::Settings(off));
    send(
        &mut m,
        0.0,
        9000,
        S,
        3,
        Message::Command(Command::position(0.2)),
    );
    assert!(m.applied_command(0.01).is_limp());
}

#[test]
fn wrong_session_command_is_counted_and_ignored() {
    let mut m = acquired(0.0);
    assert!(
        send(
            &mut m,
            0.0,
            9000,
            OTHER,
            2,
            Message::Command(Command::position(0.2))
        )
        .is_none()
    );
    assert_eq!(m.counters().wrong_session, 1);
    assert!(m.applied_command(0.0).is_limp());
    assert!(!m.has_fresh_command());
    // Free module: every command is wrong-session.
    let mut free = module();
    send(
        &mut free,
        0.0,
        9000,
        S,
        1,
        Message::Command(Command::position(0.2)),
    );
    assert_eq!(free.counters().wrong_session, 1);
}

#[test]
fn fresh_command_flag_for_lockstep() {
    let mut m = acquired(0.0);
    assert!(!m.has_fresh_command());
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Command(Command::position(0.2)),
    );
    assert!(m.has_fresh_command());
    m.clear_fresh_command();
    assert!(!m.has_fresh_command());
}

#[test]
fn feedback_at_the_configured_rate_with_consecutive_seq() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(settings(100.0, 0.5)),
    );
    let mut seqs = Vec::new();
    for tick in 0..=1000 {
        let t = f64::from(tick) * 1e-3;
        if m.feedback_due(t) {
            seqs.push(m.make_feedback(t, Feedback::default()).unwrap().seq);
        }
    }
    // One at the settings ack plus one per 10 ms over the second.
    assert!((100..=102).contains(&seqs.len()), "{}", seqs.len());
    assert!(seqs.windows(2).all(|w| w[1] == w[0] + 1), "{seqs:?}");
}

#[test]
fn default_rate_is_one_per_ms_tick() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(Settings::default()),
    );
    let sent = (0..100)
        .filter(|&tick| {
            let t = f64::from(tick) * 1e-3;
            m.feedback_due(t) && m.make_feedback(t, Feedback::default()).is_some()
        })
        .count();
    assert_eq!(sent, 100);
}

#[test]
fn messages_a_module_never_takes_are_unexpected() {
    let mut m = acquired(0.0);
    let msgs = [
        Message::Feedback(Feedback::default()),
        Message::SettingsAck(Settings::default()),
        Message::AcquireReply(AcquireReply {
            granted: true,
            module_nonce: NONCE,
        }),
    ];
    for msg in msgs {
        assert!(send(&mut m, 0.0, 9000, S, 1, msg).is_none());
    }
    assert_eq!(m.counters().unexpected, 3);
    assert_eq!(hdr(&Message::Release, S, 0).msg_type, MsgType::Release);
}

#[test]
fn new_owner_starts_with_default_settings() {
    let mut m = acquired(0.0);
    send(
        &mut m,
        0.0,
        9000,
        S,
        2,
        Message::Settings(settings(10.0, 2.0)),
    );
    send(
        &mut m,
        0.0,
        9000,
        S,
        3,
        Message::Command(Command::position(0.3)),
    );
    send(&mut m, 5.0, 9001, OTHER, 1, Message::Acquire(NONCE));
    assert_eq!(m.settings(), Settings::default());
    assert!(m.applied_command(5.0).is_limp());
}
