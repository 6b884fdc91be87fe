//! The I/O path's cost per control cycle over loopback: `UdpBus::send` (a command to
//! every module) plus `UdpBus::receive` (drain the feedback that arrived), against
//! `snake-emu`'s server streaming at 1 kHz in its own thread, for each endpoint layout
//! (a module per endpoint, as real modules with their own ports; one gateway for all).
//! The loop is paced at 1 kHz like the daemon's, so each cycle finds one feedback per
//! module waiting. Layouts alternate in rounds within one run, and the table gives the
//! median over rounds of each round's p50 / p99 (µs).
//!
//! `cargo bench --bench udp_cycle [-- MODULES ROUNDS CYCLES]` (default 18 5 3000).
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use snaked::bus::udp::{UdpBus, discover};
use snaked::bus::{Bus, FeedbackWait, GroupFeedback};
use snaked::emu::plant::{JointSpacePlant, PlantConfig};
use snaked::emu::server::{Mode, Server, ServerConfig};
use snaked::protocol::{Command, LookupFilter, Settings};
use snaked::rt::sys;

struct Layout {
    name: &'static str,
    gateway: bool,
}

const LAYOUTS: [Layout; 2] = [
    Layout {
        name: "module per endpoint",
        gateway: false,
    },
    Layout {
        name: "gateway",
        gateway: true,
    },
];

/// One round: start an emulator, connect, run `cycles` paced cycles; per-cycle I/O
/// times in ns.
fn round(n: usize, gateway: bool, cycles: usize) -> Vec<u64> {
    let config = ServerConfig {
        base_port: 0,
        gateway,
        mode: Mode::Realtime,
        ..ServerConfig::default()
    };
    let plant = JointSpacePlant::new(PlantConfig::new(n)).expect("plant");
    let mut server = Server::new(config, Box::new(plant)).expect("emulator");
    let targets = server.local_addrs().expect("addresses");
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    let emu = std::thread::spawn(move || server.run(&flag).expect("emulator runs"));

    let bind = "127.0.0.1:0".parse().unwrap();
    let found = discover(
        &targets,
        &LookupFilter::All,
        Some(n),
        bind,
        Duration::from_secs(5),
    )
    .expect("discovery");
    let mut bus = UdpBus::connect(
        &found,
        Settings::default(),
        bind,
        0x00C0_FFEE,
        Duration::from_secs(5),
    )
    .expect("connect");
    let mut group = GroupFeedback::new(n);
    let commands = vec![Command::position(0.1); n];
    let mut times = Vec::with_capacity(cycles);
    let period_ns = 1_000_000;
    let mut deadline = sys::monotonic_ns();
    for k in 0..cycles + 500 {
        deadline += period_ns;
        sys::sleep_until_ns(deadline);
        let t0 = sys::monotonic_ns();
        bus.receive(&mut group, t0, FeedbackWait::None)
            .expect("receive");
        bus.send(&commands).expect("send");
        let dt = sys::monotonic_ns() - t0;
        if k >= 500 {
            times.push(dt); // past start-up
        }
    }
    assert!(bus.counters().feedback_received > (cycles * n / 2) as u64);
    bus.release();
    stop.store(true, Ordering::Relaxed);
    emu.join().expect("emulator thread");
    times
}

fn quantile(sorted: &[u64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize] as f64 * 1e-3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median cost of tagging (and of checking) one Command frame, ns.
fn tag_cost_ns() -> (f64, f64) {
    use snaked::protocol::{Key, Message, Route, encode, open};
    let key = Key::random();
    let mut buf = [0u8; 64];
    let msg = Message::Command(Command::position(0.1));
    let reps = 20_000u32;
    let mut enc = Vec::new();
    let mut dec = Vec::new();
    for _ in 0..7 {
        let t0 = sys::monotonic_ns();
        for seq in 0..reps {
            let r = Route {
                session: 1,
                seq: u64::from(seq),
                unit: 0,
            };
            std::hint::black_box(encode(r, &msg, &key, &mut buf).unwrap());
        }
        let t1 = sys::monotonic_ns();
        for _ in 0..reps {
            std::hint::black_box(open(&buf[..48], &key).unwrap());
        }
        let t2 = sys::monotonic_ns();
        enc.push((t1 - t0) as f64 / f64::from(reps));
        dec.push((t2 - t1) as f64 / f64::from(reps));
    }
    (median(enc), median(dec))
}

fn main() {
    // `cargo bench` passes `--bench`; the numbers are ours.
    let nums: Vec<usize> = std::env::args().filter_map(|a| a.parse().ok()).collect();
    let n = nums.first().copied().unwrap_or(18);
    let rounds = nums.get(1).copied().unwrap_or(5);
    let cycles = nums.get(2).copied().unwrap_or(3000);
    let mut p50 = vec![Vec::new(); LAYOUTS.len()];
    let mut p99 = vec![Vec::new(); LAYOUTS.len()];
    for r in 0..rounds {
        for (i, layout) in LAYOUTS.iter().enumerate() {
            let mut t = round(n, layout.gateway, cycles);
            t.sort_unstable();
            let (a, b) = (quantile(&t, 0.5), quantile(&t, 0.99));
            eprintln!(
                "round {}/{rounds} {:<20} p50 {a:6.1} µs  p99 {b:6.1} µs",
                r + 1,
                layout.name
            );
            p50[i].push(a);
            p99[i].push(b);
        }
    }
    println!("udp_cycle: {n} modules, {rounds} rounds × {cycles} cycles, receive + send per cycle");
    println!("| layout | p50 (µs) | p99 (µs) |");
    println!("| --- | ---: | ---: |");
    let mut medians = Vec::new();
    for (i, layout) in LAYOUTS.iter().enumerate() {
        let (a, b) = (median(p50[i].clone()), median(p99[i].clone()));
        medians.push(a);
        println!("| {} | {a:.1} | {b:.1} |", layout.name);
    }
    println!(
        "ratio of p50s (module per endpoint / gateway): {:.1}",
        medians[0] / medians[1]
    );
    let (enc, dec) = tag_cost_ns();
    println!("one Command frame: encode + tag {enc:.0} ns, check + decode {dec:.0} ns");
}
