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
    AcquireReply, Announce, Command, Feedback, LookupFilter, MAX_DATAGRAM, Message, Name, Settings,
    decode, encode,
};

#[path = "support/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations;

/// A lockstep module: grants, acknowledges, and answers every command with one
/// feedback 1 ms later, plus some junk the bus must count and drop.
fn spawn_module(name: &str, stop: Arc<AtomicBool>) -> (FoundModule, std::thread::JoinHandle<()>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(5)))
        .unwrap();
    let announce = Announce {
        mac: [2, 0, 0, 0, 0, name.len() as u8],
        family: Name::new("SEA").unwrap(),
        name: Name::new(name).unwrap(),
        firmware: 1,
        owner_session: 0,
    };
    let found = FoundModule {
        addr: socket.local_addr().unwrap(),
        announce,
    };
    let handle = std::thread::spawn(move || {
        let (mut buf, mut tx) = ([0u8; MAX_DATAGRAM], [0u8; MAX_DATAGRAM]);
        let (mut fb_seq, mut time_us) = (0u32, 0u64);
        let send = |tx: &mut [u8], session, seq, m: &Message, to| {
            let n = encode(session, seq, m, tx).unwrap();
            socket.send_to(&tx[..n], to).unwrap();
        };
        while !stop.load(Ordering::Relaxed) {
            let Ok((n, src)) = socket.recv_from(&mut buf) else {
                continue;
            };
            let Ok((h, msg)) = decode(&buf[..n]) else {
                continue;
            };
            let fb = |time_us| {
                Message::Feedback(Feedback {
                    module_time_us: time_us,
                    ..Feedback::default()
                })
            };
            match msg {
                Message::Acquire => {
                    let r = AcquireReply {
                        granted: true,
                        owner_session: h.session,
                    };
                    send(&mut tx, h.session, h.seq, &Message::AcquireReply(r), src);
                }
                Message::Settings(s) => {
                    send(&mut tx, h.session, h.seq, &Message::SettingsAck(s), src);
                    fb_seq += 1;
                    send(&mut tx, h.session, fb_seq, &fb(time_us), src);
                }
                Message::Command(_) => {
                    // Junk first: a corrupted datagram, a lookup, a wrong session.
                    let names = LookupFilter::Names(vec![Name::new("x").unwrap(); 3]);
                    send(&mut tx, 0, 0, &Message::Lookup(names), src);
                    send(&mut tx, h.session ^ 1, fb_seq, &fb(time_us), src);
                    let n = encode(h.session, fb_seq, &fb(time_us), &mut tx).unwrap();
                    tx[n - 1] ^= 0xff;
                    socket.send_to(&tx[..n], src).unwrap();
                    time_us += 1000;
                    fb_seq += 2; // one "lost" every cycle
                    send(&mut tx, h.session, fb_seq, &fb(time_us), src);
                }
                _ => {}
            }
        }
    });
    (found, handle)
}

#[test]
fn send_and_receive_do_not_allocate() {
    let stop = Arc::new(AtomicBool::new(false));
    let (found, handles): (Vec<_>, Vec<_>) = ["a", "bb", "ccc"]
        .iter()
        .map(|n| spawn_module(n, stop.clone()))
        .unzip();
    let mut bus = UdpBus::connect(
        &found,
        Settings::default(),
        "127.0.0.1:0".parse().unwrap(),
        7,
        Duration::from_secs(3),
    )
    .unwrap();
    let mut group = GroupFeedback::new(3);
    let commands = [Command::position(0.1); 3];
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
    // The junk really went through the counted-and-dropped paths.
    assert!(
        c.bad_checksum >= 30 && c.unexpected >= 30 && c.wrong_session >= 30,
        "{c:?}"
    );
    assert!(c.feedback_lost >= 30);
    assert_eq!(group.modules[2].feedback.module_time_us, 40_000);
    bus.release();
    stop.store(true, Ordering::Relaxed);
    handles.into_iter().for_each(|h| h.join().unwrap());
}
