//! snakectl's view of slithering's compliant controller: the `--compliance` argument,
//! the setting (`params get/set`) and the windows table (`status`).
use serde_json::{Value, json};

use super::{num, text};

/// `--compliance NAME` or `--compliance '{...}'` as the `compliance` param.
pub fn arg(c: &str) -> Result<Value, String> {
    let c = c.trim();
    if c.starts_with('{') {
        let v: Value =
            serde_json::from_str(c).map_err(|e| format!("--compliance is not valid JSON: {e}"))?;
        Ok(v)
    } else {
        Ok(json!({ "controller": c }))
    }
}

/// The controller and, for a shape-based one, each parameter's compliance.
pub fn print_setting(s: &Value) {
    if s.is_null() {
        return;
    }
    println!("compliance    {}", text(&s["controller"]));
    let c = &s["config"];
    if c.is_null() {
        return;
    }
    for p in ["amplitude", "spatial_freq", "phase"] {
        let pc = &c[p];
        let g = &pc["gains"];
        println!(
            "  {p:<13} {:<3} {:<9}  M {}  B {}  K {}  range [{}, {}]  bias {}",
            if pc["enabled"] == true { "on" } else { "off" },
            text(&pc["centralization"]),
            num(&g["mass"], 2),
            num(&g["damping"], 2),
            num(&g["stiffness"], 2),
            num(&g["min"], 3),
            num(&g["max"], 3),
            num(&g["bias_force"], 2),
        );
    }
    println!(
        "  {}  torque cutoff {} Hz  deadband {} N·m  window edge {} modules",
        text(&c["compliance"]),
        num(&c["torque_cutoff_hz"], 1),
        num(&c["torque_deadband_nm"], 2),
        num(&c["edge_width_modules"], 2),
    );
}

/// `status`: the controller, its state and, while it drives, one table per field.
pub fn print_status(c: &Value) {
    if c.is_null() {
        return;
    }
    let controller = text(&c["controller"]);
    if controller == "open_loop" {
        println!("slithering open loop");
        return;
    }
    let mut line = format!(
        "slithering {controller} ({})  takeovers {}",
        text(&c["state"]),
        c["takeovers"]
    );
    if c.get("phase_lag_rad").is_some() {
        line += &format!(
            "  phase lag {} rad  mean A {} rad  mean ωS {} rad",
            num(&c["phase_lag_rad"], 3),
            num(&c["amplitude_mean_rad"], 3),
            num(&c["spatial_freq_mean_rad"], 2)
        );
    }
    println!("{line}");
    if c.get("windows").is_some() {
        println!(
            "  windows {}  born {}  dropped {}",
            c["windows"], c["windows_born"], c["windows_dropped"]
        );
    }
    let fields = [
        ("amplitude", "amplitude, rad"),
        ("spatial_freq", "spatial_freq, rad per body length"),
        ("phase", "phase lag, rad"),
    ];
    for (name, label) in fields {
        let f = &c["fields"][name];
        if f.is_null() {
            continue;
        }
        let state = if f["enabled"] == true {
            "compliant"
        } else {
            "fixed"
        };
        println!("  {label} ({}, {state})", text(&f["centralization"]));
        println!("    {:>7} {:>7} {:>9} {:>9}", "a", "b", "value", "force");
        for w in f["windows"].as_array().into_iter().flatten() {
            println!(
                "    {:>7} {:>7} {:>9} {:>9}",
                num(&w["a"], 3),
                num(&w["b"], 3),
                num(&w["value"], 4),
                num(&w["force"], 3)
            );
        }
        let count = f["count"].as_u64().unwrap_or(0);
        let shown = f["windows"].as_array().map_or(0, Vec::len) as u64;
        if count > shown {
            println!("    ({} more not reported)", count - shown);
        }
    }
}
