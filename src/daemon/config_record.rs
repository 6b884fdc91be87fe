//! `snaked.toml`'s `[record]` and `[foxglove]`: the recording, the live view and operating
//! from Foxglove (docs/recording.md); part of [`super::config::Config`].
use std::path::PathBuf;

use serde::Deserialize;

/// `[record]`: an MCAP file of every cycle (docs/recording.md).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordConfig {
    /// The file to write; empty = no recording. It must not exist yet; its directory
    /// must. `{time}` in the name is replaced by the start time (UTC, `YYYYmmdd-HHMMSS`).
    pub path: PathBuf,
    /// Stop writing (and finish the file) past this size, MB; 0 = no size cap.
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
    /// Twists expire after this long, s: the gait runs on at zero speed...
    pub teleop_timeout_s: f64,
    /// ...and the robot holds this much later, s (`arm` resumes).
    pub teleop_hold_after_s: f64,
    /// Temporal frequency per unit of the twist's `linear.x`, rad/s.
    pub teleop_speed_rad_s: f64,
    /// Largest |temporal frequency| teleop asks for, rad/s.
    pub teleop_max_speed_rad_s: f64,
}

impl Default for FoxgloveConfig {
    fn default() -> Self {
        let t = crate::station::TeleopConfig::default();
        Self {
            enabled: false,
            host: std::net::IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
            port: crate::record::DEFAULT_LIVE_PORT,
            operate: false,
            token_file: PathBuf::new(),
            teleop_topic: t.topic,
            teleop_timeout_s: t.timeout_s,
            teleop_hold_after_s: t.hold_after_s,
            teleop_speed_rad_s: t.speed_rad_s,
            teleop_max_speed_rad_s: t.max_speed_rad_s,
        }
    }
}

impl FoxgloveConfig {
    /// The teleop settings these give (checked by `TeleopConfig::check`).
    pub fn teleop(&self) -> crate::station::TeleopConfig {
        crate::station::TeleopConfig {
            topic: self.teleop_topic.clone(),
            timeout_s: self.teleop_timeout_s,
            hold_after_s: self.teleop_hold_after_s,
            speed_rad_s: self.teleop_speed_rad_s,
            max_speed_rad_s: self.teleop_max_speed_rad_s,
            ..Default::default()
        }
    }
}
