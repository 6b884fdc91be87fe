//! The shipped unit passes `systemd-analyze verify` with no warnings at all.
use std::process::Command;

#[test]
fn unit_file_verifies_without_warnings() {
    let unit = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/systemd/snaked.service"
    ))
    .unwrap();
    assert!(
        unit.contains("ExecStart=/usr/local/bin/snaked "),
        "install path as README says"
    );
    assert!(unit.contains("Type=notify") && unit.contains("WatchdogSec="));
    // verify checks that ExecStart exists: point it at the binary this build made.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("snaked.service");
    std::fs::write(
        &path,
        unit.replace("/usr/local/bin/snaked", env!("CARGO_BIN_EXE_snaked")),
    )
    .unwrap();
    let out = Command::new("systemd-analyze")
        .arg("verify")
        .arg(&path)
        .output()
        .expect("systemd-analyze is installed (.ci/run installs it)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "verify failed: {stderr}{stdout}");
    assert!(
        stderr.trim().is_empty() && stdout.trim().is_empty(),
        "warnings: {stderr}{stdout}"
    );
}
