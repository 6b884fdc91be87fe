//! `snaked.toml`'s `[record]` and `[foxglove]`: the recording, the live view and operating
//! from Foxglove (docs/recording.md); part of [`super::config::Config`].
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::config::ConfigFileError;
use crate::num::Num;
use crate::record::McapOptions;

use super::token::{TokenError, read_token};

/// `[record]`: an MCAP file of every cycle (docs/recording.md).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordConfig {
    /// The file to write; empty = no recording. It must not exist yet; its directory
    /// must. `{time}` in the name is replaced by the start time (s since the Unix epoch).
    pub path: PathBuf,
    /// Stop writing (and finish the file) past this size, MB; 0 = no size cap, else at
    /// least 1 (`record::MIN_MAX_BYTES`).
    pub max_mb: f64,
    /// Stop writing past this much loop time, s; 0 = no duration cap.
    pub max_duration_s: f64,
    /// Write the open chunk whole and sync the file at least this often, s of loop time
    /// (0.05..=60): what a crash or a power loss can lose of the file.
    pub chunk_duration_s: f64,
    /// Items the ring between the loop and the writer holds (about 13 kB each).
    pub ring_capacity: usize,
    /// Rate of the ground truth and the 3-D body, Hz.
    pub scene_rate_hz: f64,
}

impl Default for RecordConfig {
    fn default() -> Self {
        Self {
            path: PathBuf::new(),
            max_mb: 10000.0,
            max_duration_s: 0.0,
            chunk_duration_s: crate::record::DEFAULT_CHUNK_DURATION_S,
            ring_capacity: 1024,
            scene_rate_hz: 50.0,
        }
    }
}

impl RecordConfig {
    /// The file's options for the recorder (`None`: no file), `{time}` in the path
    /// replaced by now, s since the Unix epoch.
    pub fn mcap_options(&self) -> Option<McapOptions> {
        if self.path.as_os_str().is_empty() {
            return None;
        }
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let path = self
            .path
            .to_string_lossy()
            .replace("{time}", &now.to_string());
        Some(McapOptions {
            path: PathBuf::from(path),
            max_bytes: (self.max_mb > 0.0).then_some((self.max_mb * 1e6) as u64),
            max_duration_s: (self.max_duration_s > 0.0).then_some(self.max_duration_s),
            chunk_duration_s: self.chunk_duration_s,
        })
    }

    /// What the recorder would refuse when the daemon starts it, by the recorder's own
    /// check ([`McapOptions::check`]), as the configuration's error naming the key.
    pub(super) fn check(&self, file: &Path) -> Result<(), ConfigFileError> {
        let Some(opts) = self.mcap_options() else {
            return Ok(());
        };
        opts.check().map_err(|e| {
            let (key, value) = match e.mcap_field() {
                Some("max_bytes") => ("record.max_mb", Num(self.max_mb).to_string()),
                Some("max_duration_s") => (
                    "record.max_duration_s",
                    Num(self.max_duration_s).to_string(),
                ),
                Some("chunk_duration_s") => (
                    "record.chunk_duration_s",
                    Num(self.chunk_duration_s).to_string(),
                ),
                _ => ("record.path", format!("{:?}", self.path)),
            };
            ConfigFileError::Invalid {
                path: file.to_owned(),
                key,
                value,
                why: e.to_string(),
            }
        })
    }
}

/// `[foxglove]`: the live view over the Foxglove WebSocket protocol.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FoxgloveConfig {
    pub enabled: bool,
    /// Address to listen on; loopback unless a viewer on another machine must see it.
    pub host: std::net::IpAddr,
    pub port: u16,
    /// Operate from Foxglove: services for the socket's methods and a teleop channel
    /// (docs/recording.md, "Operating from Foxglove"). Off: watching only.
    pub operate: bool,
    /// A file holding the token a Foxglove client gives (`auth` service) before it
    /// operates; required when operating on an address other than loopback.
    pub token_file: PathBuf,
    /// The channel twists are published on (Foxglove's Teleop panel: `/cmd_vel`).
    pub teleop_topic: String,
    /// Twists expire after this long, s: the gait makes a controlled stop...
    pub teleop_timeout_s: f64,
    /// ...which brings the body to rest within this long, s, whatever the blend time...
    pub teleop_stop_s: f64,
    /// ...and the robot holds this much later, s (`arm` resumes).
    pub teleop_hold_after_s: f64,
    /// Temporal frequency per unit of the twist's `linear.x`, rad/s.
    pub teleop_speed_rad_s: f64,
    /// Largest |temporal frequency| teleop asks for, rad/s.
    pub teleop_max_speed_rad_s: f64,
    /// Connections the server holds at once, counted from accept (a connection still in
    /// its handshake counts); one more is closed at once, with a warning in the log.
    pub max_connections: usize,
    /// ...of which from one IP address.
    pub max_connections_per_address: usize,
    /// A connection must complete its WebSocket handshake and take the server's first
    /// message within this long, s, or it is closed.
    pub handshake_timeout_s: f64,
}

impl Default for FoxgloveConfig {
    fn default() -> Self {
        let t = crate::station::TeleopConfig::default();
        Self {
            enabled: false,
            host: std::net::IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
            port: crate::live::DEFAULT_LIVE_PORT,
            operate: false,
            token_file: PathBuf::new(),
            teleop_topic: t.topic,
            teleop_timeout_s: t.timeout_s,
            teleop_stop_s: t.stop_s,
            teleop_hold_after_s: t.hold_after_s,
            teleop_speed_rad_s: t.speed_rad_s,
            teleop_max_speed_rad_s: t.max_speed_rad_s,
            max_connections: 32,
            max_connections_per_address: 8,
            handshake_timeout_s: 5.0,
        }
    }
}

impl FoxgloveConfig {
    /// The token clients give before operating, from `token_file` (`None`: no file set),
    /// refused as [`read_token`] refuses it. The daemon reads it when it starts and the
    /// configuration's check when operating is on, so both refuse the same files.
    pub fn token(&self) -> Result<Option<String>, TokenError> {
        if self.token_file.as_os_str().is_empty() {
            return Ok(None);
        }
        read_token(&self.token_file).map(Some)
    }

    /// The teleop settings these give (checked by `TeleopConfig::check`).
    pub fn teleop(&self) -> crate::station::TeleopConfig {
        crate::station::TeleopConfig {
            topic: self.teleop_topic.clone(),
            timeout_s: self.teleop_timeout_s,
            stop_s: self.teleop_stop_s,
            hold_after_s: self.teleop_hold_after_s,
            speed_rad_s: self.teleop_speed_rad_s,
            max_speed_rad_s: self.teleop_max_speed_rad_s,
            ..Default::default()
        }
    }
}
