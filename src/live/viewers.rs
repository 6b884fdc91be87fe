//! Slow viewers made visible. The `foxglove` server thins a viewer that cannot keep up
//! (its outbox full, the oldest messages dropped) and says so only in its log ("outbox
//! for client ADDR full", at most every 30 s); it counts nothing per client. A tracing
//! layer ([`SlowViewerLayer`], installed with the binaries' logging) picks that line up
//! and the live view turns it into a `/live/viewers` message (in the recording too) and
//! a warning status every connected viewer sees.

use std::sync::Arc;
use std::sync::OnceLock;

use crossbeam_channel::{Receiver, Sender, bounded};
use foxglove::{Context, RawChannel};

use crate::foxglove_json::json_channel;
use tracing::field::{Field, Visit};
use tracing_subscriber::layer::{Context as LayerContext, Layer};

/// The topic of the slow-viewer reports.
pub const TOPIC: &str = "/live/viewers";
/// What the server logs about a full outbox.
const OUTBOX_FULL: &str = "outbox for client ";

fn reports() -> &'static (Sender<String>, Receiver<String>) {
    static REPORTS: OnceLock<(Sender<String>, Receiver<String>)> = OnceLock::new();
    REPORTS.get_or_init(|| bounded(64))
}

/// Takes the reports made since the last call: the slow viewers' addresses.
pub fn take_reports() -> Vec<String> {
    reports().1.try_iter().collect()
}

/// The layer: forwards the `foxglove` server's full-outbox lines.
pub struct SlowViewerLayer;

struct Message(Option<String>);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = Some(format!("{value:?}"));
        }
    }
}

impl<S: tracing::Subscriber> Layer<S> for SlowViewerLayer {
    fn on_event(&self, event: &tracing::Event<'_>, _ctx: LayerContext<'_, S>) {
        if !event.metadata().target().starts_with("foxglove") {
            return;
        }
        let mut m = Message(None);
        event.record(&mut m);
        let Some(text) = m.0 else { return };
        if let Some(rest) = text.split(OUTBOX_FULL).nth(1) {
            let addr = rest.trim_end_matches(" full").to_owned();
            // Full: reports pile up only if nobody reads them; drop the newest.
            let _ = reports().0.try_send(addr);
        }
    }
}

/// Writes the reports on the recorder's context.
pub struct ViewerReports {
    channel: Option<Arc<RawChannel>>,
}

impl ViewerReports {
    pub fn new(ctx: &Arc<Context>) -> Self {
        let schema = br#"{"type":"object","properties":{"viewer":{"type":"string"},"event":{"type":"string"}}}"#;
        Self {
            channel: json_channel(ctx, TOPIC, "snaked.SlowViewer", schema),
        }
    }

    /// Logs that `viewer` (its address) is being thinned.
    pub fn thinned(&self, viewer: &str) {
        if let Some(ch) = &self.channel {
            let msg = serde_json::json!({ "viewer": viewer, "event": "thinned" });
            ch.log(msg.to_string().as_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tracing_subscriber::layer::SubscriberExt;

    #[test]
    fn the_servers_full_outbox_line_becomes_a_report() {
        let subscriber = tracing_subscriber::registry().with(SlowViewerLayer);
        tracing::subscriber::with_default(subscriber, || {
            tracing::info!(target: "foxglove::websocket::connected_client::send_lossy", "outbox for client 127.0.0.1:5555 full");
            tracing::info!(target: "foxglove::websocket", "client connected");
            tracing::info!(target: "snaked", "outbox for client 1.2.3.4:1 full");
        });
        assert_eq!(take_reports(), ["127.0.0.1:5555"]);
    }
}
