//! `snaked` with `[bus] kind = "hebi"`: the real binary over HEBI's libhebi (loaded at
//! run time from `target/hebi/`, fetched by scripts/fetch-libhebi.sh when missing: a
//! missing library fails these tests, never skips them). The whole daemon runs over
//! HEBI's imitation group (no network); the bad setups are refused with their cause.
//!
//! Every configuration here confines libhebi's lookup to loopback (`interfaces =
//! ["127.0.0.1"]`): no test broadcasts on the machine's networks. [`config`] writes that
//! line itself and [`write_config`] refuses a HEBI configuration without it.

mod imitation;
mod setup;

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::support::rig;

/// The version scripts/fetch-libhebi.sh pins.
const LIBRARY: &str = "libhebi.so.2.27.0";

/// What keeps every lookup on loopback.
pub const LOOPBACK_ONLY: &str = "interfaces = [\"127.0.0.1\"]";

/// libhebi's path: `target/hebi/libhebi.so.2.27.0` beside the build, else what
/// scripts/fetch-libhebi.sh prints once it has fetched it. Panics if neither gives one.
pub fn libhebi() -> PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let here = root.join("target/hebi").join(LIBRARY);
        if here.is_file() {
            return here;
        }
        let script = root.join("scripts/fetch-libhebi.sh");
        let out = Command::new(&script).output().unwrap_or_else(|e| {
            panic!(
                "libhebi is needed by the HEBI tests: {} is missing and {} could not run: {e}",
                here.display(),
                script.display()
            )
        });
        assert!(
            out.status.success(),
            "libhebi is needed by the HEBI tests: {} is missing and scripts/fetch-libhebi.sh \
             failed ({}): {}",
            here.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        let path = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        assert!(
            path.is_file(),
            "scripts/fetch-libhebi.sh printed {path:?}, which is not a file"
        );
        path
    })
    .clone()
}

/// A configuration driving the HEBI bus through `library`, the lookup on loopback:
/// `hebi_keys` go into `[hebi]`, `rest` (whole TOML tables) after it.
pub fn config(library: &Path, hebi_keys: &str, rest: &str) -> String {
    format!(
        "[bus]\nkind = \"hebi\"\n[hebi]\n{LOOPBACK_ONLY}\nlibrary = \"{}\"\n{hebi_keys}\n{rest}\n",
        library.display()
    )
}

/// Writes `text` as `name` in `dir`; a HEBI configuration must keep its lookup on
/// loopback.
pub fn write_config(dir: &Path, name: &str, text: &str) -> PathBuf {
    assert!(
        !text.contains("\"hebi\"") || text.contains(LOOPBACK_ONLY),
        "a HEBI test's lookup stays on loopback: {text}"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// How `snaked` ended: exit code, stdout, stderr.
pub struct Ran {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `snaked --config <text> args...` to its end (at most 60 s, then killed and
/// failed), its logs off: what it says is its own message.
pub fn snaked(text: &str, args: &[&str]) -> Ran {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), "snaked.toml", text);
    let (out, err) = (dir.path().join("out"), dir.path().join("err"));
    let mut child = Command::new(rig::exe("snaked"))
        .arg("--config")
        .arg(&cfg)
        .args(args)
        .env("RUST_LOG", "off")
        .env_remove("SNAKED_LIBHEBI")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("spawning snaked");
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "snaked {args:?} did not end within 60 s; stderr: {}",
                std::fs::read_to_string(&err).unwrap_or_default()
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Ran {
        code: status.code(),
        stdout: std::fs::read_to_string(&out).unwrap(),
        stderr: std::fs::read_to_string(&err).unwrap(),
    }
}

/// Subscribes to telemetry on a connection of its own and returns the first message
/// whose params satisfy `pred` (at most 20 s).
pub fn telemetry_until(sock: &Path, what: &str, pred: impl Fn(&Value) -> bool) -> Value {
    let s = UnixStream::connect(sock).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let mut w = s.try_clone().unwrap();
    writeln!(
        w,
        r#"{{"id":1,"method":"telemetry.subscribe","params":{{"rate_hz":50}}}}"#
    )
    .unwrap();
    let mut r = BufReader::new(s);
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut last = Value::Null;
    while Instant::now() < deadline {
        let mut line = String::new();
        assert!(r.read_line(&mut line).unwrap() > 0, "the daemon closed");
        let v: Value = serde_json::from_str(&line).unwrap();
        if v["id"] == 1 {
            assert_eq!(v["result"]["subscribed"], true, "{v}");
        } else if v["method"] == "telemetry" {
            if pred(&v["params"]) {
                return v["params"].clone();
            }
            last = v;
        }
    }
    panic!("no telemetry showed {what}; last {last}");
}
