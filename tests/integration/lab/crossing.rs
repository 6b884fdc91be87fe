//! `snake-lab crossing` end to end with tiny settings: every gait and the navigator run,
//! the columns and the summary are there, bad options are named.

use super::{lab, read};

#[test]
fn crossing_runs_any_gait_and_the_navigator() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let args = [
        "crossing",
        "--family",
        "mixed",
        "--skin",
        "sleeve",
        "--layouts",
        "1",
        "--kinds",
        "along-inside,across-edge",
        "--starts",
        "2",
        "--controllers",
        "a_ws_omega,ac_sfc,navigator",
        "--seconds",
        "3",
        "--threads",
        "2",
        "--quiet",
        "--out",
        out,
    ];
    let o = lab(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = read(&dir.path().join("results.csv"));
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(
        &rows[0][..6],
        [
            "controller",
            "layout",
            "start",
            "repeat",
            "start_kind",
            "outcome"
        ]
    );
    assert!(rows[0].contains(&"gait_switches") && rows[0].contains(&"jam_episodes"));
    assert_eq!(rows.len(), 1 + 3 * 2, "{csv}");
    for row in &rows[1..] {
        assert_eq!(row.len(), rows[0].len());
        assert!(["along-inside", "across-edge"].contains(&row[4]), "{row:?}");
        assert_eq!(row[5], "timeout", "3 s is not enough to cross: {row:?}");
    }
    let summary = read(&dir.path().join("summary.md"));
    assert!(summary.contains("| navigator | 2 |"), "{summary}");
    assert!(summary.contains("Skin µ 0.2"), "{summary}");
    assert!(
        summary.contains("stuck detector against the truth"),
        "{summary}"
    );
}

#[test]
fn crossing_names_a_bad_family_and_a_foreign_name_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = lab(&["crossing", "--family", "moon", "--quiet", "--out", out]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("moon") && err.contains("thesis, mixed, rocks"),
        "{err}"
    );
    // Only the crossing compares gaits: the peg board refuses a sidewinding controller.
    let o = lab(&[
        "pegboard",
        "--controllers",
        "ac_sfc",
        "--quiet",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(2));
}
