//! JSON channels on a foxglove `Context`: the helper the recorder's neighbours share (the
//! live view's slow-viewer reports, the station's `/operator` events), below all of them.

use std::sync::Arc;

use foxglove::{Context, RawChannel, Schema};

/// A JSON channel `topic` with the JSON Schema `schema` named `name` on `ctx` (`None`,
/// and a warning, if it cannot be made: what it would carry is then not logged).
pub fn json_channel(
    ctx: &Arc<Context>,
    topic: &str,
    name: &str,
    schema: &'static [u8],
) -> Option<Arc<RawChannel>> {
    ctx.channel_builder(topic)
        .message_encoding("json")
        .schema(Schema::new(name, "jsonschema", schema))
        .build_raw()
        .map_err(|e| tracing::warn!("no {topic} channel: {e}"))
        .ok()
}
