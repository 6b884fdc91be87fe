//! `snaked.toml`: every key has a documented default (see `config/snaked.toml`,
//! which a test keeps identical to these defaults); unknown keys are rejected.
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::gait::{GaitKind, Plane};

pub use super::config_bus::{BusChoice, BusSection, HebiConfig, HebiGains};
pub use super::config_pose::PoseConfig;
pub use super::config_record::{FoxgloveConfig, RecordConfig};
pub use super::config_ros2::Ros2Config;

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    #[serde(rename = "loop")]
    pub loop_: LoopConfig,
    pub body: BodyConfig,
    pub bus: BusSection,
    pub network: NetworkConfig,
    pub hebi: HebiConfig,
    pub failsafe: FailsafeSection,
    pub gait: GaitSection,
    pub control: ControlConfig,
    pub emulator: EmulatorConfig,
    pub record: RecordConfig,
    pub foxglove: FoxgloveConfig,
    pub ros2: Ros2Config,
    pub pose: PoseConfig,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pacing {
    Realtime,
    Lockstep,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoopConfig {
    pub rate_hz: f64,
    pub pacing: Pacing,
    pub lockstep_timeout_s: f64,
    /// SCHED_FIFO priority of the loop thread, 1..=99; 0 leaves the scheduler alone.
    pub sched_fifo_priority: i32,
    /// CPU to pin the loop thread to (the daemon's other threads then keep off it);
    /// absent = no pinning.
    pub cpu: Option<usize>,
    pub lock_memory: bool,
    /// Real time: wake this long before each deadline and spin until it, s (0: sleep
    /// until the deadline). Less than half a period.
    pub busy_wait_s: f64,
    /// The loop thread's timer slack, s (1 ns .. 1 ms): how late the kernel may end its
    /// sleeps to batch wake-ups (50 µs by default for normal threads; ignored for
    /// SCHED_FIFO threads by recent kernels).
    pub timer_slack_s: f64,
    /// Keep every CPU's wake-up latency within this while the daemon runs
    /// (`/dev/cpu_dma_latency`, needs root), s; 0 keeps idle CPUs polling. Absent: 0
    /// when the loop runs under SCHED_FIFO (as cyclictest does), no limit otherwise;
    /// see [`LoopConfig::cpu_latency_limit_s`].
    pub cpu_dma_latency_s: Option<f64>,
    /// Send the gait's joint velocities as feed-forward with the positions.
    pub velocity_feedforward: bool,
}

impl LoopConfig {
    /// The wake-up latency limit the daemon holds, s, if any. A loop under SCHED_FIFO
    /// asked for real time, and an idle CPU that halts (rather than polls) wakes it tens
    /// of µs late on a quiet machine (docs/measurements/loop-timing.md, "Wake-up
    /// latency at the machine's floor"), so it holds 0 unless the key says otherwise.
    pub fn cpu_latency_limit_s(&self) -> Option<f64> {
        self.cpu_dma_latency_s
            .or((self.sched_fifo_priority > 0).then_some(0.0))
    }
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            pacing: Pacing::Realtime,
            lockstep_timeout_s: 1.0,
            sched_fifo_priority: 0,
            cpu: None,
            lock_memory: false,
            busy_wait_s: 0.0,
            timer_slack_s: 1e-9,
            cpu_dma_latency_s: None,
            velocity_feedforward: true,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BodyConfig {
    pub first_joint_plane: Plane,
    pub module_length_m: f64,
}

impl Default for BodyConfig {
    fn default() -> Self {
        Self {
            first_joint_plane: Plane::Lateral,
            module_length_m: crate::module::MODULE_LENGTH_M,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LookupBy {
    All,
    Family,
    Names,
    Macs,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetworkConfig {
    /// Local address of the loop's socket; absent = loopback when every target is, else 0.0.0.0:0.
    pub bind: Option<SocketAddr>,
    /// Where lookups go: "ip:port", "ip:first-last" port ranges, or broadcast addresses.
    pub targets: Vec<String>,
    pub lookup: LookupBy,
    pub family: String,
    /// Module names head first (lookup = "names").
    pub names: Vec<String>,
    /// MAC addresses "02:53:4e:00:00:01" head first (lookup = "macs").
    pub macs: Vec<String>,
    /// Modules the group must have; 0 accepts whatever answers.
    pub expected_modules: usize,
    pub discovery_timeout_s: f64,
    pub feedback_rate_hz: f64,
    pub command_lifetime_s: f64,
    /// The robot's network key (64 hex digits, not readable by every user); empty =
    /// an open network (docs/protocol.md §4).
    pub key_file: PathBuf,
}

impl Default for NetworkConfig {
    fn default() -> Self {
        Self {
            bind: None,
            targets: vec!["127.0.0.1:7000-7017".into()],
            lookup: LookupBy::Family,
            family: "SEA".into(),
            names: vec![],
            macs: vec![],
            expected_modules: 18,
            discovery_timeout_s: 2.0,
            feedback_rate_hz: 1000.0,
            command_lifetime_s: 0.05,
            key_file: PathBuf::new(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailsafeSection {
    pub feedback_timeout_s: f64,
    pub limp_after_s: f64,
    pub auto_resume: bool,
    pub shutdown_hold_s: f64,
}

impl Default for FailsafeSection {
    fn default() -> Self {
        Self {
            feedback_timeout_s: 0.05,
            limp_after_s: 0.5,
            auto_resume: false,
            shutdown_hold_s: 0.2,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMode {
    /// Run the initial gait as soon as feedback is healthy.
    Run,
    /// Hold the measured pose until the operator arms or sets a gait.
    Hold,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GaitSection {
    pub initial: GaitKind,
    pub start: StartMode,
    pub blend_time_s: f64,
    pub max_joint_speed_rad_s: f64,
    /// Per-gait parameter overrides, e.g. `[gait.params.sidewinding]`.
    pub params: std::collections::HashMap<GaitKind, crate::gait::ParamPatch>,
    /// Per-gait controllers, e.g. `[gait.controllers.slithering] controller =
    /// "a_ws_omega"`; a gait not named runs `open_loop`.
    pub controllers: std::collections::HashMap<GaitKind, crate::controller_interface::Selection>,
    /// Replaced by `controllers`; kept only to say so.
    #[serde(default)]
    pub slithering_controller: Option<String>,
}

impl Default for GaitSection {
    fn default() -> Self {
        Self {
            initial: GaitKind::Sidewinding,
            start: StartMode::Hold,
            blend_time_s: 2.0,
            max_joint_speed_rad_s: crate::module::MODULE_MAX_SPEED_RAD_S,
            params: Default::default(),
            controllers: Default::default(),
            slithering_controller: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlConfig {
    /// Unix socket path; "auto" = see `socket::paths`; empty = no Unix socket.
    pub socket: PathBuf,
    /// TCP port on 127.0.0.1; 0 = no TCP listener.
    pub tcp_port: u16,
    pub max_line_bytes: usize,
    pub max_clients: usize,
    pub channel_capacity: usize,
    pub ack_timeout_s: f64,
    /// Close a connection with no request and no telemetry stream for this long, s;
    /// 0 = never.
    pub idle_timeout_s: f64,
    /// The token TCP clients must present (`auth`): a file readable by the operators'
    /// group, not by every user. Required when `tcp_port` is set.
    pub tcp_token_file: PathBuf,
    /// One operator drives at a time: a driver that sends no driving request for this
    /// long no longer holds the drive, s (docs/control-socket.md, "One operator drives").
    pub driver_timeout_s: f64,
}

impl Default for ControlConfig {
    fn default() -> Self {
        Self {
            socket: PathBuf::from("auto"),
            tcp_port: 0,
            max_line_bytes: 65536,
            max_clients: 64,
            channel_capacity: 64,
            ack_timeout_s: 1.0,
            idle_timeout_s: 300.0,
            tcp_token_file: PathBuf::new(),
            driver_timeout_s: crate::operator::driver::DEFAULT_DRIVER_TIMEOUT.as_secs_f64(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EmulatorConfig {
    /// Modules of the in-process emulator (`--emulated`).
    pub modules: usize,
    pub seed: u64,
    /// World scenario for the rigid-body physics plant; empty = the joint-space plant
    /// (no world, no locomotion).
    pub world: PathBuf,
    /// Which start of the world's `[start.random]` to use.
    pub world_trial: u64,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        Self {
            modules: 18,
            seed: 1,
            world: PathBuf::new(),
            world_trial: 0,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ConfigFileError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{path}: {key} = {value}: {why}")]
    Invalid {
        path: PathBuf,
        key: &'static str,
        value: String,
        why: String,
    },
    #[error("{path}: [gait.params.{gait}]: {source}")]
    GaitParams {
        path: PathBuf,
        gait: &'static str,
        source: crate::gait::ParamError,
    },
    #[error("{path}: [gait.controllers.{gait}]: {source}")]
    Controller {
        path: PathBuf,
        gait: &'static str,
        source: crate::controller_interface::ConfigError,
    },
}

impl Config {
    pub fn load(path: &Path) -> Result<Config, ConfigFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigFileError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parse and validate; `path` only labels the messages.
    pub fn parse(text: &str, path: &Path) -> Result<Config, ConfigFileError> {
        let cfg: Config = toml::from_str(text).map_err(|e| ConfigFileError::Parse {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        cfg.validate(path)?;
        Ok(cfg)
    }
}

/// Parse "02:53:4e:00:00:01".
pub fn parse_mac(s: &str) -> Option<[u8; 6]> {
    let mut out = [0u8; 6];
    let mut parts = s.split(':');
    for b in &mut out {
        *b = u8::from_str_radix(parts.next()?, 16).ok()?;
    }
    parts.next().is_none().then_some(out)
}

mod check;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_example_equals_the_defaults() {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/config/snaked.toml"));
        let cfg = Config::load(path).expect("config/snaked.toml parses");
        assert_eq!(
            cfg,
            Config::default(),
            "config/snaked.toml must document the defaults"
        );
    }

    #[test]
    fn a_real_time_loop_holds_the_cpus_awake_unless_told_otherwise() {
        let parse = |t: &str| Config::parse(t, Path::new("x.toml")).unwrap().loop_;
        assert_eq!(parse("").cpu_latency_limit_s(), None);
        let fifo = parse("[loop]\nsched_fifo_priority = 80\n");
        assert_eq!(fifo.cpu_latency_limit_s(), Some(0.0));
        let deep = parse("[loop]\nsched_fifo_priority = 80\ncpu_dma_latency_s = 0.1\n");
        assert_eq!(deep.cpu_latency_limit_s(), Some(0.1));
        let asked = parse("[loop]\ncpu_dma_latency_s = 0.00002\n");
        assert_eq!(asked.cpu_latency_limit_s(), Some(0.00002));
    }

    #[test]
    fn the_recording_chunk_duration_is_bounded() {
        for bad in ["0.0", "0.01", "61.0", "nan"] {
            let text = format!("[record]\nchunk_duration_s = {bad}\n");
            let err = Config::parse(&text, Path::new("x.toml")).unwrap_err();
            assert!(err.to_string().contains("record.chunk_duration_s"), "{err}");
        }
        assert!(Config::parse("[record]\nchunk_duration_s = 0.05\n", Path::new("x")).is_ok());
    }

    #[test]
    fn unknown_keys_are_rejected_with_their_name() {
        let err =
            Config::parse("[loop]\nrate_hz = 500\nspeed = 3\n", Path::new("x.toml")).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("x.toml") && msg.contains("speed"), "{msg}");
    }

    #[test]
    fn out_of_range_values_are_rejected_with_key_and_range() {
        let err = Config::parse("[loop]\nrate_hz = 0.0\n", Path::new("x.toml")).unwrap_err();
        assert!(err.to_string().contains("loop.rate_hz"), "{err}");
        let err = Config::parse("[gait]\nblend_time_s = nan\n", Path::new("x.toml")).unwrap_err();
        assert!(err.to_string().contains("gait.blend_time_s"), "{err}");
    }

    /// Issue 25: docs/failsafe.md's 1 ms minimum holds in the file too, a bound refuses
    /// the very next double beyond it, and a message prints a huge value readably.
    #[test]
    fn bounds_are_exact_documented_and_readable() {
        let parse = |text: &str| Config::parse(text, Path::new("x.toml"));
        let err = parse("[failsafe]\nlimp_after_s = 0.0\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("failsafe.limp_after_s"), "{err}");
        parse("[failsafe]\nlimp_after_s = 0.001\n").unwrap();
        for (key, lo, hi) in [
            ("failsafe.limp_after_s", 0.001f64, 60.0f64),
            ("failsafe.feedback_timeout_s", 0.001, 10.0),
            ("gait.blend_time_s", 0.1, 30.0),
            ("control.ack_timeout_s", 0.01, 60.0),
        ] {
            let (section, name) = key.split_once('.').unwrap();
            for (v, ok) in [
                (lo, true),
                (hi, true),
                (lo.next_down(), false),
                (hi.next_up(), false),
            ] {
                // `{:?}` of an f64 is its shortest round-trip form: the very value.
                let text = format!("[{section}]\n{name} = {v:?}\n");
                assert_eq!(parse(&text).is_ok(), ok, "{text}");
            }
        }
        let err = parse("[failsafe]\nlimp_after_s = 1e308\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("1e308"), "{err}");
        assert!(err.len() < 160, "no 309-digit numbers: {err}");
    }

    /// Issue 25: what the daemon refuses when it starts, `--check-config` refuses too: a
    /// TCP token file every user can read.
    #[test]
    fn a_token_file_every_user_can_read_is_refused_by_the_check() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let token = dir.path().join("token");
        std::fs::write(&token, "s3cret-s3cret-s3cret\n").unwrap();
        let text = format!(
            "[control]\ntcp_port = 7878\ntcp_token_file = \"{}\"\n",
            token.display()
        );
        std::fs::set_permissions(&token, std::fs::Permissions::from_mode(0o640)).unwrap();
        Config::parse(&text, Path::new("x.toml")).unwrap();
        std::fs::set_permissions(&token, std::fs::Permissions::from_mode(0o644)).unwrap();
        let err = Config::parse(&text, Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("control.tcp_token_file") && err.contains("readable by every user"),
            "{err}"
        );
        std::fs::write(&token, "\n").unwrap();
        std::fs::set_permissions(&token, std::fs::Permissions::from_mode(0o600)).unwrap();
        let err = Config::parse(&text, Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("empty"), "{err}");
    }

    #[test]
    fn wrong_types_and_bad_gait_names_are_rejected() {
        assert!(Config::parse("[loop]\nrate_hz = \"fast\"\n", Path::new("x")).is_err());
        assert!(Config::parse("[gait]\ninitial = \"moonwalk\"\n", Path::new("x")).is_err());
        assert!(
            Config::parse("[gait.params.sidewinding]\nwobble = 1.0\n", Path::new("x")).is_err()
        );
    }

    #[test]
    fn cross_field_and_named_things_are_checked() {
        for (text, needle) in [
            (
                "[network]\nfeedback_rate_hz = 100.0\ncommand_lifetime_s = 0.002\n",
                "network.command_lifetime_s",
            ),
            (
                "[control]\nchannel_capacity = 4\n",
                "control.channel_capacity",
            ),
            (
                "[network]\ntargets = [\"127.0.0.1:7010-7000\"]\n",
                "network.targets",
            ),
            ("[network]\ntargets = [\"nonsense\"]\n", "network.targets"),
            (
                "[emulator]\nworld = \"/no/such/world.toml\"\n",
                "emulator.world",
            ),
            (
                "[gait.params.rolling]\ntaper = 0.5\n",
                "gait.params.rolling",
            ),
            (
                "[gait]\nmax_joint_speed_rad_s = 5.0\n",
                "gait.max_joint_speed_rad_s",
            ),
        ] {
            let msg = Config::parse(text, Path::new("x.toml"))
                .unwrap_err()
                .to_string();
            assert!(
                msg.contains(needle) && msg.contains("x.toml"),
                "{text}: {msg}"
            );
        }
        // At the defaults' rates a 50 ms lifetime is plenty.
        assert!(Config::parse("", Path::new("x")).is_ok());
    }

    #[test]
    fn controllers_are_built_and_named_in_errors() {
        let cfg = Config::parse(
            "[gait.controllers.slithering]\ncontroller = \"a_ws_omega\"\n\
             config = { amplitude = { gains = { stiffness = 6.0 } } }\n",
            Path::new("x"),
        )
        .unwrap();
        let sel = cfg.controller_selection(GaitKind::Slithering);
        assert_eq!(sel.controller, "a_ws_omega");
        assert_eq!(
            cfg.controller_selection(GaitKind::Rolling).controller,
            "open_loop"
        );
        for (text, needle) in [
            (
                "[gait.controllers.slithering]\ncontroller = \"fast\"\n",
                "unknown controller `fast`",
            ),
            (
                "[gait.controllers.rolling]\ncontroller = \"cpg\"\n",
                "does not run rolling",
            ),
            (
                "[gait.controllers.slithering]\ncontroller = \"a\"\nconfig = { amplitude = { gains = { bias_force = 1e308 } } }\n",
                "config.amplitude.gains.bias_force",
            ),
            (
                "[gait]\nslithering_controller = \"a\"\n",
                "[gait.controllers.slithering]",
            ),
            (
                "[gait.params.rolling]\namplitude_lat_rad = 9.0\n",
                "gait.params.rolling",
            ),
        ] {
            let msg = Config::parse(text, Path::new("x")).unwrap_err().to_string();
            assert!(msg.contains(needle), "{text}: {msg}");
        }
    }

    /// Found by `fuzz/fuzz_targets/config.rs`: with a longer module the default
    /// rolling_helix parameters are out of the joints' range; the configuration passed
    /// its checks (`snaked --check-config`) and the daemon refused it when it started.
    #[test]
    fn the_gaits_left_at_their_defaults_are_checked_for_the_module_length() {
        let text = "[body]\nmodule_length_m = 0.1\n";
        let msg = Config::parse(text, Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("x.toml") && msg.contains("[gait.params.rolling_helix]"),
            "{msg}"
        );
        // What passes is what the daemon starts with.
        let cfg = Config::parse("[body]\nmodule_length_m = 0.07\n", Path::new("x")).unwrap();
        let table = cfg.gait_table(Path::new("x")).unwrap();
        table.validate_for(cfg.body.module_length_m).unwrap();
    }

    #[test]
    fn macs_parse_strictly() {
        assert_eq!(
            parse_mac("02:53:4e:00:00:0a"),
            Some([2, 0x53, 0x4e, 0, 0, 10])
        );
        assert_eq!(parse_mac("02:53:4e:00:00"), None);
        assert_eq!(parse_mac("02:53:4e:00:00:0a:01"), None);
        let err = Config::parse(
            "[network]\nlookup = \"macs\"\nmacs = [\"zz\"]\n",
            Path::new("x"),
        )
        .unwrap_err();
        assert!(err.to_string().contains("network.macs"));
    }
}
