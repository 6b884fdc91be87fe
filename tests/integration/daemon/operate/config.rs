//! `[foxglove]` as the configuration's check sees it (issue 44): what start-up would
//! refuse, `snaked --check-config` refuses (exit 2, the key named), and start-up refuses
//! it the same way: the token file (world-readable, missing, empty, too short), a port
//! the control socket's TCP listener takes, a teleop topic that is one of the daemon's
//! own channels, the connection caps and the open files' limit they must fit below.
use crate::support::rig::{Proc, exe, limit_files};

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// A token file with `text`, mode `mode`.
fn token_file(dir: &Path, name: &str, text: &str, mode: u32) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(mode)).unwrap();
    p.display().to_string()
}

/// `snaked --check-config` on `text`, at most `files` open files: exit code, stderr.
fn check(dir: &Path, text: &str, files: Option<u64>) -> (Option<i32>, String) {
    let path = dir.join("c.toml");
    std::fs::write(&path, text).unwrap();
    let mut cmd = Command::new(exe("snaked"));
    cmd.args(["--check-config", "--config"])
        .arg(&path)
        .env("RUST_LOG", "off");
    if let Some(n) = files {
        limit_files(&mut cmd, n);
    }
    let out = cmd.output().expect("run snaked");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn check_config_refuses_what_start_up_would_in_foxglove() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = token_file(d, "good", "correct-horse-battery\n", 0o600);
    let open = token_file(d, "open", "correct-horse-battery\n", 0o644);
    let empty = token_file(d, "empty", "\n", 0o600);
    let short = token_file(d, "short", "correct-horse\n", 0o600);
    let missing = d.join("nope").display().to_string();
    let operate = |token: &str| format!("[foxglove]\noperate = true\ntoken_file = {token:?}\n");
    let cases = [
        (
            operate(&open),
            "foxglove.token_file",
            "readable by every user",
        ),
        (operate(&missing), "foxglove.token_file", "No such file"),
        (operate(&empty), "foxglove.token_file", "empty"),
        (operate(&short), "foxglove.token_file", "at least 16"),
        (
            format!(
                "[control]\ntcp_port = 7878\ntcp_token_file = {good:?}\n\
                 [foxglove]\nenabled = true\nport = 7878\n"
            ),
            "foxglove.port",
            "control.tcp_port",
        ),
        (
            "[foxglove]\nteleop_topic = \"/joints\"\n".into(),
            "foxglove.teleop_topic",
            "the daemon's own channels",
        ),
        (
            "[foxglove]\nteleop_topic = \"/operator\"\n".into(),
            "foxglove.teleop_topic",
            "the daemon's own channels",
        ),
        (
            "[foxglove]\nmax_connections = 0\n".into(),
            "foxglove.max_connections",
            "must be in",
        ),
        (
            "[foxglove]\nmax_connections = 8\nmax_connections_per_address = 9\n".into(),
            "foxglove.max_connections_per_address",
            "must be in [1, 8]",
        ),
        (
            "[foxglove]\nhandshake_timeout_s = 0.0\n".into(),
            "foxglove.handshake_timeout_s",
            "must be in",
        ),
    ];
    for (text, key, why) in &cases {
        let (code, err) = check(d, text, None);
        assert_eq!(code, Some(2), "{text}: {err}");
        assert!(
            err.contains("c.toml") && err.contains(key) && err.contains(why),
            "{text}: {err}"
        );
    }
    // The same with a good token passes.
    let (code, err) = check(d, &operate(&good), None);
    assert_eq!(code, Some(0), "{err}");
}

/// The caps plus the daemon's reserve must fit below the open files' limit: under a
/// 100-file limit the defaults (32 Foxglove connections, 64 control clients, 64 for the
/// rest) do not.
#[test]
fn caps_that_do_not_fit_below_the_file_limit_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (code, err) = check(dir.path(), "[foxglove]\nenabled = true\n", Some(100));
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("foxglove.max_connections") && err.contains("LimitNOFILE"),
        "{err}"
    );
    let (code, err) = check(
        dir.path(),
        "[foxglove]\nenabled = true\nmax_connections = 8\n[control]\nmax_clients = 8\n",
        Some(100),
    );
    assert_eq!(code, Some(0), "smaller caps fit: {err}");
}

/// Start-up runs the same check: exit 2 and the key, not exit 1 later (issue 44).
#[test]
fn start_up_refuses_a_foxglove_token_as_the_check_does() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, mode) in [
        ("short", "correct-horse\n", 0o600),
        ("open", "correct-horse-battery\n", 0o644),
    ] {
        let token = token_file(dir.path(), name, text, mode);
        let path = dir.path().join("c.toml");
        std::fs::write(
            &path,
            format!("[foxglove]\noperate = true\nport = 0\ntoken_file = {token:?}\n"),
        )
        .unwrap();
        let log = dir.path().join("log");
        let mut p = Proc::spawn_with(
            "snaked",
            &exe("snaked"),
            &[
                "--emulated".into(),
                "--config".into(),
                path.display().to_string(),
                "--socket".into(),
                dir.path().join("s.sock").display().to_string(),
            ],
            |c| {
                c.stderr(std::fs::File::create(&log).unwrap());
            },
        );
        let status = p.wait(Duration::from_secs(30));
        let err = std::fs::read_to_string(&log).unwrap();
        assert_eq!(status.code(), Some(2), "{name}: {err}");
        assert!(err.contains("foxglove.token_file"), "{name}: {err}");
    }
}
