//! Loopback tests of discovery and the bus against fake modules (see `fake.rs`).
//! Success paths return as soon as the answers are in; only failure paths wait out
//! their (short) timeouts. No timing is asserted.
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use super::discovery::natural_cmp;
use super::fake::{FakeModule, feedback_datagram};
use super::*;
use crate::bus::GroupFeedback;
use crate::protocol::{ControlStrategy, Key, LookupFilter, Name};

/// Generous bound for things that succeed early.
const LONG: Duration = Duration::from_secs(3);
/// For things that must time out.
const SHORT: Duration = Duration::from_millis(250);

fn lo() -> SocketAddr {
    "127.0.0.1:0".parse().unwrap()
}

fn fakes(names: &[&str]) -> Vec<FakeModule> {
    (0..names.len())
        .map(|i| FakeModule::spawn(names[i], "SEA", i as u8 + 1))
        .collect()
}

fn found(f: &[FakeModule]) -> Vec<FoundModule> {
    f.iter().map(FakeModule::found).collect()
}

fn connect(f: &[FakeModule], session: u32) -> UdpBus {
    UdpBus::connect(&found(f), Settings::default(), lo(), session, LONG).unwrap()
}

fn names(group: &[FoundModule]) -> Vec<String> {
    group.iter().map(|m| m.announce.name.to_string()).collect()
}

fn name_list(list: &[&str]) -> LookupFilter {
    LookupFilter::Names(list.iter().map(|n| Name::new(n).unwrap()).collect())
}

/// Poll `cond` until it holds (true) or a generous deadline passes (false).
fn eventually(mut cond: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + LONG;
    while Instant::now() < deadline {
        if cond() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    false
}

fn lockstep(min_module_time_us: u64, timeout: Duration) -> FeedbackWait {
    FeedbackWait::Lockstep {
        min_module_time_us,
        timeout_ns: timeout.as_nanos() as u64,
    }
}

// ---- discovery ------------------------------------------------------------------

#[test]
fn discover_by_family_orders_by_name() {
    let mut f = fakes(&["m10", "m2", "m1"]);
    f.push(FakeModule::spawn("x", "Other", 9));
    let targets: Vec<SocketAddr> = f.iter().map(|m| m.addr).collect();
    let sea = LookupFilter::Family(Name::new("SEA").unwrap());
    let group = discover(&targets, &sea, Some(3), lo(), LONG).unwrap();
    assert_eq!(names(&group), ["m1", "m2", "m10"]);
    assert_eq!(group[0].addr, f[2].addr);
    // Without an expected count it waits the timeout and finds the same.
    let group = discover(&targets, &sea, None, lo(), SHORT).unwrap();
    assert_eq!(names(&group), ["m1", "m2", "m10"]);
}

#[test]
fn discover_by_names_and_macs_keeps_list_order() {
    let f = fakes(&["a", "b", "c"]);
    let targets: Vec<SocketAddr> = f.iter().map(|m| m.addr).collect();
    let group = discover(&targets, &name_list(&["c", "a", "b"]), None, lo(), LONG).unwrap();
    assert_eq!(names(&group), ["c", "a", "b"]);
    assert_eq!(group[0].addr, f[2].addr);
    let macs = LookupFilter::Macs(vec![f[1].announce.mac, f[2].announce.mac]);
    let group = discover(&targets, &macs, None, lo(), LONG).unwrap();
    assert_eq!(names(&group), ["b", "c"]);
}

#[test]
fn discover_names_what_is_missing() {
    let f = fakes(&["a", "b"]);
    let targets: Vec<SocketAddr> = f.iter().map(|m| m.addr).collect();
    let err = discover(
        &targets,
        &name_list(&["a", "ghost", "b"]),
        None,
        lo(),
        SHORT,
    )
    .unwrap_err();
    match &err {
        DiscoveryError::Missing { missing, .. } => assert_eq!(missing, &["ghost"]),
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("ghost"));
    let macs = LookupFilter::Macs(vec![f[0].announce.mac, [9; 6]]);
    let err = discover(&targets, &macs, None, lo(), SHORT).unwrap_err();
    assert!(err.to_string().contains("09:09:09:09:09:09"), "{err}");
}

#[test]
fn discover_deduplicates_and_checks_the_count() {
    let f = fakes(&["a", "b"]);
    // The same module reached twice answers twice: one entry.
    let group = discover(
        &[f[0].addr, f[0].addr],
        &LookupFilter::All,
        None,
        lo(),
        SHORT,
    )
    .unwrap();
    assert_eq!(names(&group), ["a"]);
    let targets = [f[0].addr, f[1].addr];
    let err = discover(&targets, &LookupFilter::All, Some(3), lo(), SHORT).unwrap_err();
    assert!(
        matches!(&err, DiscoveryError::CountMismatch { expected: 3, found, .. } if found.len() == 2),
        "{err:?}"
    );
    let dup = name_list(&["a", "a"]);
    assert!(matches!(
        discover(&targets, &dup, None, lo(), SHORT),
        Err(DiscoveryError::DuplicateInFilter(_))
    ));
    assert!(matches!(
        discover(&[], &LookupFilter::All, None, lo(), SHORT),
        Err(DiscoveryError::NoTargets)
    ));
}

#[test]
fn announce_says_owned_but_not_by_whom() {
    let f = fakes(&["a"]);
    let group = discover(&[f[0].addr], &LookupFilter::All, Some(1), lo(), LONG).unwrap();
    assert!(!group[0].announce.owned);
    let _bus = connect(&f, 42);
    let group = discover(&[f[0].addr], &LookupFilter::All, Some(1), lo(), LONG).unwrap();
    assert!(group[0].announce.owned);
}

#[test]
fn names_sort_naturally() {
    use std::cmp::Ordering::*;
    assert_eq!(natural_cmp("m2", "m10"), Less);
    assert_eq!(natural_cmp("m10", "m9"), Greater);
    assert_eq!(natural_cmp("head", "m1"), Less);
    assert_eq!(natural_cmp("m02", "m2"), Less);
    assert_eq!(natural_cmp("m2a", "m2b"), Less);
    assert_eq!(natural_cmp("m", "m1"), Less);
    assert_eq!(natural_cmp("m1", "m1"), Equal);
}

// ---- connect --------------------------------------------------------------------

#[test]
fn connect_acquires_sets_and_releases_on_drop() {
    let f = fakes(&["a", "b"]);
    let settings = Settings {
        feedback_rate_hz: 500.0,
        command_lifetime_s: 0.1,
        strategy: ControlStrategy::Cascaded,
    };
    let bus = UdpBus::connect(&found(&f), settings, lo(), 7, LONG).unwrap();
    assert_eq!(names(bus.modules()), ["a", "b"]);
    for m in &f {
        let st = m.state();
        assert_eq!(
            (st.owner, st.owner_addr),
            (7, Some(bus.local_addr().unwrap()))
        );
        assert_eq!(st.settings, Some(settings));
    }
    drop(bus);
    assert!(eventually(|| f.iter().all(|m| m.state().owner == 0)));
}

#[test]
fn connect_retries_lost_settings() {
    let f = fakes(&["a", "b"]);
    f[1].state().drop_settings = 2;
    let bus = connect(&f, 7);
    assert_eq!(f[1].state().settings, Some(Settings::default()));
    drop(bus);
}

#[test]
fn acquire_refused_names_the_owner_and_releases_the_rest() {
    let f = fakes(&["a", "b"]);
    let _first = connect(&f[1..], 1);
    let err = UdpBus::connect(&found(&f), Settings::default(), lo(), 2, SHORT).unwrap_err();
    match &err {
        ConnectError::Acquire { failed, total: 2 } => {
            assert_eq!(failed.len(), 1);
            assert_eq!(failed[0].name, "b");
            assert_eq!(failed[0].reason, FailReason::Owned);
        }
        other => panic!("{other:?}"),
    }
    // Who owns it is never disclosed.
    assert!(!err.to_string().contains("0x00000001"), "{err}");
    assert!(err.to_string().contains("another session"), "{err}");
    // `a` was granted to session 2, then handed back.
    assert!(eventually(|| f[0].state().owner == 0));
    assert_eq!(f[1].state().owner, 1);
}

#[test]
fn connect_names_silent_and_refusing_modules() {
    let f = fakes(&["a", "b", "c"]);
    f[1].state().silent = true;
    let err = UdpBus::connect(&found(&f), Settings::default(), lo(), 3, SHORT).unwrap_err();
    assert!(
        matches!(&err, ConnectError::Acquire { failed, .. }
            if failed.len() == 1 && failed[0].reason == FailReason::NoAnswer),
        "{err:?}"
    );
    assert!(err.to_string().contains("b at"), "{err}");
    f[1].state().silent = false;
    f[2].state().refuse_settings = true;
    let err = UdpBus::connect(&found(&f), Settings::default(), lo(), 3, SHORT).unwrap_err();
    assert!(
        matches!(&err, ConnectError::Settings { failed, .. }
            if failed.len() == 1 && matches!(failed[0].reason, FailReason::KeptSettings(_))),
        "{err:?}"
    );
    assert!(eventually(|| f.iter().all(|m| m.state().owner == 0)));
}

#[test]
fn connect_rejects_bad_arguments() {
    let f = fakes(&["a"]);
    let s = Settings::default();
    let c = |found: &[FoundModule], s, session| UdpBus::connect(found, s, lo(), session, SHORT);
    assert!(matches!(c(&[], s, 1), Err(ConnectError::NoModules)));
    assert!(matches!(c(&found(&f), s, 0), Err(ConnectError::NoSession)));
    let twice = [f[0].found(), f[0].found()];
    assert!(matches!(
        c(&twice, s, 1),
        Err(ConnectError::DuplicateAddress(..))
    ));
    for bad in [0.0, 2001.0, f32::NAN] {
        let s = Settings {
            feedback_rate_hz: bad,
            ..s
        };
        assert!(matches!(
            c(&found(&f), s, 1),
            Err(ConnectError::InvalidSettings(_))
        ));
    }
    let s = Settings {
        command_lifetime_s: 0.0,
        ..s
    };
    assert!(matches!(
        c(&found(&f), s, 1),
        Err(ConnectError::InvalidSettings(_))
    ));
}

// ---- send / receive -------------------------------------------------------------

#[test]
fn commands_reach_modules_with_the_cycle_seq() {
    let f = fakes(&["a", "b"]);
    let mut bus = connect(&f, 7);
    for _ in 0..2 {
        bus.send(&[Command::position(0.5), Command::LIMP]).unwrap();
    }
    assert!(eventually(|| f
        .iter()
        .all(|m| m.state().commands.len() == 2)));
    // One seq per cycle, the same for every module, after the handshake's requests.
    let seqs: Vec<u64> = f[0].state().commands.iter().map(|c| c.0).collect();
    assert_eq!(seqs[1], seqs[0] + 1);
    assert_eq!(seqs[1], bus.command_seq());
    let other: Vec<u64> = f[1].state().commands.iter().map(|c| c.0).collect();
    assert_eq!(seqs, other);
    assert_eq!(f[0].state().commands[1].1.position_rad, 0.5);
    assert!(f[1].state().commands[1].1.is_limp());
    assert_eq!(bus.udp_counters().commands_sent, 4);
    assert!(matches!(
        bus.send(&[Command::LIMP]),
        Err(BusError::WrongCount {
            expected: 2,
            got: 1
        })
    ));
    // An infinite set-point is never put on the wire; the other module still gets its.
    let inf = Command {
        torque_nm: f32::INFINITY,
        ..Command::LIMP
    };
    bus.send(&[inf, Command::LIMP]).unwrap();
    assert!(eventually(|| f[1].state().commands.len() == 3));
    assert_eq!(f[0].state().commands.len(), 2);
    assert_eq!(bus.udp_counters().send_errors, 1);
    assert_eq!(bus.command_seq(), seqs[1] + 1);
}

#[test]
fn feedback_keeps_the_newest_and_counts_lost() {
    let f = fakes(&["a", "b"]);
    let mut bus = connect(&f, 7);
    let mut group = GroupFeedback::new(2);
    // Each module's own thread sent seq 1 (time 0) after its SettingsAck; wait for both
    // before the test thread sends more, or a late seq 1 would arrive after seq 2.
    bus.receive(&mut group, 10, lockstep(0, LONG)).unwrap();
    f[0].send_feedback(7, 2, 1000);
    f[0].send_feedback(7, 5, 2000); // 3 and 4 lost
    f[1].send_feedback(7, 2, 2000);
    bus.receive(&mut group, 11, lockstep(2000, LONG)).unwrap();
    for m in &group.modules {
        assert!(m.fresh);
        assert_eq!(m.received_ns, Some(11));
        assert_eq!(m.feedback.module_time_us, 2000);
        assert_eq!(m.feedback.position_rad, 0.25);
    }
    let c = bus.udp_counters();
    assert_eq!((c.feedback_received, c.feedback_lost), (5, 2));

    // Late and duplicate datagrams are dropped, not counted as lost.
    f[0].send_feedback(7, 4, 1500);
    f[0].send_feedback(7, 5, 2000);
    f[1].send_feedback(7, 3, 3000);
    assert!(eventually(|| {
        bus.receive(&mut group, 12, FeedbackWait::None).unwrap();
        group.modules[1].feedback.module_time_us == 3000
    }));
    assert!(!group.modules[0].fresh);
    assert_eq!(group.modules[0].feedback.module_time_us, 2000);
    let c = bus.udp_counters();
    assert_eq!((c.feedback_received, c.feedback_lost), (6, 2));
    assert_eq!(c.feedback_replayed, 2);
}

#[test]
fn forged_far_ahead_feedback_never_hides_genuine_feedback() {
    let f = fakes(&["a"]);
    let mut bus = connect(&f, 7);
    let mut group = GroupFeedback::new(1);
    bus.receive(&mut group, 0, lockstep(0, LONG)).unwrap();
    // From the module's own address, with the session in the clear and a seq a
    // billion ahead, but tagged under a key the forger guessed (the open key).
    f[0].send_raw(&feedback_datagram(7, 1_000_000_000, 9_000_000, &Key::OPEN));
    f[0].send_raw(&feedback_datagram(
        7,
        1_000_000_001,
        9_000_000,
        &Key::random(),
    ));
    for (seq, t) in [(2, 1000), (3, 2000)] {
        f[0].send_feedback(7, seq, t);
    }
    bus.receive(&mut group, 1, lockstep(2000, LONG)).unwrap();
    let c = bus.udp_counters();
    assert_eq!((c.bad_tag, c.feedback_replayed, c.feedback_lost), (2, 0, 0));
    assert_eq!(group.modules[0].feedback.module_time_us, 2000);
}

/// A frame with a valid tag under `key` around any header fields and payload.
fn framed(version: u8, msg_type: u8, session: u32, payload: &[u8], key: &Key) -> Vec<u8> {
    let mut d = b"SN".to_vec();
    d.extend_from_slice(&[version, msg_type]);
    d.extend_from_slice(&session.to_le_bytes());
    d.extend_from_slice(&1u64.to_le_bytes());
    d.extend_from_slice(&0u16.to_le_bytes());
    d.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    d.extend_from_slice(payload);
    let tag = key.tag(&d);
    d.extend_from_slice(&tag);
    d
}

#[test]
fn bad_datagrams_are_counted_and_dropped() {
    let f = fakes(&["a"]);
    let mut bus = connect(&f, 7);
    let key = f[0].state().key.unwrap();
    let good = feedback_datagram(7, 9, 1000, &key);
    let mut bad_magic = good.clone();
    bad_magic[0] = b'X';
    let mut bad_tag = good.clone();
    *bad_tag.last_mut().unwrap() ^= 1;
    let mut v1 = good.clone();
    v1[2] = 1;
    let mut too_long = good.clone();
    too_long.push(0);
    let mut strategy_7 = [0u8; 12];
    strategy_7[8] = 7;
    // The module's own thread sent seq 1 (time 0) after its SettingsAck: take it first,
    // or under load it can arrive after the good datagram below and count as stale.
    let mut group = GroupFeedback::new(1);
    bus.receive(&mut group, 0, lockstep(0, LONG)).unwrap();
    for d in [
        good[..10].to_vec(),
        bad_magic,
        framed(3, 9, 7, &[], &key),
        v1,
        framed(2, 42, 7, &[], &key),
        framed(2, 9, 7, &[0; 12], &key), // feedback of the wrong size
        vec![b'S'; MAX_DATAGRAM + 1],
        bad_tag,
        framed(2, 7, 7, &strategy_7, &key),
        framed(2, 1, 0, &[0, 0, 0, 0], &Key::OPEN), // a Lookup: never for the bus
        framed(
            2,
            4,
            7,
            &[1, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
            &Key::OPEN,
        ), // a late AcquireReply
        good,
    ] {
        f[0].send_raw(&d);
    }
    bus.receive(&mut group, 1, lockstep(1000, LONG)).unwrap();
    assert!(group.modules[0].fresh);
    let c = bus.udp_counters();
    let got = [
        c.bad_truncated,
        c.bad_magic,
        c.bad_version,
        c.v1_refused,
        c.bad_type,
        c.bad_length,
        c.bad_tag,
        c.bad_malformed,
        c.unexpected,
    ];
    assert_eq!(got, [1, 1, 1, 1, 1, 2, 1, 1, 2]);
    assert_eq!(
        (c.feedback_received, c.feedback_lost, c.wrong_session),
        (2, 7, 0)
    );
}

#[test]
fn wrong_session_and_strangers_are_counted() {
    let f = fakes(&["a"]);
    let mut bus = connect(&f, 7);
    f[0].send_feedback(8, 2, 500);
    // Even a stranger holding the session key is not the module.
    let key = f[0].state().key.unwrap();
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    stranger
        .send_to(
            &feedback_datagram(7, 2, 600, &key),
            bus.local_addr().unwrap(),
        )
        .unwrap();
    f[0].send_feedback(7, 2, 1000);
    let mut group = GroupFeedback::new(1);
    bus.receive(&mut group, 1, lockstep(1000, LONG)).unwrap();
    let c = bus.udp_counters();
    assert_eq!((c.wrong_session, c.unexpected, c.feedback_lost), (1, 1, 0));
    assert_eq!(group.modules[0].feedback.module_time_us, 1000);
}

#[test]
fn lockstep_returns_once_every_module_reported() {
    let f = fakes(&["a", "b", "c"]);
    f.iter().for_each(|m| m.state().lockstep = true);
    let mut bus = connect(&f, 7);
    let mut group = GroupFeedback::new(3);
    for k in 1..=5u64 {
        bus.send(&[Command::position(0.0); 3]).unwrap();
        bus.receive(&mut group, k, lockstep(k * 1000, LONG))
            .unwrap();
        for m in &group.modules {
            assert!(m.fresh);
            assert_eq!(m.feedback.module_time_us, k * 1000);
            assert_eq!(m.feedback.last_command_seq, bus.command_seq());
        }
    }
    assert_eq!(bus.udp_counters().feedback_lost, 0);
}

#[test]
fn lockstep_times_out_when_a_module_is_silent() {
    let f = fakes(&["a", "b"]);
    f[0].state().lockstep = true;
    let mut bus = connect(&f, 7);
    let mut group = GroupFeedback::new(2);
    bus.send(&[Command::LIMP; 2]).unwrap();
    let r = bus.receive(&mut group, 1, lockstep(1000, Duration::from_millis(100)));
    assert!(matches!(r, Err(BusError::LockstepTimeout)), "{r:?}");
    // What did arrive is still handed over.
    assert!(eventually(|| {
        let _ = bus.receive(&mut group, 2, FeedbackWait::None);
        group.modules[0].feedback.module_time_us == 1000
    }));
    assert_eq!(group.modules[1].feedback.module_time_us, 0);
    assert!(matches!(
        bus.receive(&mut GroupFeedback::new(3), 3, FeedbackWait::None),
        Err(BusError::WrongCount {
            expected: 2,
            got: 3
        })
    ));
}

#[test]
fn discovery_names_peers_that_speak_protocol_v1() {
    // An old module: answers every lookup with a v1 Announce-shaped datagram.
    let old = UdpSocket::bind("127.0.0.1:0").unwrap();
    old.set_read_timeout(Some(Duration::from_millis(5)))
        .unwrap();
    let addr = old.local_addr().unwrap();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = stop.clone();
    let t = std::thread::spawn(move || {
        let mut buf = [0u8; 2048];
        while !flag.load(std::sync::atomic::Ordering::Relaxed) {
            if let Ok((_, from)) = old.recv_from(&mut buf) {
                let mut v1 = b"SN\x01\x02\0\0\0\0\x01\0\0\0\0\0\0\0".to_vec();
                v1.extend_from_slice(&[0; 4]);
                old.send_to(&v1, from).unwrap();
            }
        }
    });
    let err = discover(&[addr], &LookupFilter::All, Some(1), lo(), SHORT).unwrap_err();
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    t.join().unwrap();
    let DiscoveryError::OldProtocol { from, count } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(from, &[addr]);
    assert!(*count >= 1);
    assert!(err.to_string().contains("protocol v1"), "{err}");
}
