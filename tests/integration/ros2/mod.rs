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

/// A daemon configuration in `dir` with the control socket there and `extra` added.
fn config(dir: &Path, extra: &str) -> std::path::PathBuf {
    let config = dir.join("snaked.toml");
    std::fs::write(
        &config,
        format!(
            "{extra}\n[control]\nsocket = {:?}\n",
            dir.join("snaked.sock").display().to_string()
        ),
    )
    .unwrap();
    config
}

fn status<'a>(r: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    &r["diagnostics"]["status"][format!("snaked: {name}")]
}

#[test]
fn rclpy_and_cyclone_dds_see_the_node_and_what_it_publishes() {
    let dir = tempfile::tempdir().unwrap();
    let config = config(
        dir.path(),
        "[ros2]\nenabled = true\nnode_name = \"snake\"\njoint_states_rate_hz = 200.0\n",
    );
    let r = run_peer("observe.py", &[&exe("snaked"), config.to_str().unwrap()]);
    let nodes = r["nodes"].as_array().unwrap();
    assert!(
        nodes.iter().any(|n| n[0] == "snake" && n[1] == "/"),
        "the node is in rclpy's graph: {r}"
    );
    assert_eq!(
        r["types"]["/joint_states"][0], "sensor_msgs/msg/JointState",
        "{r}"
    );
    assert_eq!(r["types"]["/odom"][0], "nav_msgs/msg/Odometry", "{r}");
    assert_eq!(r["types"]["/tf"][0], "tf2_msgs/msg/TFMessage", "{r}");
    assert_eq!(
        r["types"]["/imu/module_18/data_raw"][0], "sensor_msgs/msg/Imu",
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
    // The virtual chassis as odometry (REP-105 frames, a unit quaternion, covariances
    // unknown), and a module's IMU (REP-145: no orientation; gravity, m/s²).
    let odom = &r["odom"];
    assert_eq!(odom["frame_id"], "odom", "{r}");
    assert_eq!(odom["child_frame_id"], "base_link", "{r}");
    assert!(
        (odom["orientation_norm"].as_f64().unwrap() - 1.0).abs() < 1e-6,
        "{r}"
    );
    assert!(
        odom["covariance_diagonal"]
            .as_array()
            .unwrap()
            .iter()
            .all(|c| c == -1.0),
        "{r}"
    );
    assert!(odom["count"].as_u64().unwrap() >= 10, "{r}");
    let imu = &r["imu"];
    assert_eq!(imu["frame_id"], "module_1", "{r}");
    assert_eq!(imu["orientation_covariance_0"], -1.0, "{r}");
    let g: f64 = imu["accel"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_f64().unwrap().powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        (5.0..15.0).contains(&g),
        "gravity in the IMU: {g} m/s², {r}"
    );
    // Diagnostics at 1 Hz: the loop's timing, the failsafe running, the bus, the
    // recorder, the node, the external pose the test published (counted).
    let loop_ = status(&r, "loop");
    assert!(
        loop_["values"]["cycles"]
            .as_str()
            .unwrap()
            .parse::<u64>()
            .unwrap()
            > 100,
        "{r}"
    );
    assert!(loop_["values"]["period_error_p99_us"].is_string(), "{r}");
    assert_eq!(status(&r, "failsafe")["values"]["mode"], "running", "{r}");
    assert_eq!(status(&r, "failsafe")["level"], 0, "{r}");
    assert!(
        status(&r, "bus")["values"]["feedback_received"].is_string(),
        "{r}"
    );
    assert_eq!(status(&r, "recorder")["values"]["dropped"], "0", "{r}");
    assert!(
        status(&r, "ros2 node")["values"]["published"].is_string(),
        "{r}"
    );
    assert!(
        r["received_poses"].as_u64().unwrap_or(0) > 0,
        "the pose input: {r}"
    );
    // The node's state, latched: the gait it runs.
    assert_eq!(r["state"]["gait"], "sidewinding", "{r}");
    assert_eq!(r["state"]["mode"], "running", "{r}");
    // Cyclone DDS, a second DDS, reads the same joint states and the transforms
    // odom → base_link → body (the URDF's root), the head ahead of the chassis.
    let c = &r["cyclone"];
    assert!(c["joint_states"].as_u64().unwrap_or(0) > 10, "{r}");
    assert_eq!(c["names"], serde_json::json!(names), "{r}");
    assert_eq!(
        c["tf_pairs"],
        serde_json::json!([["base_link", "body"], ["odom", "base_link"]]),
        "{r}"
    );
    assert!(c["head_in_base_link"][0].as_f64().unwrap() > 0.1, "{r}");
    assert_eq!(r["daemon_exit"], 0, "{r}");
    assert_eq!(r["daemon_stopped_safely"], true, "{r}");
}

#[test]
fn rclpy_drives_and_tunes_the_robot_through_the_operator_api() {
    let dir = tempfile::tempdir().unwrap();
    let mcap = dir.path().join("run.mcap");
    let config = config(
        dir.path(),
        &format!(
            "[ros2]\nenabled = true\noperate = true\n[record]\npath = {:?}\n",
            mcap.display().to_string()
        ),
    );
    let r = run_peer("operate.py", &[&exe("snaked"), config.to_str().unwrap()]);
    assert!(r["state_after_s"].is_number(), "the latched state: {r}");
    // The parameters, named as Foxglove's Parameters panel names them, read live.
    let names = r["names"].as_array().expect("list_parameters answered");
    for n in ["gait", "params.temporal_freq_rad_s", "controller.name"] {
        assert!(names.iter().any(|x| x == n), "{n} listed: {r}");
    }
    assert_eq!(r["get"][0], "sidewinding", "{r}");
    assert!(r["get"][2].is_null(), "an unknown name is not set: {r}");
    let before = r["get"][1].as_f64().unwrap();
    assert_eq!(r["set"]["ok"], true, "{r}");
    let after = r["after_set"][0].as_f64().unwrap();
    assert!(
        (after - before * 0.75).abs() < 1e-6,
        "set and read back: {r}"
    );
    // Refusals come back as failed set results with the operator API's reason.
    for k in ["set_out_of_range", "set_bad_gait", "set_unknown"] {
        assert_eq!(r[k]["ok"], false, "{k}: {r}");
        assert!(!r[k]["reason"].as_str().unwrap().is_empty(), "{k}: {r}");
    }
    assert!(
        r["set_bad_gait"]["reason"]
            .as_str()
            .unwrap()
            .contains("swimming"),
        "{r}"
    );
    // Services: a gait, hold, arm, navigation off, e-stop.
    assert_eq!(r["gait_service"]["success"], true, "{r}");
    assert!(r["gait_after_s"].is_number(), "the gait switched: {r}");
    assert_eq!(r["hold"]["success"], true, "{r}");
    assert!(r["held_after_s"].is_number(), "{r}");
    assert_eq!(r["arm"]["success"], true, "{r}");
    assert!(r["armed_after_s"].is_number(), "{r}");
    // goal_pose: navigating to it by the poses on external_pose.
    assert!(r["goal_after_s"].is_number(), "steering by position: {r}");
    let (goal, sent) = (&r["goal_state"]["goal_m"], &r["goal_sent_m"]);
    for k in 0..2 {
        let (g, s) = (goal[k].as_f64().unwrap(), sent[k].as_f64().unwrap());
        assert!((g - s).abs() < 1e-9, "the goal as sent: {r}");
    }
    let d = r["goal_state"]["distance_m"].as_f64().unwrap();
    assert!((3.0..5.0).contains(&d), "about 4 m to go: {r}");
    assert_eq!(r["navigate_off"], true, "{r}");
    // /cmd_vel: linear.x 0.8 is 0.8 rad/s of temporal frequency (the station's mapping).
    assert!(
        (r["driven_speed"][0].as_f64().unwrap() - 0.8).abs() < 1e-6,
        "{r}"
    );
    assert_eq!(r["driven_motion"], "running", "{r}");
    // The dead-man: a controlled stop once the twists stop (0.5 s), then a hold 2 s later.
    assert!(r["stopped_after_s"].as_f64().expect("stopped") < 2.0, "{r}");
    let held = r["held_by_dead_man_after_s"].as_f64().expect("held");
    assert!(
        (2.0..6.0).contains(&held),
        "held {held} s after the last twist: {r}"
    );
    assert_eq!(r["estop"]["success"], true, "{r}");
    assert!(r["estopped_after_s"].is_number(), "{r}");
    // Loopback only in the namespace: no warning about discovery beyond it.
    assert_eq!(r["warned_beyond_localhost"], false, "{r}");
    assert_eq!(r["daemon_exit"], 0, "{r}");
    // Every request is recorded as an operator action of `ros2`.
    let bytes = std::fs::read(&mcap).expect("the recording");
    let mut actions = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("MCAP") {
        let m = m.expect("a message");
        if m.channel.topic == "/operator" {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            actions.push((v["client"].clone(), v["action"].clone(), v["ok"].clone()));
        }
    }
    let has = |client: &str, action: &str, ok: bool| {
        actions
            .iter()
            .any(|(c, a, o)| c == client && a == action && *o == ok)
    };
    assert!(has("ros2", "params.set", true), "{actions:?}");
    assert!(
        has("ros2", "params.set", false),
        "the refused speed: {actions:?}"
    );
    assert!(has("ros2", "gait.set", true), "{actions:?}");
    assert!(
        has("ros2", "hold", true) && has("ros2", "arm", true),
        "{actions:?}"
    );
    assert!(has("ros2", "estop", true), "{actions:?}");
    assert!(has("ros2", "gait.resume", true), "teleop: {actions:?}");
    assert!(has("dead-man (ros2)", "gait.stop", true), "{actions:?}");
}

/// The daemon's log when it runs `seconds` with `extra` configuration in a namespace
/// that has, besides loopback, a veth pair up (an interface DDS would discover on; its
/// packets stay in the namespace).
fn log_with_a_second_interface(extra: &str, seconds: u32) -> String {
    let dir = tempfile::tempdir().unwrap();
    let config = config(dir.path(), extra);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(root.join("scripts/in-netns.sh"))
        .args([
            "bash",
            "-c",
            "ip link add v0 type veth peer name v1 && ip addr add 10.9.9.9/24 dev v0 && \
             ip link set v0 up && ip link set v1 up && \
             exec timeout --preserve-status -s INT \"$1\" \"$2\" --emulated --config \"$3\"",
            "netns",
            &seconds.to_string(),
            &exe("snaked"),
            config.to_str().unwrap(),
        ])
        .output()
        .expect("running scripts/in-netns.sh");
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{log}");
    log
}

#[test]
fn operating_with_discovery_beyond_localhost_is_warned_at_start() {
    let log = log_with_a_second_interface("[ros2]\nenabled = true\noperate = true\n", 3);
    let warning = log
        .lines()
        .find(|l| l.contains("discovery reaches beyond localhost"))
        .unwrap_or_else(|| panic!("no warning: {log}"));
    assert!(
        warning.contains("WARN") && warning.contains("v0"),
        "{warning}"
    );
    assert!(log.contains("stopped safely"), "{log}");
    // Publishing only: nothing to warn about.
    let log = log_with_a_second_interface("[ros2]\nenabled = true\n", 2);
    assert!(!log.contains("beyond localhost"), "{log}");
}
