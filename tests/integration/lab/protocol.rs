//! The directional-compliance experiments run the protocol they are evaluated with by
//! default (`scenarios/protocols/`), and a protocol file of one's own sets a run.

use std::path::{Path, PathBuf};

use super::{lab, lab_ok, read};

/// The built-in protocol's world with `protocol` as its `[protocol]` table.
fn protocol_file(dir: &Path, protocol: &str) -> PathBuf {
    let builtin = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/protocols/peg-array.toml");
    let builtin = read(&builtin);
    let start = builtin.find("\n[protocol]\n").unwrap() + 1;
    let end = builtin.find("\n[friction]\n").unwrap() + 1;
    let text = format!("{}{protocol}\n{}", &builtin[..start], &builtin[end..]);
    let path = dir.join("mine.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn peg_array_defaults_to_the_evaluated_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("default");
    lab_ok(
        "peg-array --controllers dc_nc --starts 1 --repeats 1 --seconds 1 --no-calibrate \
         --quiet --out",
        &[out.to_str().unwrap()],
    );
    let md = read(&out.join("summary.md"));
    assert!(
        md.contains("Protocol: `scenarios/protocols/peg-array.toml (built in)`"),
        "{md}"
    );
    // The nominal of the documented evaluation
    // (docs/measurements/directional-compliance.md), not the daemon's.
    assert!(
        md.contains(
            "amplitude_lat_rad 1.2, amplitude_dor_rad 0, spatial_freq_rad 6.283185307179586"
        ),
        "{md}"
    );
    let help = lab_ok("peg-array --help", &[]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("scenarios/protocols/peg-array.toml"),
        "{help}"
    );
}

#[test]
fn a_protocol_file_sets_the_run_unless_the_command_line_says_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let file = protocol_file(
        dir.path(),
        "[protocol]\nnominal = { amplitude_lat_rad = 1.0 }\n\
         layouts = 2\nstarts = 2\nrepeats = 1\nseconds = 0.5\n",
    );
    let run = |name: &str, typed: &str| {
        let out = dir.path().join(name);
        let line = format!("peg-array --controllers dc_nc --no-calibrate --quiet {typed}");
        lab_ok(
            &line,
            &[
                "--scenario",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        (
            read(&out.join("results.csv")),
            read(&out.join("summary.md")),
        )
    };
    let (csv, md) = run("file", "");
    assert_eq!(csv.lines().count(), 1 + 2 * 2, "{csv}");
    let counts = "2 layout(s) (seed101, seed102), 2 start(s) each, 1 trial(s) per start";
    assert!(md.contains(counts), "{md}");
    assert!(md.contains("at most 0.5 s per trial"), "{md}");
    assert!(md.contains("amplitude_lat_rad 1, "), "{md}");
    // What is typed wins; --nominal patches the protocol's nominal.
    let (csv, md) = run(
        "typed",
        r#"--layouts 1 --starts 1 --repeats 2 --seconds 0.3 --nominal {"spatial_freq_rad":5.0}"#,
    );
    assert_eq!(csv.lines().count(), 1 + 2, "{csv}");
    assert!(md.contains("at most 0.3 s per trial"), "{md}");
    let nominal = "amplitude_lat_rad 1, amplitude_dor_rad 0, spatial_freq_rad 5,";
    assert!(md.contains(nominal), "{md}");
    // A protocol's nominal is checked as the daemon checks it, naming the file.
    let bad = protocol_file(
        dir.path(),
        "[protocol]\nnominal = { amplitude_lat_rad = 2.0 }\n",
    );
    let out = dir.path().join("bad");
    let o = lab(&[
        "peg-array",
        "--scenario",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("mine.toml: [protocol] nominal") && err.contains("amplitude_lat_rad"),
        "{err}"
    );
}
