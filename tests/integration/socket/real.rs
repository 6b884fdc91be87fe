//! The real loop behind the real server, for the socket tests that need the loop's own
//! behaviour (controllers, the navigator): over the echo bus with scripted torques.
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;
use snaked::bus::echo::EchoBus;
use snaked::gait::{GaitKind, GaitTable};
use snaked::rt::harness::{PERIOD_NS, echo_harness_on};
use snaked::safety::failsafe::FailsafeConfig;
use snaked::socket::client::Client;

use crate::support::socket::{RealLoop, serve_real_loop};

/// Torques against the bend at every fourth joint (pegs, as the compliant controllers
/// feel them).
fn pegs(i: usize, position_rad: f32) -> f32 {
    if i.is_multiple_of(4) && position_rad.abs() > 0.05 {
        2.0 * position_rad.signum()
    } else {
        0.0
    }
}

/// The real loop over an echo bus (torques against the bend at every other lateral
/// joint), stepped about ten times faster than real time on its own thread.
pub fn real_loop() -> RealLoop {
    let mut table = GaitTable::default();
    table.get_mut(GaitKind::Slithering).temporal_freq_rad_s = 3.0;
    let bus = EchoBus::new(18, PERIOD_NS).with_torque(pegs);
    let h = echo_harness_on(
        bus,
        table,
        GaitKind::Slithering,
        false,
        FailsafeConfig::default(),
    );
    serve_real_loop(h, |control| {
        for _ in 0..10 {
            control.step();
        }
        std::thread::sleep(Duration::from_millis(1));
    })
}

/// `status` once `ok` holds for it (or the last one after 30 s).
pub fn status_when(c: &mut Client, ok: impl Fn(&Value) -> bool) -> Value {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let s = c.call("status", None).unwrap();
        if ok(&s) || Instant::now() > deadline {
            return s;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

pub fn snakectl(l: &RealLoop, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_snakectl"))
        .arg("--socket")
        .arg(&l.path)
        .args(args)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?}: {text}{err}");
    text
}
