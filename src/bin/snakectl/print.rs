//! What snakectl prints: the daemon's answers as text.

use serde_json::Value;
use snaked::socket::api::PATCH_FIELDS;

use super::controller;

pub(crate) fn pretty(v: &Value) -> String {
    serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string())
}

/// A number with `digits` decimals, or "-" for null (non-finite on the daemon's side).
pub(crate) fn num(v: &Value, digits: usize) -> String {
    v.as_f64()
        .map_or_else(|| "-".to_owned(), |x| format!("{x:.digits$}"))
}

pub(crate) fn text(v: &Value) -> String {
    v.as_str().map_or_else(|| v.to_string(), str::to_owned)
}

/// A gait's non-zero params on one line, in the struct's order.
pub(crate) fn params_inline(p: &Value) -> String {
    PATCH_FIELDS
        .iter()
        .filter(|k| p[**k].as_f64().is_some_and(|x| x != 0.0))
        .map(|k| format!("{k}={}", num(&p[*k], 3)))
        .collect::<Vec<_>>()
        .join(" ")
}

pub(crate) fn print_params(p: &Value, indent: &str) {
    let width = PATCH_FIELDS.iter().map(|k| k.len()).max().unwrap_or(0);
    for k in PATCH_FIELDS {
        println!("{indent}{k:<width$}  {:>9}", num(&p[k], 4));
    }
}

pub(crate) fn print_status(r: &Value) {
    let j = &r["joints"];
    let d = &r["daemon"];
    println!("mode      {} ({})", text(&r["mode"]), text(&r["reason"]));
    println!(
        "gait      {}  blend {:.0}%  blend time {} s",
        text(&r["gait"]),
        r["blend_progress"].as_f64().unwrap_or(0.0) * 100.0,
        num(&r["blend_time_s"], 1)
    );
    println!(
        "loop      t {} s  cycle {}  {} Hz {}  bus {}",
        num(&r["t_s"], 3),
        r["cycle"],
        num(&d["loop_rate_hz"], 0),
        text(&d["pacing"]),
        text(&d["bus"])
    );
    println!("modules   {}", r["modules"]);
    println!(
        "requests  {} applied, {} refused",
        r["requests_applied"], r["requests_refused"]
    );
    println!(
        "joints    max |torque| {} N·m  max |velocity| {} rad/s  max tracking error {} rad  \
         max feedback age {} s",
        num(&j["max_abs_torque_nm"], 2),
        num(&j["max_abs_velocity_rad_s"], 2),
        num(&j["max_tracking_error_rad"], 3),
        num(&j["max_feedback_age_s"], 4)
    );
    println!("position  {}", joined(&j["position_rad"], 2));
    println!("torque    {}", joined(&j["torque_nm"], 2));
    controller::print_status(&r["controller"]);
    print_navigator(&r["navigator"], &r["progress"]);
    print_record(&r["record"]);
    println!("daemon    snaked {}", text(&d["version"]));
}

/// The recorder's line: what it does with its file, how big, what it could not keep;
/// why the file failed on the next.
pub(crate) fn print_record(r: &Value) {
    let mut line = format!("record    {}", text(&r["state"]));
    if let Some(path) = r["path"].as_str() {
        line += &format!(" {path}  {} bytes", r["bytes"]);
    }
    if let Some(n) = r["dropped"].as_u64() {
        line += &format!("  dropped {n}");
    }
    if r["lost"].as_u64().is_some_and(|n| n > 0) {
        line += &format!("  lost {}", r["lost"]);
    }
    println!("{line}");
    if let Some(e) = r["error"].as_str() {
        println!("          {e}");
    }
}

/// The navigator's line: what it runs and why, or why it stopped; and the stuck signal.
pub(crate) fn print_navigator(n: &Value, progress: &Value) {
    let stuck = match progress["stuck"].as_bool() {
        Some(true) => "stuck",
        _ => "making way or measuring",
    };
    if n["active"] == true {
        println!(
            "navigate  towards {} rad: {} ({}), {} switches; {stuck}",
            num(&n["travel_rad"], 3),
            text(&n["choice"]),
            text(&n["why"]),
            n["switches"]
        );
    } else if !n["stopped"].is_null() {
        println!("navigate  off (stopped: {}); {stuck}", text(&n["stopped"]));
    } else {
        println!("navigate  off; {stuck}");
    }
}

pub(crate) fn joined(arr: &Value, digits: usize) -> String {
    arr.as_array()
        .into_iter()
        .flatten()
        .map(|v| format!("{:>w$}", num(v, digits), w = digits + 4))
        .collect::<Vec<_>>()
        .join(" ")
}

pub(crate) fn print_stats(r: &Value) {
    let l = &r["loop"];
    println!(
        "cycles {}  overruns {}  skipped periods {}  late feedback {}",
        r["cycles"], l["overruns"], l["skipped_periods"], l["late_feedback"]
    );
    println!();
    let cols = ["count", "mean", "min", "p50", "p99", "p99.9", "max"];
    let keys = [
        "count", "mean_us", "min_us", "p50_us", "p99_us", "p999_us", "max_us",
    ];
    print!("{:<14}", "µs");
    for c in cols {
        print!("{c:>10}");
    }
    println!();
    for (label, key) in [
        ("wake-up", "wakeup_latency"),
        ("period error", "period_error"),
        ("compute", "compute"),
        ("feedback age", "feedback_age"),
    ] {
        print!("{label:<14}");
        for k in keys {
            let v = &l[key][k];
            let cell = if k == "count" {
                v.to_string()
            } else {
                num(v, 1)
            };
            print!("{cell:>10}");
        }
        println!();
    }
    println!();
    println!("bus");
    // The counters every bus keeps, then the bus's own (`detail`), one per line.
    let bus = r["bus"].as_object().cloned().unwrap_or_default();
    let mut rows: Vec<(String, Value)> = Vec::new();
    for (k, v) in bus {
        match v {
            Value::Object(detail) => rows.extend(detail),
            v => rows.push((k, v)),
        }
    }
    let width = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in &rows {
        println!("  {k:<width$}  {v:>12}");
    }
    println!();
    print_record(&r["record"]);
}

pub(crate) fn telemetry_line(p: &Value) -> String {
    let joints = p["joints"].as_array().cloned().unwrap_or_default();
    let max_torque = joints
        .iter()
        .filter_map(|j| j["torque_nm"].as_f64())
        .fold(0.0f64, |m, t| m.max(t.abs()));
    let positions: Vec<String> = joints
        .iter()
        .map(|j| format!("{:>6}", num(&j["position_rad"], 2)))
        .collect();
    format!(
        "t {:>10} s  cycle {:>9}  {:<8} {:<20} blend {:>3.0}%  max|τ| {:>5.2} N·m  θ {}",
        num(&p["t_s"], 3),
        p["cycle"],
        text(&p["mode"]),
        text(&p["gait"]),
        p["blend_progress"].as_f64().unwrap_or(0.0) * 100.0,
        max_torque,
        positions.join(" ")
    )
}
