//! A sweep split into shards and merged gives the unsharded run's report.

use std::path::Path;

use super::{lab, lab_ok, read};

/// `snake-lab pegboard` with two controllers on two layouts (4 trials, 2 s each):
/// the second controller's plotted trial (plan index 2) falls in shard 3 of 3.
fn run(out: &Path, extra: &[&str]) {
    let mut args = vec![out.to_str().unwrap()];
    args.extend_from_slice(extra);
    lab_ok(
        "pegboard --controllers open_loop,a_ws_omega --layouts 2 --starts 1 --seconds 2 \
         --threads 1 --quiet --out",
        &args,
    );
}

#[test]
fn three_shards_merged_equal_the_unsharded_run() {
    let whole = tempfile::tempdir().unwrap();
    run(whole.path(), &[]);
    let shards = tempfile::tempdir().unwrap();
    // Given in any order, as a scheduler finishes them.
    for k in ["3/3", "1/3", "2/3"] {
        run(shards.path(), &["--shard", k]);
    }
    assert!(
        !shards.path().join("results.csv").exists(),
        "a shard writes no report"
    );
    let o = lab(&["merge", shards.path().to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = read(&whole.path().join("results.csv"));
    let b = read(&shards.path().join("results.csv"));
    assert_eq!(a.lines().count(), 5, "{a}");
    assert_eq!(a, b, "row for row");
    // The same summary and command, but for where each was written.
    let summary = |d: &Path| read(&d.join("summary.md")).replace(d.to_str().unwrap(), "OUT");
    assert_eq!(summary(whole.path()), summary(shards.path()));
    for png in [
        "cycles_per_m.png",
        "path-a_ws_omega.png",
        "signals-a_ws_omega.png",
    ] {
        assert!(shards.path().join(png).exists(), "{png}");
    }
}

#[test]
fn merge_names_the_missing_shards_and_refuses_other_runs() {
    let dir = tempfile::tempdir().unwrap();
    run(dir.path(), &["--shard", "2/3"]);
    let o = lab(&["merge", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("2 of 3 shards missing: 1/3, 3/3 (have 2/3)"),
        "{err}"
    );
    // A shard of another plan (other boards) is not merged with this one.
    let other = tempfile::tempdir().unwrap();
    run(other.path(), &["--shard", "1/3", "--seed-base", "2000"]);
    let o = lab(&[
        "merge",
        dir.path().to_str().unwrap(),
        other.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("is not of the same run"), "{err}");
    let o = lab(&["merge", other.path().join("nothing-here").to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = lab(&["pegboard", "--shard", "4/3"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn merge_names_an_incomplete_shard() {
    let dir = tempfile::tempdir().unwrap();
    for k in ["1/2", "2/2"] {
        run(dir.path(), &["--shard", k]);
    }
    // Shard 1/2 with one of its two trials gone.
    let path = dir.path().join("shard-1-of-2.cbor");
    let mut file: ciborium::Value =
        ciborium::from_reader(std::fs::File::open(&path).unwrap()).unwrap();
    let ciborium::Value::Map(fields) = &mut file else {
        panic!("a shard file is a map")
    };
    let results = fields
        .iter_mut()
        .find(|(k, _)| k.as_text() == Some("results"))
        .map(|(_, v)| v)
        .unwrap();
    let ciborium::Value::Array(trials) = results else {
        panic!("results is an array")
    };
    trials.pop();
    ciborium::into_writer(&file, std::fs::File::create(&path).unwrap()).unwrap();
    let o = lab(&["merge", dir.path().to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("shard 1/2 is incomplete: it holds 1 trials, 1 of its 2"),
        "{err}"
    );
}
