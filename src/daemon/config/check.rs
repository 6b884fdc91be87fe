//! The configuration's checks: every key's range, the checks between keys, and what the
//! keys name (targets, the world file, each gait's parameters and controller), so that
//! `snaked --check-config` finds everything that would stop the daemon later.
use std::path::Path;

use super::{Config, ConfigFileError, LookupBy, parse_mac};
use crate::gait::GaitKind;
use crate::num::Num;

impl Config {
    /// The default gait parameters with `[gait.params.*]` applied, every gait checked
    /// for this body's module length (as the daemon checks the table when it starts).
    pub fn gait_table(&self, path: &Path) -> Result<crate::gait::GaitTable, ConfigFileError> {
        let l = self.body.module_length_m;
        let mut table = crate::gait::GaitTable::default();
        let mut kinds: Vec<_> = self.gait.params.keys().copied().collect();
        kinds.sort_by_key(|k| k.index());
        for kind in kinds {
            let p = table
                .get(kind)
                .patched_for(kind, &self.gait.params[&kind], l)
                .map_err(|source| ConfigFileError::GaitParams {
                    path: path.to_owned(),
                    gait: kind.name(),
                    source,
                })?;
            *table.get_mut(kind) = p;
        }
        // The gaits left at their defaults too: the defaults suit the SEA module, and a
        // longer module can take one out of range (rolling_helix's from about 0.1 m).
        table
            .validate_for(l)
            .map_err(|(kind, source)| ConfigFileError::GaitParams {
                path: path.to_owned(),
                gait: kind.name(),
                source,
            })?;
        Ok(table)
    }

    /// Checks between keys, and of what the keys name (targets, the world file), so
    /// that `--check-config` finds everything that would stop the daemon later.
    fn cross_checks(&self, path: &Path) -> Result<(), ConfigFileError> {
        let bad = |key: &'static str, value: String, why: String| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value,
            why,
        };
        let half_period_s = 0.5 / self.loop_.rate_hz;
        if !(self.loop_.busy_wait_s >= 0.0 && self.loop_.busy_wait_s < half_period_s) {
            return Err(bad(
                "loop.busy_wait_s",
                Num(self.loop_.busy_wait_s).to_string(),
                format!(
                    "must be at least 0 and less than half a period ({} s at \
                     loop.rate_hz = {}): the loop spins that long every cycle",
                    Num(half_period_s),
                    Num(self.loop_.rate_hz)
                ),
            ));
        }
        let net = &self.network;
        // A module drops a command older than its lifetime: it must outlive at least two
        // of the loop's command periods and two feedback periods, or the joints go limp
        // between commands.
        let period_s = (1.0 / self.loop_.rate_hz).max(1.0 / net.feedback_rate_hz);
        if net.command_lifetime_s < 2.0 * period_s {
            return Err(bad(
                "network.command_lifetime_s",
                Num(net.command_lifetime_s).to_string(),
                format!(
                    "must be at least two periods of the loop and of the feedback \
                     ({:.4} s at loop.rate_hz = {} and network.feedback_rate_hz = {}), \
                     or the modules go limp between commands",
                    2.0 * period_s,
                    self.loop_.rate_hz,
                    net.feedback_rate_hz
                ),
            ));
        }
        let token = &self.control.tcp_token_file;
        if self.control.tcp_port != 0 && token.as_os_str().is_empty() {
            return Err(bad(
                "control.tcp_token_file",
                "\"\"".into(),
                "TCP needs a token file (readable by the operators' group, not by every user): \
                 without one any local user could drive the robot"
                    .into(),
            ));
        }
        if self.control.tcp_port != 0 {
            // The daemon reads it when it starts: whatever it would refuse, refuse now.
            crate::daemon::token::read_token(token).map_err(|e| {
                bad(
                    "control.tcp_token_file",
                    token.display().to_string(),
                    e.to_string(),
                )
            })?;
        }
        self.foxglove_checks(path)?;
        self.bus_checks(path)?;
        self.ros2_checks(path)?;
        self.pose_checks(path)?;
        let cap = crate::rt::control_loop::MAX_REQUESTS_PER_CYCLE;
        if self.control.channel_capacity < cap {
            return Err(bad(
                "control.channel_capacity",
                self.control.channel_capacity.to_string(),
                format!(
                    "must be at least the loop's {cap} requests per cycle: a smaller queue could \
                     not hold one cycle's worth"
                ),
            ));
        }
        if !net.key_file.as_os_str().is_empty() {
            crate::protocol::Key::load(&net.key_file).map_err(|e| {
                bad(
                    "network.key_file",
                    net.key_file.display().to_string(),
                    e.to_string(),
                )
            })?;
        }
        for t in &net.targets {
            if let Err(e) = crate::bus::udp::parse_targets(t) {
                return Err(bad("network.targets", format!("{t:?}"), e.to_string()));
            }
        }
        let world = &self.emulator.world;
        if !world.as_os_str().is_empty() {
            let scenario = crate::emu::world::scenario::WorldScenario::load(world)
                .map_err(|e| bad("emulator.world", world.display().to_string(), e.to_string()))?;
            scenario
                .generate_trial(self.emulator.modules, self.emulator.world_trial)
                .map_err(|e| bad("emulator.world", world.display().to_string(), e.to_string()))?;
        }
        Ok(())
    }

    /// `[foxglove]` against the rest, and what the daemon reads for it when it starts: the
    /// token file, the teleop settings, a port of its own, a teleop topic that is none of
    /// the daemon's own channels, and the connections it lets in below the file limit.
    fn foxglove_checks(&self, path: &Path) -> Result<(), ConfigFileError> {
        let bad = |key: &'static str, value: String, why: String| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value,
            why,
        };
        let fx = &self.foxglove;
        if fx.enabled && fx.operate {
            fx.token().map_err(|e| {
                bad(
                    "foxglove.token_file",
                    fx.token_file.display().to_string(),
                    e.to_string(),
                )
            })?;
        }
        fx.teleop()
            .check()
            .map_err(|e| bad("foxglove", "teleop settings".into(), e))?;
        // The recorder's channels, and the live view's and the station's own.
        use crate::live::viewers::TOPIC as VIEWERS;
        use crate::station::actions::TOPIC as OPERATOR;
        let recorder = crate::record::Topic::ALL.iter().map(|t| t.name());
        if let Some(own) = recorder
            .chain([VIEWERS, OPERATOR])
            .find(|t| *t == fx.teleop_topic)
        {
            return Err(bad(
                "foxglove.teleop_topic",
                format!("{own:?}"),
                "one of the daemon's own channels (docs/recording.md, \"Channels\"): clients \
                 would publish twists on the topic it publishes on"
                    .into(),
            ));
        }
        let tcp = self.control.tcp_port;
        if fx.enabled && tcp != 0 && fx.port == tcp {
            return Err(bad(
                "foxglove.port",
                fx.port.to_string(),
                "the control socket's TCP port (control.tcp_port) too: one of them could not \
                 listen"
                    .into(),
            ));
        }
        // What the daemon raises its soft limit to when it starts (`daemon::files`).
        if let Ok(limit) = crate::daemon::files::file_limit() {
            self.check_file_limit(path, limit.hard)?;
        }
        Ok(())
    }

    /// Each gait's controller: `[gait.controllers.*]` or `open_loop`.
    pub fn controller_selection(&self, gait: GaitKind) -> crate::controller_interface::Selection {
        self.gait
            .controllers
            .get(&gait)
            .cloned()
            .unwrap_or_else(|| crate::controller_interface::Selection::named("open_loop"))
    }

    /// Builds every configured controller once (for a body of `emulator.modules`
    /// modules) so a bad one is named before the daemon starts.
    fn check_gaits(&self, path: &Path) -> Result<(), ConfigFileError> {
        let table = self.gait_table(path)?;
        let layout = crate::gait::BodyLayout::alternating(
            self.emulator.modules.max(2),
            self.body.first_joint_plane,
            self.body.module_length_m,
        );
        for gait in GaitKind::ALL {
            let ctx = crate::controller_interface::BuildContext {
                gait,
                layout: &layout,
                params: table.get(gait),
            };
            let sel = self.controller_selection(gait);
            crate::controller_interface::registry::build(crate::controllers::REGISTRY, &sel, &ctx)
                .map_err(|source| ConfigFileError::Controller {
                    path: path.to_owned(),
                    gait: gait.name(),
                    source,
                })?;
        }
        Ok(())
    }

    pub fn validate(&self, path: &Path) -> Result<(), ConfigFileError> {
        let bad = |key: &'static str, value: String, why: &str| ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value,
            why: why.to_owned(),
        };
        // Exact: a bound accepts up to the value it prints, which reads back as itself.
        let range = |key: &'static str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                let why = format!("must be in [{}, {}]", Num(lo), Num(hi));
                Err(bad(key, Num(v).to_string(), &why))
            }
        };
        range("loop.rate_hz", self.loop_.rate_hz, 1.0, 10_000.0)?;
        let fx = &self.foxglove;
        range("foxglove.teleop_timeout_s", fx.teleop_timeout_s, 0.05, 10.0)?;
        let (lo, hi) = crate::rt::gait_clock::STOP_TIME_RANGE_S;
        range("foxglove.teleop_stop_s", fx.teleop_stop_s, lo, hi)?;
        range(
            "foxglove.teleop_hold_after_s",
            fx.teleop_hold_after_s,
            0.05,
            60.0,
        )?;
        range(
            "foxglove.teleop_speed_rad_s",
            fx.teleop_speed_rad_s,
            0.01,
            10.0,
        )?;
        range(
            "foxglove.teleop_max_speed_rad_s",
            fx.teleop_max_speed_rad_s,
            0.01,
            10.0,
        )?;
        if !fx.teleop_topic.starts_with('/') {
            let why = "a channel's topic, starting with '/'";
            return Err(bad(
                "foxglove.teleop_topic",
                format!("{:?}", fx.teleop_topic),
                why,
            ));
        }
        range(
            "foxglove.max_connections",
            fx.max_connections as f64,
            1.0,
            4096.0,
        )?;
        range(
            "foxglove.max_connections_per_address",
            fx.max_connections_per_address as f64,
            1.0,
            fx.max_connections as f64,
        )?;
        range(
            "foxglove.handshake_timeout_s",
            fx.handshake_timeout_s,
            0.1,
            60.0,
        )?;
        // Operating is a privilege: off loopback, only with a token clients must give.
        if fx.operate && !fx.host.is_loopback() && fx.token_file.as_os_str().is_empty() {
            let why = "operating from Foxglove on an address other than loopback needs \
                       foxglove.token_file (clients give the token to the `auth` service): \
                       without it anyone on the network could drive the robot";
            return Err(bad("foxglove.operate", "true".into(), why));
        }
        range(
            "loop.lockstep_timeout_s",
            self.loop_.lockstep_timeout_s,
            0.001,
            60.0,
        )?;
        range(
            "loop.sched_fifo_priority",
            self.loop_.sched_fifo_priority as f64,
            0.0,
            99.0,
        )?;
        range("loop.timer_slack_s", self.loop_.timer_slack_s, 1e-9, 1e-3)?;
        if let Some(s) = self.loop_.cpu_dma_latency_s {
            range("loop.cpu_dma_latency_s", s, 0.0, 0.1)?;
        }
        range("body.module_length_m", self.body.module_length_m, 0.01, 1.0)?;
        range(
            "network.discovery_timeout_s",
            self.network.discovery_timeout_s,
            0.01,
            60.0,
        )?;
        range(
            "network.feedback_rate_hz",
            self.network.feedback_rate_hz,
            1.0,
            2000.0,
        )?;
        range(
            "network.command_lifetime_s",
            self.network.command_lifetime_s,
            0.001,
            10.0,
        )?;
        range(
            "failsafe.feedback_timeout_s",
            self.failsafe.feedback_timeout_s,
            0.001,
            10.0,
        )?;
        // docs/failsafe.md: at least 1 ms (0 would go limp at a fault's first cycle and
        // count a fault cleared by one healthy cycle).
        range(
            "failsafe.limp_after_s",
            self.failsafe.limp_after_s,
            0.001,
            60.0,
        )?;
        range(
            "failsafe.shutdown_hold_s",
            self.failsafe.shutdown_hold_s,
            0.0,
            10.0,
        )?;
        range("gait.blend_time_s", self.gait.blend_time_s, 0.1, 30.0)?;
        range(
            "gait.max_joint_speed_rad_s",
            self.gait.max_joint_speed_rad_s,
            0.1,
            crate::module::MODULE_MAX_SPEED_RAD_S,
        )?;
        range(
            "control.max_line_bytes",
            self.control.max_line_bytes as f64,
            256.0,
            16.0 * 1024.0 * 1024.0,
        )?;
        range(
            "control.max_clients",
            self.control.max_clients as f64,
            1.0,
            4096.0,
        )?;
        range(
            "control.channel_capacity",
            self.control.channel_capacity as f64,
            1.0,
            65536.0,
        )?;
        range(
            "control.ack_timeout_s",
            self.control.ack_timeout_s,
            0.01,
            60.0,
        )?;
        range(
            "control.idle_timeout_s",
            self.control.idle_timeout_s,
            0.0,
            86400.0,
        )?;
        range(
            "control.driver_timeout_s",
            self.control.driver_timeout_s,
            0.1,
            3600.0,
        )?;
        range("emulator.modules", self.emulator.modules as f64, 2.0, 64.0)?;
        range("record.max_mb", self.record.max_mb, 0.0, 1e7)?;
        range(
            "record.max_duration_s",
            self.record.max_duration_s,
            0.0,
            1e7,
        )?;
        range(
            "record.chunk_duration_s",
            self.record.chunk_duration_s,
            0.05,
            60.0,
        )?;
        range(
            "record.ring_capacity",
            self.record.ring_capacity as f64,
            16.0,
            65536.0,
        )?;
        range(
            "record.scene_rate_hz",
            self.record.scene_rate_hz,
            1.0,
            1000.0,
        )?;
        // What the recorder refuses when it starts (its size cap's minimum, the path).
        self.record.check(path)?;
        self.cross_checks(path)?;
        if let Some(old) = &self.gait.slithering_controller {
            return Err(bad(
                "gait.slithering_controller",
                format!("{old:?}"),
                &format!(
                    "replaced by a table per gait: [gait.controllers.slithering] controller = \
                     {old:?} (docs/control-socket.md)"
                ),
            ));
        }
        self.check_gaits(path)?;
        if self.network.targets.is_empty() {
            return Err(bad(
                "network.targets",
                "[]".into(),
                "needs at least one target",
            ));
        }
        match self.network.lookup {
            LookupBy::Names if self.network.names.is_empty() => {
                return Err(bad(
                    "network.names",
                    "[]".into(),
                    "lookup = \"names\" needs names",
                ));
            }
            LookupBy::Macs if self.network.macs.is_empty() => {
                return Err(bad(
                    "network.macs",
                    "[]".into(),
                    "lookup = \"macs\" needs MACs",
                ));
            }
            _ => {}
        }
        for m in &self.network.macs {
            parse_mac(m).ok_or_else(|| {
                bad(
                    "network.macs",
                    m.clone(),
                    "not a MAC like 02:53:4e:00:00:01",
                )
            })?;
        }
        Ok(())
    }
}
