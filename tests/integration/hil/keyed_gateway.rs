//! Hardware-in-loop over protocol v2's other layout and a keyed network: `snake-emu
//! --gateway --network-key-file K` serves every module on one endpoint, and the daemon
//! with `network.key_file = K` discovers, acquires and drives them all through it.
use crate::support::rig;

use std::os::unix::fs::PermissionsExt;
use std::time::Duration;

use rig::Rig;

const N: usize = 8;

#[test]
fn the_daemon_drives_a_keyed_gateway() {
    let keys = tempfile::tempdir().unwrap();
    let key_path = keys.path().join("network.key");
    std::fs::write(
        &key_path,
        format!("{}\n", snaked::protocol::Key::random().to_hex()),
    )
    .unwrap();
    std::fs::set_permissions(&key_path, std::fs::Permissions::from_mode(0o600)).unwrap();
    let key = key_path.display().to_string();
    let mut rig = Rig::start(
        N,
        &["--gateway", "--network-key-file", &key],
        &format!("key_file = \"{key}\""),
        "[gait]\ninitial = \"rolling\"\nstart = \"run\"",
    );
    let s = rig
        .client
        .wait_status(Duration::from_secs(30), "running", |s| {
            s["mode"] == "running"
        });
    // Past the 2 s blend into the gait.
    std::thread::sleep(Duration::from_millis(4000));
    let stats = rig.client.call("stats", serde_json::json!({}));
    let bus = &stats["bus"];
    assert_eq!(bus["detail"]["bad_tag"], 0, "{stats}");
    assert_eq!(bus["detail"]["wrong_session"], 0, "{stats}");
    assert_eq!(bus["dropped"], 0, "{stats}");
    assert!(bus["feedback_received"].as_u64().unwrap() > 2000, "{stats}");
    let rec = rig.stop(N);
    // Every module behind the one endpoint followed its rolling set-points.
    let late = rec.span(2.5, f64::INFINITY);
    for i in 0..N {
        let swing = rec.pos[i][late.clone()]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        assert!(swing.1 - swing.0 > 0.1, "module {i} moved {swing:?} ({s})");
    }
}
