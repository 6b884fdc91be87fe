//! The recording's channels, one foxglove `RawChannel` per topic in the recorder's own
//! `Context`: whatever is logged goes to every sink of that context (the MCAP file, the
//! live view's clients). A message nobody listens to is not even encoded.

use std::sync::Arc;

use foxglove::schemas::{FrameTransforms, SceneUpdate};
use foxglove::{Context, Encode, FoxgloveError, PartialMetadata, RawChannel, Schema};

use super::schemas;
use crate::live::Latch;

/// Every topic the recorder writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Topic {
    Joints,
    Commands,
    Imu,
    BodyEstimate,
    Navigation,
    ControllerSignals,
    ControllerWindows,
    ControllerInfo,
    Events,
    Stats,
    Tf,
    SceneWorld,
    SceneBody,
}

impl Topic {
    pub const ALL: [Topic; 13] = [
        Topic::Joints,
        Topic::Commands,
        Topic::Imu,
        Topic::BodyEstimate,
        Topic::Navigation,
        Topic::ControllerSignals,
        Topic::ControllerWindows,
        Topic::ControllerInfo,
        Topic::Events,
        Topic::Stats,
        Topic::Tf,
        Topic::SceneWorld,
        Topic::SceneBody,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Topic::Joints => "/joints",
            Topic::Commands => "/commands",
            Topic::Imu => "/imu",
            Topic::BodyEstimate => "/body/estimate",
            Topic::Navigation => "/navigation",
            Topic::ControllerSignals => "/controller/signals",
            Topic::ControllerWindows => "/controller/windows",
            Topic::ControllerInfo => "/controller/info",
            Topic::Events => "/events",
            Topic::Stats => "/stats",
            Topic::Tf => "/tf",
            Topic::SceneWorld => "/scene/world",
            Topic::SceneBody => "/scene/body",
        }
    }

    fn index(self) -> usize {
        self as usize
    }

    /// The JSON schema of a JSON-encoded topic (`None`: one of Foxglove's own types).
    pub fn json_schema(self) -> Option<serde_json::Value> {
        Some(match self {
            Topic::Joints => schemas::joints(),
            Topic::Commands => schemas::commands(),
            Topic::Imu => schemas::imu(),
            Topic::BodyEstimate => schemas::body_estimate(),
            Topic::Navigation => schemas::navigation(),
            Topic::ControllerSignals => schemas::controller_signals(),
            Topic::ControllerWindows => schemas::controller_windows(),
            Topic::ControllerInfo => schemas::controller_info(),
            Topic::Events => schemas::events(),
            Topic::Stats => schemas::stats(),
            Topic::Tf | Topic::SceneWorld | Topic::SceneBody => return None,
        })
    }
}

/// The channels and how many messages each has written to the file.
pub struct Channels {
    raw: Vec<Arc<RawChannel>>,
    /// Messages written to the file per topic (counted only while the file is open).
    written: [u64; Topic::ALL.len()],
    /// Whether the MCAP file is a sink now.
    pub file_open: bool,
    /// Where latched messages are kept for the live view's late subscribers.
    pub latch: Option<Arc<Latch>>,
    buf: Vec<u8>,
}

impl Channels {
    pub fn new(ctx: &Arc<Context>) -> Result<Self, FoxgloveError> {
        let raw = Topic::ALL
            .iter()
            .map(|&t| {
                let builder = ctx.channel_builder(t.name());
                let (schema, encoding) = match t.json_schema() {
                    Some(s) => {
                        let title = s["title"].as_str().unwrap_or("snaked").to_owned();
                        let data = serde_json::to_vec(&s).map_err(|e| {
                            FoxgloveError::EncodeError(format!("schema of {}: {e}", t.name()))
                        })?;
                        (Schema::new(title, "jsonschema", data), "json".to_owned())
                    }
                    None if t == Topic::Tf => proto::<FrameTransforms>(),
                    None => proto::<SceneUpdate>(),
                };
                builder
                    .schema(schema)
                    .message_encoding(encoding)
                    .build_raw()
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            raw,
            written: [0; Topic::ALL.len()],
            file_open: false,
            latch: None,
            buf: Vec::with_capacity(16 * 1024),
        })
    }

    pub fn channel(&self, t: Topic) -> &Arc<RawChannel> {
        &self.raw[t.index()]
    }

    /// Whether anyone (file or live client) listens to `t`.
    pub fn wanted(&self, t: Topic) -> bool {
        self.channel(t).has_sinks()
    }

    /// Encodes a JSON body with `write` and logs it (skipped when nobody listens).
    pub fn log_json(
        &mut self,
        t: Topic,
        log_time: u64,
        write: impl FnOnce(&mut Vec<u8>) -> serde_json::Result<()>,
    ) {
        self.log(t, None, log_time, |b| write(b).map_err(|e| e.to_string()));
    }

    /// Like [`Channels::log_json`], and kept for live clients that subscribe later
    /// (replacing what was kept under the same `key`).
    pub fn log_json_latched(
        &mut self,
        t: Topic,
        key: u64,
        log_time: u64,
        write: impl FnOnce(&mut Vec<u8>) -> serde_json::Result<()>,
    ) {
        self.log(t, Some(key), log_time, |b| {
            write(b).map_err(|e| e.to_string())
        });
    }

    /// Logs a well-known (protobuf) message.
    pub fn log_proto(&mut self, t: Topic, log_time: u64, msg: &impl Encode) {
        self.log(t, None, log_time, |b| {
            msg.encode(b).map_err(|e| e.to_string())
        });
    }

    /// Like [`Channels::log_proto`], latched as [`Channels::log_json_latched`] is.
    pub fn log_proto_latched(&mut self, t: Topic, key: u64, log_time: u64, msg: &impl Encode) {
        self.log(t, Some(key), log_time, |b| {
            msg.encode(b).map_err(|e| e.to_string())
        });
    }

    fn log(
        &mut self,
        t: Topic,
        latch_key: Option<u64>,
        log_time: u64,
        encode: impl FnOnce(&mut Vec<u8>) -> Result<(), String>,
    ) {
        let latch = latch_key.and_then(|k| self.latch.clone().map(|l| (k, l)));
        let wanted = self.wanted(t);
        if !wanted && latch.is_none() {
            return;
        }
        self.buf.clear();
        if let Err(e) = encode(&mut self.buf) {
            tracing::warn!(topic = t.name(), "recorder: cannot encode: {e}");
            return;
        }
        let channel = &self.raw[t.index()];
        if wanted {
            let meta = PartialMetadata {
                log_time: Some(log_time),
            };
            channel.log_with_meta(&self.buf, meta);
            if self.file_open {
                self.written[t.index()] += 1;
            }
        }
        if let Some((key, latch)) = latch {
            latch.keep(channel, key, &self.buf, log_time);
        }
    }

    pub fn written(&self, t: Topic) -> u64 {
        self.written[t.index()]
    }

    pub fn written_total(&self) -> u64 {
        self.written.iter().sum()
    }
}

fn proto<T: Encode>() -> (Schema, String) {
    let schema = T::get_schema().expect("foxglove's well-known types carry their schema");
    (schema, T::get_message_encoding())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_topic_has_a_channel_and_a_schema() {
        let ctx = Context::new();
        let ch = Channels::new(&ctx).expect("channels");
        for t in Topic::ALL {
            let c = ch.channel(t);
            assert_eq!(c.topic(), t.name());
            let s = c.schema().expect("schema");
            match t {
                Topic::Tf => assert_eq!(s.name, "foxglove.FrameTransforms"),
                Topic::SceneWorld | Topic::SceneBody => assert_eq!(s.name, "foxglove.SceneUpdate"),
                _ => {
                    assert_eq!(
                        (s.encoding.as_str(), c.message_encoding()),
                        ("jsonschema", "json")
                    );
                    let v: serde_json::Value = serde_json::from_slice(&s.data).expect("JSON");
                    assert_eq!(v["type"], "object");
                }
            }
        }
    }
}
