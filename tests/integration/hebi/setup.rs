//! Bad HEBI setups get clear answers: the exit code, and a message naming the problem
//! (the key, the path, the modules and where they were looked for).
use std::path::Path;

use super::{Ran, config, libhebi, snaked};

/// `[control] socket = ""`: nothing of these runs is left behind.
const NO_SOCKET: &str = "[control]\nsocket = \"\"\n";

fn imitation(library: &Path, rest: &str) -> String {
    config(library, "imitation = 18", &format!("{rest}{NO_SOCKET}"))
}

/// Exit `code`, and stderr holds every one of `what`.
fn says(ran: &Ran, code: i32, what: &[&str]) {
    let err = &ran.stderr;
    assert_eq!(ran.code, Some(code), "stderr: {err}");
    for w in what {
        assert!(err.contains(w), "stderr lacks {w:?}: {err}");
    }
}

#[test]
fn a_library_path_that_does_not_exist_is_a_bad_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let nope = dir.path().join("nope").join("libhebi.so.2.27.0");
    let text = imitation(&nope, "");
    let nope = nope.display().to_string();
    for args in [&[][..], &["--check-config"][..]] {
        let ran = snaked(&text, args);
        says(
            &ran,
            2,
            &[
                "bad configuration",
                "hebi.library",
                "not found",
                &format!("looked in: {nope} (hebi.library)"),
            ],
        );
    }
}

#[test]
fn a_file_that_is_not_libhebi_cannot_be_loaded() {
    // A text file under libhebi's name: the loader refuses it, and says why.
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("libhebi.so.2.27.0");
    std::fs::write(&fake, "not a shared library\n").unwrap();
    let ran = snaked(&imitation(&fake, ""), &["--check-config"]);
    let fake = fake.display().to_string();
    says(
        &ran,
        2,
        &[
            "bad configuration",
            "hebi.library",
            &format!("cannot load {fake} as libhebi"),
        ],
    );
    // The loader's reason, not libloading's bare "dlopen failed".
    let reason = ran
        .stderr
        .split("dlopen failed: ")
        .nth(1)
        .unwrap_or_default();
    assert!(!reason.trim().is_empty(), "{}", ran.stderr);

    // A real shared library that is not libhebi: loaded, then refused by its symbols.
    let libm = Path::new("/lib/x86_64-linux-gnu/libm.so.6");
    if libm.is_file() {
        let ran = snaked(&imitation(libm, ""), &["--check-config"]);
        says(
            &ran,
            2,
            &[
                "bad configuration",
                "hebi.library",
                "libm.so.6",
                "hebiGetLibraryVersion",
                "not libhebi",
            ],
        );
    } else {
        eprintln!("no {}: the shared library case not run", libm.display());
    }
}

#[test]
fn a_gain_out_of_range_is_named() {
    let text = imitation(&libhebi(), "[hebi.gains.all]\nposition_kp = -1.0\n");
    for args in [&[][..], &["--check-config"][..]] {
        let ran = snaked(&text, args);
        says(
            &ran,
            2,
            &["bad configuration", "hebi.gains", "all.position_kp"],
        );
    }
}

#[test]
fn lockstep_pacing_with_the_hebi_bus_is_refused_at_check_config() {
    let lib = libhebi();
    let in_file = imitation(&lib, "[loop]\npacing = \"lockstep\"\n");
    let ran = snaked(&in_file, &["--check-config"]);
    says(&ran, 2, &["bad configuration", "loop.pacing", "lockstep"]);
    assert!(ran.stderr.contains("hebi"), "{}", ran.stderr);
    // The command line's override too.
    let ran = snaked(
        &imitation(&lib, ""),
        &["--check-config", "--pacing", "lockstep"],
    );
    says(&ran, 2, &["bad configuration", "loop.pacing", "lockstep"]);
}

#[test]
fn a_module_missing_at_start_up_is_named_with_where_it_was_looked_for() {
    let text = config(
        &libhebi(),
        "names = [\"SA001\", \"SA002\"]\nlookup_timeout_s = 0.5\n",
        NO_SOCKET,
    );
    let started = std::time::Instant::now();
    let ran = snaked(&text, &[]);
    let took = started.elapsed();
    let err = &ran.stderr;
    assert!(
        matches!(ran.code, Some(c) if c != 0),
        "{:?}: {err}",
        ran.code
    );
    for w in [
        "SA001",
        "SA002",
        "not found on 127.0.0.1",
        "nothing answered",
    ] {
        assert!(err.contains(w), "stderr lacks {w:?}: {err}");
    }
    assert!(
        took.as_secs_f64() < 20.0,
        "gave up after the lookup's timeout: {took:?}"
    );
}

#[test]
fn list_modules_on_loopback_says_none_answered_and_exits_0() {
    let text = config(&libhebi(), "lookup_timeout_s = 0.5\n", NO_SOCKET);
    let ran = snaked(&text, &["--list-modules"]);
    assert_eq!(ran.code, Some(0), "stderr: {}", ran.stderr);
    let lines: Vec<&str> = ran.stdout.lines().collect();
    let header = lines.first().copied().unwrap_or_default();
    assert!(
        header.starts_with("# libhebi 2.27.0")
            && header.contains("0 module(s) answered on 127.0.0.1"),
        "{}",
        ran.stdout
    );
    assert_eq!(
        lines.len(),
        2,
        "the columns' header, no module: {}",
        ran.stdout
    );
    assert!(lines[1].starts_with("family"), "{}", ran.stdout);
}
