//! `snaked --emulated --world ... --record FILE` as an operator runs it: a few seconds
//! of the physics world at 1 kHz, a gait and a controller change, SIGTERM, and the file
//! finished properly: read back by the `mcap` crate and, where it is installed, by
//! Python's `mcap` package (an independent reader).
use crate::support::rig;

use std::collections::BTreeMap;
use std::process::Command;
use std::time::Duration;

use rig::{Client, Proc, exe};
use serde_json::{Value, json};

/// Every key of `v` in `schema`: a property, or one of a map's `additionalProperties`;
/// arrays by their `items`. Structure only, not types: what a viewer's path completion
/// and the layout test rely on.
fn conforms(schema: &Value, v: &Value, at: &str) -> Result<(), String> {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let sub = schema
                    .get("properties")
                    .and_then(|p| p.get(k))
                    .or_else(|| schema.get("additionalProperties").filter(|a| a.is_object()));
                match sub {
                    Some(sub) => conforms(sub, x, &format!("{at}.{k}"))?,
                    // An object the schema leaves open (a controller's own config).
                    None if schema.get("properties").is_none() => {}
                    None => return Err(format!("{at}.{k} is not in the schema")),
                }
            }
            Ok(())
        }
        Value::Array(xs) => match schema.get("items") {
            Some(items) => xs
                .iter()
                .try_for_each(|x| conforms(items, x, &format!("{at}[]"))),
            None => Ok(()),
        },
        _ => Ok(()),
    }
}

/// Per-topic message counts and the JSON messages of `topics`.
fn read(path: &std::path::Path, topics: &[&str]) -> (BTreeMap<String, u64>, Vec<(String, Value)>) {
    let bytes = std::fs::read(path).expect("the recording exists");
    let mut counts = BTreeMap::new();
    let mut kept = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let m = m.expect("a well-formed message");
        *counts.entry(m.channel.topic.clone()).or_insert(0) += 1;
        if topics.contains(&m.channel.topic.as_str()) {
            let v: Value = serde_json::from_slice(&m.data).expect("JSON");
            kept.push((m.channel.topic.clone(), v));
        }
    }
    (counts, kept)
}

#[test]
fn the_daemon_records_a_run_and_finishes_the_file_on_sigterm() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let file = dir.path().join("run.mcap");
    let world = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat.toml");
    let mut d = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--emulated".into(),
            "--world".into(),
            world.into(),
            "--socket".into(),
            sock.display().to_string(),
            "--record".into(),
            file.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    c.wait_status(Duration::from_secs(30), "engaged", |s| {
        s["controller"]["state"] == "engaged"
    });
    c.call("gait.set", json!({"gait": "slithering"}));
    c.call(
        "controller.set",
        json!({"gait": "slithering", "controller": "a_ws_omega"}),
    );
    c.wait_status(
        Duration::from_secs(60),
        "compliant slithering drives",
        |s| s["controller"]["preset"] == "a_ws_omega" && s["controller"]["state"] == "engaged",
    );
    let stats = c.call("stats", json!({}));
    let dropped_live = stats["record_dropped"].as_u64().expect("reported in stats");
    d.signal(libc::SIGTERM);
    assert!(d.wait(Duration::from_secs(30)).success(), "exit 0");

    let (counts, msgs) = read(
        &file,
        &[
            "/joints",
            "/events",
            "/controller/signals",
            "/body/estimate",
            "/stats",
            "/commands",
            "/imu",
            "/navigation",
            "/controller/windows",
            "/controller/info",
        ],
    );
    let cycles: Vec<u64> = msgs
        .iter()
        .filter(|(t, _)| t == "/joints")
        .map(|(_, v)| v["cycle"].as_u64().expect("cycle"))
        .collect();
    assert!(cycles.len() > 2000, "{counts:?}");
    for topic in ["/commands", "/imu", "/body/estimate", "/controller/signals"] {
        assert_eq!(counts[topic], cycles.len() as u64, "{topic}: {counts:?}");
    }
    // Cycles come in order; a gap is a skipped period (an overrun of this debug build
    // on a shared machine) or a record the full ring dropped, and `stats` counts both.
    assert!(cycles.windows(2).all(|w| w[1] > w[0]), "in order");
    let gaps: u64 = cycles.windows(2).map(|w| w[1] - w[0] - 1).sum();
    println!(
        "{} cycles recorded, {gaps} missing (dropped by the ring before the stop: {dropped_live})",
        cycles.len()
    );
    // The world and the body in 3-D, the ground truth as frames.
    assert_eq!(counts["/scene/world"], 1, "{counts:?}");
    assert!(
        counts["/tf"] > 50 && counts["/scene/body"] > 50,
        "{counts:?}"
    );
    assert!(counts["/stats"] >= 2, "once a second: {counts:?}");
    // Every message as its channel's schema says.
    for (topic, v) in &msgs {
        let schema = snaked::record::Topic::ALL
            .iter()
            .find(|t| t.name() == topic)
            .and_then(|t| t.json_schema())
            .expect("a JSON topic");
        conforms(&schema, v, topic).unwrap_or_else(|e| panic!("{e}: {v}"));
    }
    // The loop's timing as `stats` gives it: the wake-up latency (one per cycle) and the
    // period error (one fewer).
    let (_, last_stats) = msgs.iter().rfind(|(t, _)| t == "/stats").unwrap();
    let woke = last_stats["wakeup_latency"]["count"].as_u64().unwrap();
    let periods = last_stats["period_error"]["count"].as_u64().unwrap();
    assert!(woke > 1000 && periods + 1 == woke, "{last_stats}");
    assert!(counts["/controller/windows"] > 0, "the compliant windows");
    assert!(
        counts["/controller/info"] >= 2,
        "open loop, then a_ws_omega"
    );
    // Events: the mode changes, both requests, the takeovers.
    let events: Vec<&Value> = msgs
        .iter()
        .filter(|(t, _)| t == "/events")
        .map(|(_, v)| v)
        .collect();
    let text = serde_json::to_string(&events).unwrap();
    for needle in [
        "running",
        "set_gait",
        "set_controller",
        "engaged",
        "shutdown",
    ] {
        assert!(text.contains(needle), "{needle} in {text}");
    }
    let named = msgs
        .iter()
        .any(|(t, v)| t == "/controller/signals" && v["signals"]["phase_lag_rad"].is_number());
    assert!(named, "compliant slithering's signals by name");
    // The pose estimate ran in the loop: a valid body frame with a finite heading.
    let estimated = msgs.iter().rfind(|(t, _)| t == "/body/estimate");
    let (_, body) = estimated.expect("body estimates recorded");
    assert_eq!(body["valid"], true, "{body}");
    assert!(
        body["heading_rad"].as_f64().is_some_and(f64::is_finite),
        "{body}"
    );
    assert_eq!(body["orientation_wxyz"].as_array().map(Vec::len), Some(4));

    // The independent reader, where it is installed (.ci/run installs it).
    if !python_has_mcap() {
        return;
    }
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/mcap-summary.py");
    let text = python(&[script.as_ref(), file.as_os_str()]);
    let joints_line = text
        .lines()
        .find(|l| l.trim_start().starts_with("/joints "))
        .unwrap_or_else(|| panic!("{text}"));
    let n: u64 = joints_line
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(n, cycles.len() as u64, "{text}");
    assert!(text.contains("metadata snaked.status"), "{text}");
}

/// Whether python3 has the `mcap` package; CI must (`.ci/run` installs it).
fn python_has_mcap() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import mcap.reader"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have python3 mcap"
        );
        println!("skipped the Python reader: pip install mcap");
    }
    ok
}

/// Runs python3 with `args`: its output, once it succeeded.
fn python(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new("python3").args(args).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "python3 {args:?}:\n{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

/// docs/recording.md's Python recipe, as a user copies it, reading the file named by
/// its first argument.
fn documented_recipe() -> String {
    let doc = include_str!("../../../docs/recording.md");
    let section = &doc[doc
        .find("## Reading a recording with Python")
        .expect("the section")..];
    let start = section.find("```python\n").expect("a python block") + 10;
    let len = section[start..].find("```").expect("its end");
    let code = &section[start..start + len];
    assert!(code.contains("make_reader(f)") && code.contains("\"run.mcap\""));
    format!(
        "import sys\n{}",
        code.replace("\"run.mcap\"", "sys.argv[1]")
    )
}

/// Loop time of the first and the last `/joints` message, s, and how many there are.
fn joints_span(path: &std::path::Path) -> (f64, f64, usize) {
    let (_, msgs) = read(path, &["/joints"]);
    let t: Vec<f64> = msgs
        .iter()
        .map(|(_, v)| v["t_ns"].as_u64().expect("t_ns") as f64 * 1e-9)
        .collect();
    (t[0], t[t.len() - 1], t.len())
}

/// `snaked --recover FILE`: the recovered file's path and what the tool printed.
fn recover(file: &std::path::Path) -> (std::path::PathBuf, String) {
    let out = Command::new(exe("snaked"))
        .arg("--recover")
        .arg(file)
        .output()
        .expect("snaked --recover");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (file.with_file_name("run.recovered.mcap"), text)
}

#[test]
fn a_killed_recording_is_recovered_and_read_with_the_documented_recipe() {
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let file = dir.path().join("run.mcap");
    let config = dir.path().join("snaked.toml");
    std::fs::write(
        &config,
        "[record]\nchunk_duration_s = 0.1\nring_capacity = 256\n",
    )
    .unwrap();
    let mut d = Proc::spawn(
        "snaked",
        &exe("snaked"),
        &[
            "--config".into(),
            config.display().to_string(),
            "--emulated".into(),
            "--socket".into(),
            sock.display().to_string(),
            "--record".into(),
            file.display().to_string(),
        ],
    );
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    let s = c.wait_status(Duration::from_secs(60), "3 s of loop time", |s| {
        s["t_s"].as_f64().is_some_and(|t| t >= 3.0)
    });
    let killed_at = s["t_s"].as_f64().unwrap();
    d.signal(libc::SIGKILL);
    assert_eq!(
        std::os::unix::process::ExitStatusExt::signal(&d.wait(Duration::from_secs(30))),
        Some(libc::SIGKILL)
    );

    // As the kill left it: no footer, but whole chunks of less than 100 ms each.
    let bytes = std::fs::read(&file).unwrap();
    let spans: Vec<u64> = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .map_while(Result::ok)
        .filter_map(|r| match r {
            mcap::records::Record::Chunk { header, .. } => {
                Some(header.message_end_time - header.message_start_time)
            }
            _ => None,
        })
        .collect();
    assert!(spans.len() >= 10, "{} chunks", spans.len());
    assert!(spans.iter().all(|&ns| ns < 100_000_000), "{spans:?}");

    let (recovered, report) = recover(&file);
    println!("{report}");
    let (first, last, n) = joints_span(&recovered);
    let lost = killed_at - last;
    println!(
        "killed at t = {killed_at:.3} s; recovered /joints {first:.3}..{last:.3} s ({n} \
         messages); lost the last {lost:.3} s"
    );
    // Lost: the open chunk (≤ 100 ms) and what the ring held (≤ 256 items).
    assert!(lost < 1.0, "lost {lost:.3} s");

    if !python_has_mcap() {
        return;
    }
    let recipe = documented_recipe();
    let text = python(&["-c".as_ref(), recipe.as_ref(), recovered.as_os_str()]);
    // One line per /joints message (log time, t_ns, positions), then the metadata.
    let t_ns: Vec<u64> = text
        .lines()
        .filter_map(|l| l.split_whitespace().nth(1)?.parse().ok())
        .collect();
    assert_eq!(t_ns.len(), n, "the recipe reads every recovered message");
    assert_eq!(*t_ns.last().unwrap() as f64 * 1e-9, last);
    assert!(text.contains("snaked.recovery"), "the recovery is noted");
}

/// Under a file-size limit with the default signal handling (`LimitFSIZE=`, `ulimit -f`):
/// SIGXFSZ used to kill the daemon 0.7 s into the recording (no safe stop, no log, the
/// socket left behind). It ignores the signal, so the write fails (EFBIG) and the
/// recorder says the file is unfinished; the robot is driven on, `status` and `stats`
/// show the recorder failed and count what it lost, SIGTERM stops it cleanly, and the
/// file recovers.
#[test]
fn a_file_size_limit_is_reported_as_an_unfinished_file_that_recovers() {
    use std::io::{BufRead, BufReader};
    use std::os::unix::process::CommandExt;

    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("s.sock");
    let file = dir.path().join("run.mcap");
    // The file may not grow past 1 MB.
    let limit: u64 = 1_000_000;
    let mut cmd = Command::new(exe("snaked"));
    cmd.args(["--emulated", "--socket"])
        .arg(&sock)
        .arg("--record")
        .arg(&file)
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .env("RUST_LOG", "warn");
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: limit,
                rlim_max: limit,
            };
            libc::setrlimit(libc::RLIMIT_FSIZE, &lim);
            // What a service gets: the default action, which kills the process.
            libc::signal(libc::SIGXFSZ, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = cmd.spawn().expect("spawn snaked");
    let stderr = child.stderr.take().unwrap();
    let mut d = Proc {
        name: "snaked",
        child: Some(child),
    };
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    let mut log = Vec::new();
    let wait = |log: &mut Vec<String>, needle: &str| {
        while !log.iter().any(|l| l.contains(needle)) {
            match rx.recv_timeout(Duration::from_secs(60)) {
                Ok(l) => log.push(l),
                Err(e) => panic!("no {needle:?} in the log ({e}):\n{}", log.join("\n")),
            }
        }
    };
    wait(&mut log, "was not finished");

    // Still driving, and saying what became of the recording.
    let mut c = Client::connect(&sock, Duration::from_secs(30));
    let status = c.call("status", json!({}));
    assert_eq!(status["mode"], "running", "{status}");
    let record = &status["record"];
    assert_eq!(record["state"], "failed", "{record}");
    assert_eq!(record["path"], file.display().to_string(), "{record}");
    let error = record["error"].as_str().unwrap_or_default();
    assert!(
        error.contains("File too large") && error.contains("snaked --recover"),
        "{record}"
    );
    assert!(record["bytes"].as_u64().unwrap() <= limit, "{record}");
    let lost = |c: &mut Client| c.call("stats", json!({}))["record"]["lost"].as_u64();
    let before = lost(&mut c).expect("stats counts the items lost");
    std::thread::sleep(Duration::from_millis(300));
    let after = lost(&mut c).unwrap();
    assert!(
        after > before,
        "lost {before} then {after}: every item since is lost"
    );
    let shown = Command::new(exe("snakectl"))
        .arg("--socket")
        .arg(&sock)
        .arg("status")
        .output()
        .unwrap();
    let shown = String::from_utf8_lossy(&shown.stdout);
    assert!(shown.contains("record    failed"), "{shown}");
    drop(c);

    d.signal(libc::SIGTERM);
    assert!(d.wait(Duration::from_secs(30)).success(), "exit 0");
    log.extend(rx.try_iter());
    let text = log.join("\n");
    assert!(!text.contains("file is finished"), "{text}");
    assert!(!text.contains("recording finished"), "{text}");
    assert!(text.contains("snaked --recover"), "{text}");
    assert!(
        !sock.exists(),
        "the socket file is removed at the safe stop"
    );
    let size = std::fs::metadata(&file).unwrap().len();
    assert!(size <= limit, "{size} bytes");

    // The log says how much the file holds; recovery gets at least that.
    let line = log.iter().find(|l| l.contains("was not finished")).unwrap();
    let held: f64 = line
        .split("hold the first ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    let (recovered, report) = recover(&file);
    println!("{line}\n{report}");
    let (first, last, n) = joints_span(&recovered);
    assert!(n > 100, "{n} /joints");
    assert!(
        last - first >= held - 0.002,
        "{first}..{last} s, {held} s held"
    );
}

/// `snaked ARGS --config CONFIG`: its exit code and what it said on stderr.
fn snaked_with(config: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(exe("snaked"))
        .args(args)
        .arg("--config")
        .arg(config)
        .env("RUST_LOG", "off")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), err)
}

/// `--check-config` refuses the `[record]` settings the recorder would refuse when the
/// daemon starts (by the recorder's own check), and the daemon refuses them the same
/// way: exit 2, the file and the key named.
#[test]
fn check_config_refuses_the_record_settings_the_start_would() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().display();
    let config = dir.path().join("c.toml");
    let sock = dir.path().join("s.sock");
    let start = ["--emulated", "--socket", sock.to_str().unwrap()];
    for (text, key) in [
        (
            format!("[record]\npath = \"{d}/r.mcap\"\nmax_mb = 5e-324\n"),
            "record.max_mb",
        ),
        (
            format!("[record]\npath = \"{d}/r.mcap\"\nmax_mb = 0.5\n"),
            "record.max_mb",
        ),
        (format!("[record]\npath = \"{d}\"\n"), "record.path"),
        (
            format!("[record]\npath = \"{d}/missing/r-{{time}}.mcap\"\n"),
            "record.path",
        ),
    ] {
        std::fs::write(&config, &text).unwrap();
        for args in [&["--check-config"][..], &start] {
            let (code, err) = snaked_with(&config, args);
            assert_eq!(code, Some(2), "{args:?} {text}: {err}");
            assert!(err.contains("c.toml") && err.contains(key), "{text}: {err}");
        }
    }
    // At the smallest cap, in a directory that exists, it is fine.
    let text = format!("[record]\npath = \"{d}/r.mcap\"\nmax_mb = 1\n");
    std::fs::write(&config, text).unwrap();
    let (code, err) = snaked_with(&config, &["--check-config"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        !dir.path().join("r.mcap").exists(),
        "a check creates nothing"
    );
}
