//! snaked as a ROS 2 node against rclpy (ROS 2 Jazzy on Fast DDS, pinned wheels from
//! PyPI: scripts/ros2-peers.sh), each test in a network namespace whose only interface
//! is loopback (scripts/in-netns.sh): no DDS packet leaves the machine. A missing peer
//! fails the test; it does not skip.

use std::path::Path;
use std::process::Command;

use crate::support::rig::exe;

/// Runs `script` (beside this file) with the peers' Python in a namespace of its own,
/// and returns the JSON line it printed last.
fn run_peer(script: &str, args: &[&str]) -> serde_json::Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = root.join("tests/integration/ros2").join(script);
    let out = Command::new(root.join("scripts/ros2-peers.sh"))
        .arg("run")
        .args(["bash", "-c", "exec \"$ROS2_PEERS_PYTHON\" \"$@\"", "peer"])
        .arg(&script)
        .args(args)
        .output()
        .expect("running scripts/ros2-peers.sh");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the ROS 2 peer failed ({}): {stdout}\n{stderr}",
        out.status
    );
    // Fast DDS may print to stdout too: the report is the last JSON line.
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| panic!("no report from the peer: {stdout}\n{stderr}"));
    serde_json::from_str(line).unwrap()
}

#[test]
fn rclpy_sees_the_node_its_joint_states_and_its_robot_description() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("snaked.toml");
    let socket = dir.path().join("snaked.sock");
    std::fs::write(
        &config,
        format!(
            "[ros2]\nenabled = true\nnode_name = \"snake\"\njoint_states_rate_hz = 200.0\n\
             [control]\nsocket = {:?}\n",
            socket.display().to_string()
        ),
    )
    .unwrap();
    let r = run_peer(
        "joint_states.py",
        &[&exe("snaked"), config.to_str().unwrap()],
    );
    let nodes = r["nodes"].as_array().unwrap();
    assert!(
        nodes.iter().any(|n| n[0] == "snake" && n[1] == "/"),
        "the node is in rclpy's graph: {r}"
    );
    assert_eq!(
        r["joint_states_type"][0], "sensor_msgs/msg/JointState",
        "{r}"
    );
    // Joint names as the URDF names its joints; every module's position, velocity, effort.
    let names: Vec<String> = (1..=18).map(|k| format!("module-{k:02}")).collect();
    assert_eq!(r["names"], serde_json::json!(names), "{r}");
    assert_eq!(r["positions"].as_array().unwrap().len(), 18);
    assert_eq!(r["velocities"], 18);
    assert_eq!(r["efforts"], 18);
    // The embedded emulator runs sidewinding: the joints are not all at zero, and within
    // the joints' range, rad.
    let pos: Vec<f64> = r["positions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(pos.iter().any(|p| p.abs() > 0.05), "{pos:?}");
    assert!(pos.iter().all(|p| p.abs() < 1.6), "{pos:?}");
    // Stamped with the wall clock.
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs() as i64;
    assert!((r["stamp_sec"].as_i64().unwrap() - now).abs() < 120, "{r}");
    // At the configured rate (200 Hz), within what best-effort gives on a loaded machine.
    let rate = r["rate_hz"].as_f64().unwrap();
    assert!((50.0..=220.0).contains(&rate), "{rate} Hz");
    // The URDF, latched: a listener that came later still got it, with the same joints.
    let urdf = r["description"].as_str().unwrap();
    assert!(
        urdf.contains("<joint name=\"module-01\"") && urdf.contains("<joint name=\"module-18\""),
        "{urdf}"
    );
    assert_eq!(r["daemon_exit"], 0, "{r}");
    assert_eq!(r["daemon_stopped_safely"], true, "{r}");
}
