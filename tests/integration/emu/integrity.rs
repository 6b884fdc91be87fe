//! Protocol v2's integrity against the UDP emulator, as a hostile local user or a
//! stray host would try it (docs/protocol.md §8): nobody but the owner can release,
//! configure or drive a module, even knowing the session id; a replayed capture does
//! nothing; v1 is refused and counted; a keyed network ignores whoever lacks the key.
//! And the gateway layout: one endpoint, every unit, frames bundled.
use std::time::Duration;

use snaked::emu::plant::{NoiseConfig, PlantConfig};
use snaked::emu::server::{Mode, ServerConfig};
use snaked::protocol::{Command, Key, LookupFilter, Message, Settings};

use crate::support::emu_client;
use emu_client::{Client, Running, S};

fn plant(n: usize) -> PlantConfig {
    PlantConfig {
        noise: NoiseConfig::NONE,
        ..PlantConfig::new(n)
    }
}

fn realtime() -> ServerConfig {
    ServerConfig {
        base_port: 0,
        mode: Mode::Realtime,
        ..ServerConfig::default()
    }
}

#[test]
fn only_the_owner_drives_a_module_and_replays_do_nothing() {
    let emu = Running::start(realtime(), plant(1));
    let m = emu.addrs[0];
    let mut owner = Client::new();
    owner.acquire(m);
    owner.settings(m, Settings::default());
    let cmd = owner.frame(m, 0, S, &Message::Command(Command::position(0.4)));
    owner.sock.send_to(&cmd, m).unwrap();

    // The stranger knows the session id (more than a lookup tells: it says only
    // "owned") and guesses keys; it also replays the owner's command bytes.
    let mut stranger = Client::new();
    stranger.send(m, 0, &Message::Lookup(LookupFilter::All));
    let Some((_, _, Message::Announce(a))) = stranger.reply() else {
        panic!("no announce")
    };
    assert!(a.owned);
    stranger.send(m, S, &Message::Release);
    stranger.send(m, S, &Message::Settings(Settings::default()));
    stranger.send(m, S, &Message::Command(Command::position(1.0)));
    stranger.sock.send_to(&cmd, m).unwrap();
    stranger.sock.send_to(&cmd, m).unwrap();
    // Its own Acquire is refused, with nothing in the reply to build a key from.
    stranger.send(m, 0x0BAD, &Message::Acquire([9; 16]));
    let Some((_, _, Message::AcquireReply(r))) = stranger.reply() else {
        panic!("no acquire reply")
    };
    assert!(!r.granted);
    assert_eq!(r.module_nonce, [0; 16]);

    // The owner still streams, and the joint goes where the owner said.
    let mut last = None;
    for _ in 0..30 {
        owner.send(m, S, &Message::Command(Command::position(0.4)));
        last = owner.feedback_from(m, Duration::from_millis(10)).pop();
    }
    let (_, f) = last.expect("the owner's feedback kept coming");
    assert!((f.position_rad - 0.4).abs() < 0.05, "{}", f.position_rad);
    // And none of it went to the stranger.
    assert!(stranger.recv(Duration::from_millis(50)).is_none());
    let c = emu.stop();
    assert_eq!(
        c.bad_tag, 3,
        "release, settings, command under a guessed key"
    );
    assert_eq!(c.replayed, 2, "the replayed command, twice");
    assert_eq!(c.wrong_session, 0);
}

#[test]
fn v1_datagrams_are_refused_and_counted() {
    let emu = Running::start(realtime(), plant(1));
    let mut c = Client::new();
    // A v1 Lookup (16-byte header, CRC-32 trailer) as an old daemon sends it.
    let mut v1 = b"SN\x01\x01\0\0\0\0\x01\0\0\0\x04\0\0\0\0\0\0\0".to_vec();
    let crc = crc32fast::hash(&v1);
    v1.extend_from_slice(&crc.to_le_bytes());
    for _ in 0..3 {
        c.sock.send_to(&v1, emu.addrs[0]).unwrap();
    }
    assert!(c.recv(Duration::from_millis(150)).is_none());
    let counters = emu.stop();
    assert_eq!((counters.v1_refused, counters.bad_version), (3, 0));
}

#[test]
fn a_keyed_network_ignores_whoever_lacks_the_key() {
    let key = Key::random();
    let mut config = realtime();
    config.module.network_key = key;
    let emu = Running::start(config, plant(1));
    let m = emu.addrs[0];
    let mut outsider = Client::new();
    outsider.send(m, 0, &Message::Lookup(LookupFilter::All));
    outsider.send(m, S, &Message::Acquire([1; 16]));
    assert!(outsider.recv(Duration::from_millis(150)).is_none());
    let mut insider = Client::keyed(key);
    insider.acquire(m);
    insider.settings(m, Settings::default());
    assert!(
        !insider
            .feedback_from(m, Duration::from_millis(50))
            .is_empty()
    );
    assert_eq!(emu.stop().bad_tag, 2);
}

#[test]
fn a_gateway_serves_every_unit_with_bundled_frames() {
    let config = ServerConfig {
        gateway: true,
        ..realtime()
    };
    let emu = Running::start(config, plant(5));
    assert_eq!(emu.addrs.len(), 1);
    let gw = emu.addrs[0];
    let mut c = Client::new();
    for unit in 0..5 {
        c.acquire_unit(gw, unit);
    }
    // One Lookup brought all five announces (in one datagram: they fit).
    let mut settings = Vec::new();
    for unit in 0..5 {
        settings.extend(c.frame(gw, unit, S, &Message::Settings(Settings::default())));
    }
    c.sock.send_to(&settings, gw).unwrap();
    let mut units_seen = std::collections::BTreeSet::new();
    for _ in 0..40 {
        let mut bundle = Vec::new();
        for unit in 0..5 {
            let cmd = Command::position(0.1 * f64::from(unit));
            bundle.extend(c.frame(gw, unit, S, &Message::Command(cmd)));
        }
        c.sock.send_to(&bundle, gw).unwrap();
        // 5 ms of the stream (it never pauses: 1 kHz).
        let until = std::time::Instant::now() + Duration::from_millis(5);
        while let Some((_, h, m)) = c.recv(Duration::from_millis(5)) {
            if let Message::Feedback(_) = m {
                units_seen.insert(h.unit);
            }
            if std::time::Instant::now() > until {
                break;
            }
        }
    }
    assert_eq!(units_seen.into_iter().collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
    // The 5 units' feedback of one tick travels in one datagram.
    assert!(
        c.frames >= 4 * c.datagrams,
        "{} frames in {} datagrams",
        c.frames,
        c.datagrams
    );
    let counters = emu.stop();
    assert_eq!(counters.commands, 200);
}
