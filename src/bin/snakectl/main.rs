//! snakectl: command-line client of the snaked control socket.
//!
//! Exit status: 0 success, 1 the daemon answered with an error, 2 usage error,
//! 3 cannot reach the daemon (not running, connection lost, no answer).
mod controller;
mod print;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand};
use serde_json::{Map, Value, json};
use snaked::socket::client::{Client, ClientError, Endpoint};

use controller::ControllerCmd;
use print::{
    num, params_inline, pretty, print_params, print_stats, print_status, telemetry_line, text,
};

/// Control a running snaked through its control socket.
#[derive(Parser, Debug)]
#[command(name = "snakectl", version)]
struct Cli {
    /// Unix socket of the daemon [default: $SNAKED_SOCKET, else /run/snaked/snaked.sock or
    /// $XDG_RUNTIME_DIR/snaked.sock, whichever exists].
    #[arg(long, value_name = "PATH", global = true, conflicts_with = "tcp")]
    socket: Option<PathBuf>,
    /// Talk to the daemon's TCP listener instead (needs its token: --token-file).
    #[arg(long, value_name = "HOST:PORT", global = true)]
    tcp: Option<String>,
    /// The daemon's TCP token file (control.tcp_token_file) [default: $SNAKED_TOKEN_FILE].
    #[arg(long, value_name = "PATH", global = true, requires = "tcp")]
    token_file: Option<PathBuf>,
    /// Print the daemon's raw JSON result instead of text.
    #[arg(long, global = true)]
    json: bool,
    /// Seconds to wait for an answer.
    #[arg(long, value_name = "S", default_value_t = 5.0, global = true)]
    timeout: f64,
    /// Take the drive from whoever holds it before the command (one operator drives at
    /// a time: a driving command is refused while another client drives).
    #[arg(long, global = true)]
    take_over: bool,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Mode, gait, loop time, counters and a joint summary.
    Status,
    /// List gaits or switch gait.
    Gait {
        #[command(subcommand)]
        cmd: GaitCmd,
    },
    /// Show or change gait parameters and the blend time.
    Params {
        #[command(subcommand)]
        cmd: ParamsCmd,
    },
    /// List, show or choose each gait's controller.
    Controller {
        #[command(subcommand)]
        cmd: ControllerCmd,
    },
    /// Go that way or there on its own: the navigator picks and changes gaits and
    /// controllers (docs/navigation.md). HEADING: the direction of travel, rad, in the
    /// pose estimate's world; or X,Y: a goal, m, in the position source's world (needs
    /// fixes from `pose.external` or ROS 2); `off` stops it. Any command that drives the
    /// robot stops it too.
    Navigate {
        #[arg(allow_hyphen_values = true, value_name = "HEADING|X,Y|off")]
        heading: String,
        /// The navigator's settings as JSON, e.g. '{"slither_max_s": 60}'.
        #[arg(long)]
        config: Option<String>,
    },
    /// Take the drive from the operator who holds it (one operator drives at a time; a
    /// one-shot command holds it only while it runs, so this frees it).
    TakeOver,
    /// Freeze the joints where they are.
    Hold,
    /// Stop driving the joints.
    Limp,
    /// Emergency stop: limp and latched until `arm`.
    Estop,
    /// Leave hold / limp / e-stop and blend into the active gait.
    Arm,
    /// Loop timing statistics and bus counters.
    Stats,
    /// Live telemetry.
    Watch {
        /// Messages per second (1..=200).
        #[arg(long, default_value_t = 10.0)]
        rate: f64,
        /// Stop after this many messages.
        #[arg(long)]
        count: Option<u64>,
    },
    /// Call any method with raw JSON params; prints the JSON result.
    Call {
        method: String,
        /// A JSON object, e.g. '{"gait":"rolling"}'.
        params: Option<String>,
    },
}

#[derive(Subcommand, Debug)]
enum GaitCmd {
    /// Every gait, the active one marked with `*`.
    List,
    /// Blend into gait NAME.
    Set { name: String },
    /// A controlled stop: the body at rest within S seconds, whatever the blend time.
    Stop {
        #[arg(long, value_name = "S")]
        within: Option<f64>,
    },
    /// The stopped gait moves again, at full speed within S seconds.
    Resume {
        #[arg(long, value_name = "S")]
        within: Option<f64>,
    },
}

#[derive(Subcommand, Debug)]
enum ParamsCmd {
    /// One gait's parameters, or all of them.
    Get { gait: Option<String> },
    /// `params set GAIT key=value ...` or `params set --blend-time S`.
    Set {
        /// Gait blend time, s (0.1..=30).
        #[arg(long, value_name = "S", conflicts_with_all = ["gait", "assignments", "compliance"])]
        blend_time: Option<f64>,
        /// Replaced by `snakectl controller set GAIT NAME` (refused with that hint).
        #[arg(long, value_name = "NAME|JSON", hide = true)]
        compliance: Option<String>,
        #[arg(required_unless_present = "blend_time")]
        gait: Option<String>,
        /// key=value pairs, e.g. amplitude_lat_rad=0.6 temporal_freq_rad_s=1.2
        #[arg(value_name = "KEY=VALUE", allow_hyphen_values = true)]
        assignments: Vec<String>,
    },
}

fn main() -> ExitCode {
    // A closed pipe (`snakectl status | head -c 10`) ends the process quietly, as it does
    // Unix tools, instead of failing every later write (Rust ignores SIGPIPE by default).
    // SAFETY: setting a signal's disposition to the default before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(msg)) => {
            eprintln!("snakectl: {msg}");
            ExitCode::from(2)
        }
        Err(Failure::Client(e @ ClientError::Rpc(_))) => {
            eprintln!("snakectl: snaked refused: {e}");
            ExitCode::from(1)
        }
        Err(Failure::Client(e)) => {
            eprintln!("snakectl: {e}");
            ExitCode::from(3)
        }
    }
}

enum Failure {
    Usage(String),
    Client(ClientError),
}

impl From<ClientError> for Failure {
    fn from(e: ClientError) -> Self {
        Failure::Client(e)
    }
}

fn endpoint(cli: &Cli) -> Endpoint {
    if let Some(addr) = &cli.tcp {
        return Endpoint::Tcp(addr.clone());
    }
    let path = cli
        .socket
        .clone()
        .or_else(|| std::env::var_os("SNAKED_SOCKET").map(PathBuf::from))
        .unwrap_or_else(snaked::socket::paths::client_socket);
    Endpoint::Unix(path)
}

fn run(cli: &Cli) -> Result<(), Failure> {
    if !(cli.timeout.is_finite() && cli.timeout > 0.0) {
        return Err(Failure::Usage("--timeout must be a positive number".into()));
    }
    // Build the request first: usage errors must not need a daemon.
    let (method, params) = request(&cli.cmd)?;
    let mut timeout = Duration::from_secs_f64(cli.timeout);
    if let Cmd::Controller {
        cmd: ControllerCmd::Calibrate { seconds, .. },
    } = &cli.cmd
    {
        // The daemon answers when the calibration is done (up to 1.5x its time + 5 s;
        // 3 cycles of a slow gait are long).
        let wait = seconds.map_or(controller::CALIBRATION_WAIT_S, |s| 1.5 * s + 10.0);
        timeout = timeout.max(Duration::from_secs_f64(wait));
    }
    let token = tcp_token(cli)?;
    let mut client = Client::connect(&endpoint(cli), Some(timeout))?;
    let outcome = converse(cli, &mut client, token, method, params);
    // What the daemon said on its own (e.g. that it serves this connection over its
    // client limit for one stop): the operator sees it, whatever came of the call.
    for n in client.notices() {
        eprintln!("snakectl: snaked says: {} ({})", n.message, n.code);
    }
    outcome
}

/// Authenticate if asked, call the method and print its result.
fn converse(
    cli: &Cli,
    client: &mut Client,
    token: Option<String>,
    method: &str,
    params: Option<Value>,
) -> Result<(), Failure> {
    if let Some(token) = token {
        client.call("auth", Some(json!({ "token": token })))?;
    }
    if cli.take_over {
        client.call("take_over", None)?;
    }
    let result = client.call(method, params)?;
    match &cli.cmd {
        Cmd::Watch { count, .. } => return watch(client, cli.json, *count),
        Cmd::Call { .. } if !cli.json => println!("{}", pretty(&result)),
        _ if cli.json => println!("{result}"),
        cmd => print_human(cmd, &result),
    }
    Ok(())
}

/// The token a TCP connection authenticates with (`None` on the Unix socket).
fn tcp_token(cli: &Cli) -> Result<Option<String>, Failure> {
    if cli.tcp.is_none() {
        return Ok(None);
    }
    let path = cli
        .token_file
        .clone()
        .or_else(|| std::env::var_os("SNAKED_TOKEN_FILE").map(PathBuf::from))
        .ok_or_else(|| {
            Failure::Usage("--tcp needs the daemon's token: --token-file PATH".into())
        })?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Failure::Usage(format!("--token-file {}: {e}", path.display())))?;
    let token = text.lines().next().unwrap_or_default().trim().to_owned();
    if token.is_empty() {
        return Err(Failure::Usage(format!(
            "--token-file {}: empty",
            path.display()
        )));
    }
    Ok(Some(token))
}

/// The method and params a command sends.
fn request(cmd: &Cmd) -> Result<(&str, Option<Value>), Failure> {
    Ok(match cmd {
        Cmd::Status => ("status", None),
        Cmd::Gait { cmd: GaitCmd::List } => ("gait.list", None),
        Cmd::Gait {
            cmd: GaitCmd::Set { name },
        } => ("gait.set", Some(json!({ "gait": name }))),
        Cmd::Gait {
            cmd: GaitCmd::Stop { within },
        } => ("gait.stop", within.map(|s| json!({ "within_s": s }))),
        Cmd::Gait {
            cmd: GaitCmd::Resume { within },
        } => ("gait.resume", within.map(|s| json!({ "within_s": s }))),
        Cmd::TakeOver => ("take_over", None),
        Cmd::Params {
            cmd: ParamsCmd::Get { gait },
        } => ("params.get", gait.as_ref().map(|g| json!({ "gait": g }))),
        Cmd::Params {
            cmd:
                ParamsCmd::Set {
                    blend_time,
                    compliance,
                    gait,
                    assignments,
                },
        } => (
            "params.set",
            Some(params_set(*blend_time, compliance, gait, assignments)?),
        ),
        Cmd::Controller { cmd } => controller::request(cmd).map_err(Failure::Usage)?,
        Cmd::Navigate { heading, config } => ("navigate", Some(navigate(heading, config)?)),
        Cmd::Hold => ("hold", None),
        Cmd::Limp => ("limp", None),
        Cmd::Estop => ("estop", None),
        Cmd::Arm => ("arm", None),
        Cmd::Stats => ("stats", None),
        Cmd::Watch { rate, .. } => ("telemetry.subscribe", Some(json!({ "rate_hz": rate }))),
        Cmd::Call { method, params } => {
            let params = match params {
                None => None,
                Some(text) => Some(
                    serde_json::from_str(text)
                        .map_err(|e| Failure::Usage(format!("params are not valid JSON: {e}")))?,
                ),
            };
            (method.as_str(), params)
        }
    })
}

fn navigate(heading: &str, config: &Option<String>) -> Result<Value, Failure> {
    if heading == "off" {
        if config.is_some() {
            return Err(Failure::Usage("`navigate off` takes no --config".into()));
        }
        return Ok(json!({ "off": true }));
    }
    let number = |t: &str| t.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    let bad = || {
        Failure::Usage(format!(
            "{heading:?}: a heading (rad), a goal X,Y (m) or `off`"
        ))
    };
    let mut p = match heading.split_once(',') {
        Some((x, y)) => {
            json!({ "goal_m": [number(x).ok_or_else(bad)?, number(y).ok_or_else(bad)?] })
        }
        None => json!({ "heading_rad": number(heading).ok_or_else(bad)? }),
    };
    if let Some(c) = config {
        p["config"] = serde_json::from_str(c)
            .map_err(|e| Failure::Usage(format!("--config is not valid JSON: {e}")))?;
    }
    Ok(p)
}

fn params_set(
    blend_time: Option<f64>,
    compliance: &Option<String>,
    gait: &Option<String>,
    assignments: &[String],
) -> Result<Value, Failure> {
    if let Some(t) = blend_time {
        return Ok(json!({ "blend_time_s": t }));
    }
    let mut p = Map::new();
    p.insert("gait".into(), json!(gait));
    if let Some(c) = compliance {
        return Err(Failure::Usage(format!(
            "--compliance was replaced: snakectl controller set {} {c}",
            gait.as_deref().unwrap_or("GAIT")
        )));
    } else if assignments.is_empty() {
        return Err(Failure::Usage(
            "give at least one KEY=VALUE, e.g. amplitude_lat_rad=0.6".into(),
        ));
    }
    for a in assignments {
        let (key, value) = a
            .split_once('=')
            .ok_or_else(|| Failure::Usage(format!("`{a}` is not KEY=VALUE")))?;
        let v: f64 = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| Failure::Usage(format!("`{key}`: `{value}` is not a finite number")))?;
        p.insert(key.trim().to_owned(), json!(v));
    }
    Ok(Value::Object(p))
}

fn watch(client: &mut Client, json_lines: bool, count: Option<u64>) -> Result<(), Failure> {
    let mut seen = 0u64;
    while count.is_none_or(|n| seen < n) {
        let msg = client.next_message()?;
        if msg["method"] != "telemetry" {
            continue;
        }
        seen += 1;
        let p = &msg["params"];
        if json_lines {
            println!("{p}");
        } else {
            println!("{}", telemetry_line(p));
        }
    }
    Ok(())
}

fn print_human(cmd: &Cmd, r: &Value) {
    match cmd {
        Cmd::Status => print_status(r),
        Cmd::Gait { cmd: GaitCmd::List } => {
            for g in r["gaits"].as_array().into_iter().flatten() {
                let mark = if g["active"] == true { "*" } else { " " };
                let line = format!(
                    "{mark} {:<20} {}",
                    text(&g["name"]),
                    params_inline(&g["params"])
                );
                println!("{}", line.trim_end());
            }
        }
        Cmd::Gait {
            cmd: GaitCmd::Stop { .. } | GaitCmd::Resume { .. },
        } => println!(
            "gait: {} within {} s",
            text(&r["motion"]),
            text(&r["within_s"])
        ),
        Cmd::Gait { .. } => println!("gait: blending into {}", text(&r["gait"])),
        Cmd::Params {
            cmd: ParamsCmd::Get { .. },
        } => {
            if let Some(all) = r["gaits"].as_object() {
                for (name, p) in all {
                    println!("{name}");
                    print_params(p, "  ");
                }
            } else {
                println!("{}", text(&r["gait"]));
                print_params(&r["params"], "  ");
            }
            println!("blend_time_s  {}", num(&r["blend_time_s"], 2));
        }
        Cmd::Params { .. } => match r.get("blend_time_s") {
            Some(t) => println!("blend_time_s = {}", num(t, 2)),
            None => {
                println!("{} (applied)", text(&r["gait"]));
                print_params(&r["params"], "  ");
            }
        },
        Cmd::Controller {
            cmd: ControllerCmd::List { .. },
        } => controller::print_list(r),
        Cmd::Controller {
            cmd: ControllerCmd::Calibrate { .. },
        } => controller::print_calibration(r),
        Cmd::Controller {
            cmd: ControllerCmd::Heading { .. },
        } => println!(
            "{} {}: nominal heading {}",
            text(&r["gait"]),
            text(&r["controller"]),
            r["heading_rad"]
        ),
        Cmd::Controller { .. } => controller::print_installed(r),
        Cmd::Navigate { .. } => match (r["navigating"].as_bool(), r["goal_m"].as_array()) {
            (Some(true), Some(g)) if g.len() == 2 => println!(
                "navigating to ({}, {}) m, by position; travelling {} rad now",
                num(&g[0], 3),
                num(&g[1], 3),
                num(&r["travel_rad"], 3)
            ),
            (Some(true), _) => println!("navigating towards {} rad", num(&r["travel_rad"], 3)),
            _ => println!("navigation off"),
        },
        Cmd::Stats => print_stats(r),
        _ => println!("ok"),
    }
}
