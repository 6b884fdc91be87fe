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

/// The udev rule lets the unit's group hold the CPU latency limit, and the unit lets the
/// device into its private /dev with write access.
#[test]
fn the_cpu_latency_device_reaches_the_service() {
    let root = env!("CARGO_MANIFEST_DIR");
    let unit = std::fs::read_to_string(format!("{root}/systemd/snaked.service")).unwrap();
    let rule =
        std::fs::read_to_string(format!("{root}/systemd/60-snaked-cpu-latency.rules")).unwrap();
    let group = unit
        .lines()
        .find_map(|l| l.strip_prefix("Group="))
        .expect("the unit names its group");
    let rule_line = rule
        .lines()
        .find(|l| !l.starts_with('#') && !l.trim().is_empty())
        .unwrap();
    assert!(
        rule_line.contains("KERNEL==\"cpu_dma_latency\"")
            && rule_line.contains(&format!("GROUP=\"{group}\""))
            && rule_line.contains("MODE=\"0660\""),
        "{rule_line}"
    );
    assert!(unit.contains("BindPaths=-/dev/cpu_dma_latency"));
    assert!(unit.contains("DeviceAllow=/dev/cpu_dma_latency rw"));
}
