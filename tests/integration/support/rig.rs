//! Shared pieces of the hardware-in-loop tests: free ports, child processes that
//! are killed when a test fails, a line-JSON client, and the emulator's recording.

use std::io::{BufRead, BufReader, Write};
use std::net::UdpSocket;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// A base port with `n` consecutive free UDP ports on 127.0.0.1.
pub fn free_udp_ports(n: u16) -> u16 {
    let seed = std::process::id() as u16;
    for attempt in 0..200u16 {
        let base = 20000 + (seed.wrapping_mul(7).wrapping_add(attempt * 97) % 30000);
        let held: Vec<_> = (0..n)
            .filter_map(|i| UdpSocket::bind(("127.0.0.1", base + i)).ok())
            .collect();
        if held.len() == n as usize {
            return base;
        }
    }
    panic!("no {n} consecutive free UDP ports");
}

/// A child process killed on drop (so a failing test leaves nothing running).
pub struct Proc {
    pub name: &'static str,
    pub child: Option<Child>,
}

impl Proc {
    pub fn spawn(name: &'static str, exe: &str, args: &[String]) -> Proc {
        Self::spawn_with(name, exe, args, |_| {})
    }

    /// As [`Proc::spawn`], the command prepared by `setup` first (limits, its output).
    pub fn spawn_with(
        name: &'static str,
        exe: &str,
        args: &[String],
        setup: impl FnOnce(&mut Command),
    ) -> Proc {
        let mut cmd = Command::new(exe);
        cmd.args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .env("RUST_LOG", "warn");
        setup(&mut cmd);
        let child = cmd
            .spawn()
            .unwrap_or_else(|e| panic!("spawning {name}: {e}"));
        Proc {
            name,
            child: Some(child),
        }
    }

    pub fn pid(&self) -> i32 {
        self.child.as_ref().expect("running").id() as i32
    }

    pub fn signal(&self, sig: i32) {
        // SAFETY: sending a signal to our own child.
        unsafe { libc::kill(self.pid(), sig) };
    }

    /// Wait for exit, at most `timeout`.
    pub fn wait(&mut self, timeout: Duration) -> ExitStatus {
        let deadline = Instant::now() + timeout;
        let child = self.child.as_mut().expect("running");
        loop {
            if let Some(status) = child.try_wait().expect("try_wait") {
                self.child = None;
                return status;
            }
            assert!(
                Instant::now() < deadline,
                "{} did not exit within {timeout:?}",
                self.name
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    pub fn is_running(&mut self) -> bool {
        matches!(self.child.as_mut().map(|c| c.try_wait()), Some(Ok(None)))
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// The process `cmd` starts may open at most `n` files (RLIMIT_NOFILE, soft and hard).
pub fn limit_files(cmd: &mut Command, n: u64) {
    use std::os::unix::process::CommandExt;
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            let r = libc::rlimit {
                rlim_cur: n,
                rlim_max: n,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &r) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// Raises this process's open files' soft limit to the hard one (a flood's own ends).
pub fn raise_file_limit() {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit and setrlimit read and write the struct they are given.
    unsafe {
        assert_eq!(libc::getrlimit(libc::RLIMIT_NOFILE, &mut r), 0);
        r.rlim_cur = r.rlim_max;
        assert_eq!(libc::setrlimit(libc::RLIMIT_NOFILE, &r), 0);
    }
}

/// Waits (at most 30 s) until the log file at `path` holds every one of `what`; the log.
pub fn wait_log(path: &Path, what: &[&str]) -> String {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let log = std::fs::read_to_string(path).unwrap_or_default();
        if what.iter().all(|w| log.contains(w)) {
            return log;
        }
        assert!(Instant::now() < deadline, "the log lacks {what:?}:\n{log}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A line-JSON client of the control socket.
pub struct Client {
    reader: BufReader<UnixStream>,
    writer: UnixStream,
    next_id: u64,
}

impl Client {
    /// Connect, retrying until the daemon has created its socket.
    pub fn connect(path: &Path, timeout: Duration) -> Client {
        let deadline = Instant::now() + timeout;
        loop {
            match UnixStream::connect(path) {
                Ok(s) => {
                    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
                    return Client {
                        reader: BufReader::new(s.try_clone().unwrap()),
                        writer: s,
                        next_id: 1,
                    };
                }
                Err(e) => {
                    assert!(
                        Instant::now() < deadline,
                        "connecting to {}: {e}",
                        path.display()
                    );
                    std::thread::sleep(Duration::from_millis(50));
                }
            }
        }
    }

    /// Send a request and return the whole answer object.
    pub fn call_raw(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let line = json!({"id": id, "method": method, "params": params}).to_string();
        writeln!(self.writer, "{line}").unwrap();
        loop {
            let mut buf = String::new();
            let n = self.reader.read_line(&mut buf).expect("reading an answer");
            assert!(n > 0, "daemon closed the connection");
            let v: Value = serde_json::from_str(&buf).expect("answers are JSON");
            if v.get("id") == Some(&json!(id)) {
                return v;
            }
        }
    }

    /// Send a request; panic on an error answer.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        let v = self.call_raw(method, params);
        match v.get("result") {
            Some(r) => r.clone(),
            None => panic!("{method} failed: {v}"),
        }
    }

    /// Poll `status` until `pred` holds, at most `timeout`.
    pub fn wait_status(
        &mut self,
        timeout: Duration,
        what: &str,
        pred: impl Fn(&Value) -> bool,
    ) -> Value {
        let deadline = Instant::now() + timeout;
        loop {
            let s = self.call("status", json!({}));
            if pred(&s) {
                return s;
            }
            assert!(
                Instant::now() < deadline,
                "timed out waiting for {what}; last status {s}"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// The emulator's ground-truth recording: `t_s,cmd_0..,pos_0..,torque_0..`.
pub struct Recording {
    pub t: Vec<f64>,
    pub cmd: Vec<Vec<f64>>,
    pub pos: Vec<Vec<f64>>,
    pub torque: Vec<Vec<f64>>,
}

impl Recording {
    pub fn load(path: &Path, n: usize) -> Recording {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().expect("header").split(',').collect();
        assert_eq!(header.len(), 1 + 3 * n, "recording columns: {header:?}");
        let mut r = Recording {
            t: vec![],
            cmd: vec![vec![]; n],
            pos: vec![vec![]; n],
            torque: vec![vec![]; n],
        };
        for line in lines {
            let v: Vec<f64> = line
                .split(',')
                .map(|x| x.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            if v.len() != 1 + 3 * n {
                continue; // a row cut by the stop
            }
            r.t.push(v[0]);
            for i in 0..n {
                r.cmd[i].push(v[1 + i]);
                r.pos[i].push(v[1 + n + i]);
                r.torque[i].push(v[1 + 2 * n + i]);
            }
        }
        r
    }

    /// Index range of rows with `t0 <= t < t1`.
    pub fn span(&self, t0: f64, t1: f64) -> std::ops::Range<usize> {
        let a = self.t.partition_point(|&t| t < t0);
        let b = self.t.partition_point(|&t| t < t1);
        a..b
    }
}

pub fn exe(name: &str) -> String {
    match name {
        "snaked" => env!("CARGO_BIN_EXE_snaked").to_owned(),
        "snake-emu" => env!("CARGO_BIN_EXE_snake-emu").to_owned(),
        "snakectl" => env!("CARGO_BIN_EXE_snakectl").to_owned(),
        _ => panic!("unknown binary {name}"),
    }
}

pub fn tmp_path(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

/// `snake-emu` and `snaked` as processes on loopback, talking protocol v2, with the
/// daemon's socket connected and the emulator recording its ground truth.
pub struct Rig {
    pub dir: tempfile::TempDir,
    pub emu: Proc,
    pub daemon: Proc,
    pub client: Client,
    pub sock: PathBuf,
    pub recording: PathBuf,
}

impl Rig {
    /// `emu_args` are added to snake-emu's; `network` goes into the daemon's `[network]`
    /// section and `sections` after it (whole TOML sections, not `[network]`/`[control]`).
    pub fn start(n: usize, emu_args: &[&str], network: &str, sections: &str) -> Rig {
        let dir = tempfile::tempdir().unwrap();
        let base = free_udp_ports(n as u16);
        let recording = dir.path().join("truth.csv");
        let sock = dir.path().join("snaked.sock");
        let mut args = vec![
            "--modules".to_owned(),
            n.to_string(),
            "--base-port".into(),
            base.to_string(),
            "--record".into(),
            recording.display().to_string(),
        ];
        args.extend(emu_args.iter().map(|a| a.to_string()));
        let emu = Proc::spawn("snake-emu", &exe("snake-emu"), &args);
        let cfg_path = dir.path().join("snaked.toml");
        let last = base + n as u16 - 1;
        let cfg = format!(
            "[network]\ntargets = [\"127.0.0.1:{base}-{last}\"]\nexpected_modules = {n}\n\
             discovery_timeout_s = 5.0\n{network}\n{sections}\n[control]\nsocket = \"{}\"\n",
            sock.display()
        );
        std::fs::write(&cfg_path, cfg).unwrap();
        let daemon = Proc::spawn(
            "snaked",
            &exe("snaked"),
            &["--config".into(), cfg_path.display().to_string()],
        );
        let client = Client::connect(&sock, Duration::from_secs(30));
        Rig {
            dir,
            emu,
            daemon,
            client,
            sock,
            recording,
        }
    }

    /// SIGTERM the daemon (exit 0 and socket removed are checked), then the emulator;
    /// returns the emulator's recording.
    pub fn stop(mut self, n: usize) -> Recording {
        self.daemon.signal(libc::SIGTERM);
        let status = self.daemon.wait(Duration::from_secs(20));
        assert!(status.success(), "snaked exits 0 on SIGTERM: {status:?}");
        assert!(!self.sock.exists(), "the socket file is removed");
        self.emu.signal(libc::SIGTERM);
        assert!(
            self.emu.wait(Duration::from_secs(20)).success(),
            "snake-emu exits 0"
        );
        Recording::load(&self.recording, n)
    }
}
