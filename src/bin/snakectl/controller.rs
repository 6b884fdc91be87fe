//! snakectl's view of controllers, with no per-gait code: `controller list|get|set|calibrate|heading`
//! and the `controller` part of `status`, printed from the names and units the daemon
//! reports.
use clap::Subcommand;
use serde_json::{Map, Value, json};

use super::print::{num, text};

#[derive(Subcommand, Debug)]
pub enum ControllerCmd {
    /// Every gait's controllers with their presets and signals (or one gait's).
    List { gait: Option<String> },
    /// What each gait runs, with its configuration (or one gait).
    Get { gait: Option<String> },
    /// Run controller NAME (a controller or a preset) for GAIT, e.g.
    /// `controller set slithering a_ws_omega amplitude.gains.stiffness=6`.
    Set {
        gait: String,
        name: String,
        /// A preset of the controller.
        #[arg(long)]
        preset: Option<String>,
        /// Configuration overrides as a JSON object.
        #[arg(long, value_name = "JSON")]
        config: Option<String>,
        /// Configuration overrides, KEY.PATH=VALUE (merged onto --config).
        #[arg(value_name = "KEY=VALUE", allow_hyphen_values = true)]
        assignments: Vec<String>,
    },
    /// Calibrate GAIT's controller (default: the running gait's) on open ground:
    /// directional compliance measures the ground's friction offset over a few gait
    /// cycles. Waits until it is done and prints what was measured.
    Calibrate {
        gait: Option<String>,
        /// Measure this long (default: 3 gait cycles).
        #[arg(long, value_name = "S")]
        seconds: Option<f64>,
        /// Forget the calibration instead.
        #[arg(long, conflicts_with = "seconds")]
        clear: bool,
    },
    /// The nominal heading GAIT's controller steers to (anti-compliant sidewinding, the
    /// slithering controllers):
    /// RAD in the pose estimate's world (yaw 0 where the daemon started), or `here`
    /// for the heading now.
    Heading {
        /// Radians, or `here`.
        #[arg(allow_hyphen_values = true)]
        heading: String,
        /// The gait (default: the running one).
        #[arg(long)]
        gait: Option<String>,
    },
}

/// The method and params of a `controller` command (usage errors as text).
pub fn request(cmd: &ControllerCmd) -> Result<(&'static str, Option<Value>), String> {
    Ok(match cmd {
        ControllerCmd::List { gait } => (
            "controller.list",
            gait.as_ref().map(|g| json!({ "gait": g })),
        ),
        ControllerCmd::Get { gait } => (
            "controller.get",
            gait.as_ref().map(|g| json!({ "gait": g })),
        ),
        ControllerCmd::Set {
            gait,
            name,
            preset,
            config,
            assignments,
        } => {
            let mut p = json!({ "gait": gait, "controller": name });
            if let Some(preset) = preset {
                p["preset"] = json!(preset);
            }
            if config.is_some() || !assignments.is_empty() {
                p["config"] = config_overrides(config.as_deref(), assignments)?;
            }
            ("controller.set", Some(p))
        }
        ControllerCmd::Calibrate {
            gait,
            seconds,
            clear,
        } => {
            let mut p = json!({});
            if let Some(g) = gait {
                p["gait"] = json!(g);
            }
            if let Some(s) = seconds {
                p["seconds"] = json!(s);
            }
            if *clear {
                p["clear"] = json!(true);
            }
            ("controller.calibrate", Some(p))
        }
        ControllerCmd::Heading { heading, gait } => {
            let mut p = json!({});
            if heading == "here" {
                p["here"] = json!(true);
            } else {
                let h: f64 = heading
                    .parse()
                    .ok()
                    .filter(|h: &f64| h.is_finite())
                    .ok_or_else(|| format!("heading {heading:?}: radians or `here`"))?;
                p["heading_rad"] = json!(h);
            }
            if let Some(g) = gait {
                p["gait"] = json!(g);
            }
            ("controller.heading", Some(p))
        }
    })
}

/// `KEY.PATH=VALUE` assignments as a nested JSON object: the value is read as JSON
/// (number, boolean, null, quoted string), else taken as a string.
pub fn config_overrides(base: Option<&str>, assignments: &[String]) -> Result<Value, String> {
    let mut config = match base {
        Some(text) => serde_json::from_str::<Value>(text)
            .map_err(|e| format!("--config is not valid JSON: {e}"))?,
        None => Value::Object(Map::new()),
    };
    if !config.is_object() {
        return Err("--config must be a JSON object".into());
    }
    for a in assignments {
        let (path, value) = a
            .split_once('=')
            .ok_or_else(|| format!("`{a}` is not KEY=VALUE (e.g. amplitude.gains.stiffness=6)"))?;
        let value = value.trim();
        let v = serde_json::from_str::<Value>(value).unwrap_or_else(|_| json!(value));
        let keys: Vec<&str> = path.trim().split('.').collect();
        if keys.iter().any(|k| k.is_empty()) {
            return Err(format!("`{path}`: empty key"));
        }
        let mut slot = &mut config;
        for (i, k) in keys.iter().enumerate() {
            let map = slot
                .as_object_mut()
                .ok_or_else(|| format!("`{path}`: {} is not an object", keys[..i].join(".")))?;
            slot = map.entry(k.to_string()).or_insert_with(|| json!({}));
        }
        *slot = v;
    }
    Ok(config)
}

/// `controller list`: every gait's controllers, presets and report names.
pub fn print_list(r: &Value) {
    for (gait, g) in r["gaits"].as_object().into_iter().flatten() {
        println!("{gait}  (runs {})", label(&g["installed"]));
        for c in g["controllers"].as_array().into_iter().flatten() {
            println!("  {:<22} {}", text(&c["name"]), text(&c["summary"]));
            for p in c["presets"].as_array().into_iter().flatten() {
                let mark = if p["name"] == c["default_preset"] {
                    "*"
                } else {
                    " "
                };
                println!(
                    "    {mark} {:<28} {}",
                    text(&p["name"]),
                    text(&p["summary"])
                );
            }
            let signals: Vec<String> = c["report"]["signals"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|s| format!("{} [{}]", text(&s["name"]), text(&s["unit"])))
                .collect();
            if !signals.is_empty() {
                println!("      signals: {}", signals.join(", "));
            }
        }
    }
}

/// "name/preset (id N)", or the selector's serpenoid when nothing is installed.
fn label(info: &Value) -> String {
    if info.is_null() {
        return "the selector's serpenoid".into();
    }
    format!(
        "{}/{} (id {})",
        text(&info["controller"]),
        text(&info["preset"]),
        info["id"]
    )
}

/// `controller get` / `controller set`: the installed controller(s) and their
/// configuration.
pub fn print_installed(r: &Value) {
    let print_one = |gait: &str, info: &Value| {
        println!("{gait:<20} {}", label(info));
        if let Some(cfg) = info.get("config").filter(|c| !c.is_null()) {
            let flat = flatten(cfg);
            if !flat.is_empty() {
                println!("  {}", flat.join("  "));
            }
        }
    };
    if let Some(all) = r["gaits"].as_object() {
        for (gait, info) in all {
            print_one(gait, info);
        }
    } else {
        print_one(&text(&r["gait"]), &r["controller"]);
    }
}

/// `a.b.c=v` for every leaf of a configuration.
fn flatten(v: &Value) -> Vec<String> {
    fn walk(prefix: &str, v: &Value, out: &mut Vec<String>) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, x, out);
                }
            }
            other => out.push(format!("{prefix}={other}")),
        }
    }
    let mut out = Vec::new();
    walk("", v, &mut out);
    out
}

/// `status`: the active gait's controller, its state and, while it drives, its
/// signals and one table per window field.
pub fn print_status(c: &Value) {
    if c.is_null() || c["controller"].is_null() {
        println!("control   the selector's serpenoid");
        return;
    }
    println!(
        "control   {}/{} ({})  takeovers {}",
        text(&c["controller"]),
        text(&c["preset"]),
        text(&c["state"]),
        c["takeovers"]
    );
    if let Some(signals) = c["signals"].as_object() {
        let line: Vec<String> = signals
            .iter()
            .map(|(k, v)| format!("{k} {}", num(v, 3)))
            .collect();
        println!("  {}", line.join("  "));
    }
    for f in c["fields"].as_array().into_iter().flatten() {
        let state = if f["enabled"] == true {
            "compliant"
        } else {
            "fixed"
        };
        println!(
            "  {} ({}, {state}, {} windows)",
            text(&f["name"]),
            text(&f["centralization"]),
            f["count"]
        );
        let windows = f["windows"].as_array().cloned().unwrap_or_default();
        let Some(first) = windows.first().and_then(Value::as_object) else {
            continue;
        };
        let cols: Vec<&String> = first.keys().filter(|k| *k != "a" && *k != "b").collect();
        let mut head = format!("    {:>7} {:>7}", "a", "b");
        for c in &cols {
            head += &format!(" {c:>9}");
        }
        println!("{head}");
        for w in &windows {
            let mut row = format!("    {:>7} {:>7}", num(&w["a"], 3), num(&w["b"], 3));
            for c in &cols {
                row += &format!(" {:>9}", num(&w[c.as_str()], 4));
            }
            println!("{row}");
        }
        let count = f["count"].as_u64().unwrap_or(0);
        if count > windows.len() as u64 {
            println!("    ({} more not reported)", count - windows.len() as u64);
        }
    }
}

/// How long `controller calibrate` waits without `--seconds`, s (the daemon's longest
/// default calibration is 3 cycles of the slowest gait, capped at 600 s).
pub const CALIBRATION_WAIT_S: f64 = 910.0;

/// `controller calibrate`: what was measured, and the override that keeps it.
pub fn print_calibration(r: &Value) {
    let controller = text(&r["controller"]);
    if r["calibration"] == "none" {
        println!(
            "{} {controller}: calibration cleared (offset 0)",
            text(&r["gait"])
        );
        return;
    }
    println!(
        "{} {controller}: calibrated over {} s",
        text(&r["gait"]),
        num(&r["seconds"], 1)
    );
    // Directional compliance reports its offsets per body section in the fields
    // `sections_lateral` / `sections_dorsal` (column `offset`).
    let fields = r["fields"].as_array().cloned().unwrap_or_default();
    let mut keep = Map::new();
    for (name, key) in [
        ("sections_lateral", "lateral_rad"),
        ("sections_dorsal", "dorsal_rad"),
    ] {
        let Some(f) = fields.iter().find(|f| f["name"] == name) else {
            continue;
        };
        let values: Vec<Value> = f["windows"]
            .as_array()
            .map(|w| w.iter().map(|s| s["offset"].clone()).collect())
            .unwrap_or_default();
        let shown: Vec<String> = values.iter().map(|v| num(v, 4)).collect();
        println!("  offset {key:<12} {} (head to tail)", shown.join("  "));
        let values = values
            .into_iter()
            .map(|v| if v.is_number() { v } else { json!(0.0) });
        keep.insert(key.to_owned(), Value::Array(values.collect()));
    }
    if !keep.is_empty() && !keep.contains_key("dorsal_rad") {
        // A planar controller keeps a dorsal offset per section too (zeros).
        let n = keep["lateral_rad"].as_array().map_or(0, Vec::len);
        keep.insert("dorsal_rad".into(), json!(vec![0.0; n]));
    }
    if !keep.is_empty() {
        println!(
            "  kept until the controller is replaced; to keep it in a new one: --config '{}'",
            json!({ "friction_offset": keep })
        );
    }
}
