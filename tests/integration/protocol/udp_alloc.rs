//! Proof that the bus's real-time path (`send`, `receive`, including the lockstep
//! wait and the handling of bad datagrams) allocates nothing: a counting global
//! allocator that counts only on the thread under test.
use std::net::UdpSocket;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use snaked::bus::udp::{FoundModule, UdpBus};
use snaked::bus::{Bus, FeedbackWait, GroupFeedback};
use snaked::protocol::{
    AcquireReply, Announce, Command, Feedback, Frames, Key, LookupFilter, MAX_DATAGRAM, Message,
    Name, Route, Settings, encode, open,
};

use crate::support::counting_alloc;
use counting_alloc::allocations;

/// One endpoint serving `names` as units 0.., in lockstep: grants, acknowledges, and
/// answers every command with one feedback 1 ms later, plus some junk the bus must
/// count and drop. Open network; the module nonce is fixed.
fn spawn_endpoint(
    names: &[&str],
    stop: Arc<AtomicBool>,
) -> (Vec<FoundModule>, std::thread::JoinHandle<()>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(5)))
        .unwrap();
    let found: Vec<FoundModule> = names
        .iter()
        .enumerate()
        .map(|(unit, name)| FoundModule {
            addr: socket.local_addr().unwrap(),
            unit: unit as u16,
            announce: Announce {
                mac: [2, 0, 0, 0, unit as u8, name.len() as u8],
                family: Name::new("SEA").unwrap(),
                name: Name::new(name).unwrap(),
                firmware: 1,
                owned: false,
            },
        })
        .collect();
    let macs: Vec<_> = found.iter().map(|f| f.announce.mac).collect();
    let handle = std::thread::spawn(move || {
        let (mut buf, mut tx) = ([0u8; MAX_DATAGRAM], [0u8; MAX_DATAGRAM]);
        let mut keys = vec![Key::OPEN; macs.len()];
        let (mut fb_seq, mut time_us) = (vec![0u64; macs.len()], vec![0u64; macs.len()]);
        let send = |tx: &mut [u8], session, seq, unit, m: &Message, key: &Key, to| {
            let n = encode(Route { session, seq, unit }, m, key, tx).unwrap();
            socket.send_to(&tx[..n], to).unwrap();
        };
        while !stop.load(Ordering::Relaxed) {
            let Ok((n, src)) = socket.recv_from(&mut buf) else {
                continue;
            };
            for frame in Frames::new(&buf[..n]) {
                let Ok((h, frame)) = frame else { break };
                let u = usize::from(h.unit);
                let key = if h.msg_type.uses_network_key() {
                    Key::OPEN
                } else {
                    keys[u]
                };
                let Ok(msg) = open(frame, &key) else { continue };
                let fb = |time_us| {
                    Message::Feedback(Feedback {
                        module_time_us: time_us,
                        ..Feedback::default()
                    })
                };
                let unit = h.unit;
                match msg {
                    Message::Acquire(host) => {
                        let nonce = [7; 16];
                        keys[u] = Key::OPEN.session_key(h.session, &macs[u], &host, &nonce);
                        let r = AcquireReply {
                            granted: true,
                            module_nonce: nonce,
                        };
                        let m = Message::AcquireReply(r);
                        send(&mut tx, h.session, h.seq, unit, &m, &Key::OPEN, src);
                    }
                    Message::Settings(s) => {
                        let m = Message::SettingsAck(s);
                        send(&mut tx, h.session, h.seq, unit, &m, &keys[u], src);
                        fb_seq[u] += 1;
                        let f = fb(time_us[u]);
                        send(&mut tx, h.session, fb_seq[u], unit, &f, &keys[u], src);
                    }
                    Message::Command(_) => {
                        // Junk first: a corrupted frame, a lookup, a wrong session,
                        // a forged frame under the open key.
                        let names = LookupFilter::Names(vec![Name::new("x").unwrap(); 3]);
                        let lookup = Message::Lookup(names);
                        send(&mut tx, 0, 0, 0, &lookup, &Key::OPEN, src);
                        let f = fb(time_us[u]);
                        send(&mut tx, h.session ^ 1, fb_seq[u], unit, &f, &keys[u], src);
                        send(&mut tx, h.session, u64::MAX, unit, &f, &Key::OPEN, src);
                        let r = Route {
                            session: h.session,
                            seq: fb_seq[u],
                            unit,
                        };
                        let n = encode(r, &f, &keys[u], &mut tx).unwrap();
                        tx[n - 1] ^= 0xff;
                        socket.send_to(&tx[..n], src).unwrap();
                        time_us[u] += 1000;
                        fb_seq[u] += 2; // one "lost" every cycle
                        let f = fb(time_us[u]);
                        send(&mut tx, h.session, fb_seq[u], unit, &f, &keys[u], src);
                    }
                    _ => {}
                }
            }
        }
    });
    (found, handle)
}

/// 40 lockstep cycles with the counting allocator on, over `endpoints` (each a list
/// of unit names).
fn run_without_allocating(endpoints: &[&[&str]]) {
    let stop = Arc::new(AtomicBool::new(false));
    let (found, handles): (Vec<_>, Vec<_>) = endpoints
        .iter()
        .map(|names| spawn_endpoint(names, stop.clone()))
        .unzip();
    let found: Vec<FoundModule> = found.into_iter().flatten().collect();
    let n = found.len();
    let mut bus = UdpBus::connect(
        &found,
        Settings::default(),
        "127.0.0.1:0".parse().unwrap(),
        7,
        Duration::from_secs(3),
    )
    .unwrap();
    let mut group = GroupFeedback::new(n);
    let commands = vec![Command::position(0.1); n];
    let wait = |k: u64| FeedbackWait::Lockstep {
        min_module_time_us: k * 1000,
        timeout_ns: 3_000_000_000,
    };
    // Warm-up cycle outside the count (first use of lazily initialised std state).
    bus.send(&commands).unwrap();
    bus.receive(&mut group, 0, wait(1)).unwrap();

    let before = allocations();
    for k in 2..=40u64 {
        bus.send(&commands).unwrap();
        bus.receive(&mut group, k, wait(k)).unwrap();
        bus.receive(&mut group, k, FeedbackWait::None).unwrap();
    }
    let allocated = allocations() - before;

    assert_eq!(allocated, 0, "the real-time path allocated");
    let c = bus.counters();
    // The junk really went through the counted-and-dropped paths (the bus's own
    // detail, by name, in the counters every bus reports).
    let detail = |name| c.detail.get(name).expect("the UDP bus counts it");
    assert!(
        detail("bad_tag") >= 60 && detail("unexpected") >= 30 && detail("wrong_session") >= 30,
        "{c:?}"
    );
    assert!(c.dropped >= 120, "{c:?}");
    assert!(c.feedback_lost >= 30);
    assert_eq!(group.modules[n - 1].feedback.module_time_us, 40_000);
    bus.release();
    stop.store(true, Ordering::Relaxed);
    handles.into_iter().for_each(|h| h.join().unwrap());
}

#[test]
fn send_and_receive_do_not_allocate() {
    run_without_allocating(&[&["a"], &["bb"], &["ccc"]]);
}

#[test]
fn bundled_send_and_receive_do_not_allocate() {
    run_without_allocating(&[&["a", "bb", "ccc"]]);
}
