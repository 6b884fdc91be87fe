//! Operating from Foxglove (`[foxglove] operate`), through `snaked --emulated` and a
//! WebSocket client speaking as Foxglove's panels do: services answer what the control
//! socket answers, twists drive (the Teleop panel) and the dead-man stops then holds,
//! parameters read and set (the Parameters panel), a token gates everything but
//! `auth`, `status` and `estop`, slow viewers are thinned and reported; every action is
//! an `/operator` event in the recording naming the client.
use crate::support::rig;

use std::net::SocketAddr;
use std::time::Duration;

use rig::{Client, Proc, exe};
use serde_json::{Value, json};

mod access;
mod config;
mod continuity;
mod drive;
mod drivers;
mod listener;
mod tune;
mod viewers;

fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

pub(super) struct Daemon {
    proc: Proc,
    pub(super) sock: Client,
    pub(super) fox: SocketAddr,
    dir: tempfile::TempDir,
}

/// `snaked --emulated` on flat ground, operating from Foxglove with `extra` config.
pub(super) fn daemon(extra: &str) -> Daemon {
    daemon_with(extra, |_| {})
}

/// As [`daemon`], its command prepared by `setup` before it starts (a lower file limit,
/// its log to a file).
pub(super) fn daemon_with(extra: &str, setup: impl FnOnce(&mut std::process::Command)) -> Daemon {
    daemon_in("flat.toml", extra, setup)
}

/// As [`daemon_with`], in `world` (a file of `scenarios/`).
pub(super) fn daemon_in(
    world: &str,
    extra: &str,
    setup: impl FnOnce(&mut std::process::Command),
) -> Daemon {
    let dir = tempfile::tempdir().unwrap();
    let port = free_tcp_port();
    let config = dir.path().join("snaked.toml");
    std::fs::write(
        &config,
        format!("[foxglove]\noperate = true\nport = {port}\n{extra}\n"),
    )
    .unwrap();
    let sock = dir.path().join("s.sock");
    let world = format!("{}/scenarios/{world}", env!("CARGO_MANIFEST_DIR"));
    let proc = Proc::spawn_with(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--world".into(),
            world,
            "--config".into(),
            config.display().to_string(),
            "--socket".into(),
            sock.display().to_string(),
            "--record".into(),
            dir.path().join("run.mcap").display().to_string(),
        ],
        setup,
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(Duration::from_secs(30), "running", |s| {
        s["mode"] == "running"
    });
    Daemon {
        proc,
        sock: c,
        fox: SocketAddr::from(([127, 0, 0, 1], port)),
        dir,
    }
}

impl Daemon {
    /// A connection of its own to the control socket (one operator, say `snakectl`):
    /// it drives only while it is connected.
    pub(super) fn once(&self) -> Client {
        Client::connect(&self.dir.path().join("s.sock"), Duration::from_secs(10))
    }

    /// SIGTERM, exit 0, and the `/operator` events of the recording.
    pub(super) fn stop(self) -> Vec<Value> {
        self.stop_with(&["/operator"]).remove(0)
    }

    /// SIGTERM, exit 0, and the recording's messages on each of `topics`.
    pub(super) fn stop_with(mut self, topics: &[&str]) -> Vec<Vec<Value>> {
        self.proc.signal(libc::SIGTERM);
        assert!(self.proc.wait(Duration::from_secs(30)).success(), "exit 0");
        let bytes = std::fs::read(self.dir.path().join("run.mcap")).expect("recording");
        let mut out = vec![Vec::new(); topics.len()];
        for m in mcap::MessageStream::new(&bytes).expect("MCAP") {
            let m = m.expect("a message");
            if let Some(k) = topics.iter().position(|t| *t == m.channel.topic) {
                out[k].push(serde_json::from_slice(&m.data).expect("JSON"));
            }
        }
        out
    }
}

pub(super) fn slithering_speed(c: &mut Client) -> f64 {
    let p = c.call("params.get", json!({"gait": "slithering"}));
    p["params"]["temporal_freq_rad_s"]
        .as_f64()
        .expect("a speed")
}
