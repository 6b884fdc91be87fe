//! The server: foxglove's WebSocket server (subprotocol `foxglove.sdk.v1`) on the
//! recorder's context, so live clients get the same channels as the file. It runs on a
//! one-worker tokio runtime of its own, owned by the recorder's writer thread (so the
//! recorder works the same whether or not its caller is inside a runtime). Messages that
//! are published once (the world, controller infos) are latched ([`Latch`]): re-sent to
//! each client that subscribes later. When operating, it carries the station: services,
//! parameters and the teleop channel.

use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Weak};
use std::time::Duration;

use foxglove::websocket::{Capability, ChannelView, Client, ClientChannel, ServerListener, Status};
use foxglove::{Context, WebSocketServerHandle};

use super::latch::Latch;
use super::viewers::{ViewerReports, take_reports};
use super::{Asset, LiveError, LiveOptions};
use crate::station::access::Access;
use crate::station::actions::Actions;
use crate::station::drive::Drive;
use crate::station::parameters::{Parameters, publish_changes};
use crate::station::services::{Operating, services};

/// The one encoding clients may publish in (the server's `supportedEncodings`).
const CLIENT_ENCODING: &str = "json";

/// The server's listener: the latch, the teleop channel and the parameter
/// subscriptions when operating.
struct Listener {
    latch: Arc<Latch>,
    drive: Option<Drive>,
    /// Parameter names clients subscribed to (the server reports first and last).
    subscribed: Arc<AtomicUsize>,
}

impl ServerListener for Listener {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        self.latch.on_subscribe(client, channel);
    }

    fn on_client_advertise(&self, client: Client, channel: &ClientChannel) {
        if channel.encoding != CLIENT_ENCODING {
            tracing::warn!(
                "live view: foxglove client {} advertised {} in {:?}: refused (json only)",
                u32::from(client.id()),
                channel.topic,
                channel.encoding
            );
            client.send_status(
                Status::error(format!(
                    "channel {}: encoding {:?} refused: this server takes {CLIENT_ENCODING} \
                     only; its messages are ignored",
                    channel.topic, channel.encoding
                ))
                .with_id("snaked.client_channel"),
            );
        }
    }

    fn on_message_data(&self, client: Client, channel: &ClientChannel, payload: &[u8]) {
        // A channel in another encoding was refused when advertised: never read.
        if channel.encoding != CLIENT_ENCODING {
            return;
        }
        if let Some(d) = &self.drive {
            d.on_message(&client, &channel.topic, payload);
        }
    }

    fn on_parameters_subscribe(&self, names: Vec<String>) {
        self.subscribed.fetch_add(names.len(), Ordering::Relaxed);
    }

    fn on_parameters_unsubscribe(&self, names: Vec<String>) {
        let n = names.len();
        let _ = self
            .subscribed
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |k| {
                Some(k.saturating_sub(n))
            });
    }

    fn on_client_connect(&self) {
        self.latch.on_client_connect();
    }

    fn on_client_disconnect(&self) {
        self.latch.on_client_disconnect();
    }
}

/// Every slow viewer the server reported (`live::viewers`): a `/live/viewers`
/// message and a warning status to every viewer. Runs until aborted.
async fn report_slow_viewers(reports: ViewerReports, server: Weak<WebSocketServerHandle>) {
    let mut tick = tokio::time::interval(Duration::from_millis(200));
    loop {
        tick.tick().await;
        for viewer in take_reports() {
            reports.thinned(&viewer);
            let Some(h) = server.upgrade() else { return };
            h.publish_status(
                Status::warning(format!(
                    "viewer {viewer} cannot keep up: the live view drops its oldest messages"
                ))
                .with_id("snaked.slow_viewer"),
            );
        }
    }
}

/// How long the viewers get to close at shutdown.
const CLOSE_GRACE: Duration = Duration::from_secs(1);

/// A running live server.
pub struct Live {
    runtime: Option<tokio::runtime::Runtime>,
    /// Shared (weakly) with the parameter updates' task.
    handle: Option<Arc<WebSocketServerHandle>>,
    /// The tasks that publish through it: parameter updates (when operating), slow
    /// viewers.
    tasks: Vec<tokio::task::AbortHandle>,
    addr: SocketAddr,
    pub latch: Arc<Latch>,
}

impl Live {
    /// Binds and starts the server on `opts.addr` (port 0: any free port).
    pub fn start(
        opts: &LiveOptions,
        ctx: &Arc<Context>,
        name: String,
        model: Asset,
    ) -> Result<Self, LiveError> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("snaked-live")
            .enable_all()
            .build()
            .map_err(LiveError::Runtime)?;
        let latch = Arc::new(Latch::default());
        let host = match opts.addr.ip() {
            IpAddr::V4(ip) => ip.to_string(),
            IpAddr::V6(ip) => format!("[{ip}]"),
        };
        let mut server = ctx
            .websocket_server()
            .name(name)
            .bind(host, opts.addr.port());
        // Admission (the patched crate, third_party/foxglove): caps counted from accept,
        // a handshake timeout; a failed accept is retried, never the end of the server.
        if let Some(n) = opts.max_connections {
            server = server.max_connections(n);
        }
        if let Some(n) = opts.max_connections_per_address {
            server = server.max_connections_per_ip(n);
        }
        if let Some(t) = opts.handshake_timeout {
            server = server.handshake_timeout(t);
        }
        let mut server = server.fetch_asset_handler_blocking_fn(move |_client, uri: String| {
            if uri == model.uri {
                Ok(model.body.clone().into_bytes())
            } else {
                Err(format!("no asset {uri:?} (this server has {})", model.uri))
            }
        });
        let mut drive = None;
        let mut operating_now = None;
        let subscribed = Arc::new(AtomicUsize::new(0));
        if let Some(station) = &opts.station {
            // Operating: services and the teleop channel, through the control socket.
            let operating = Arc::new(Operating {
                access: Access::new(station.config.token.clone()),
                actions: Actions::new(ctx),
                station: station.clone(),
            });
            drive = Some({
                let _enter = runtime.enter();
                Drive::start(operating.clone())
            });
            server = server
                .capabilities([
                    Capability::ClientPublish,
                    Capability::Services,
                    Capability::Parameters,
                ])
                .supported_encodings([CLIENT_ENCODING])
                .services(services(&operating))
                .parameter_handler(Arc::new(Parameters {
                    operating: operating.clone(),
                }));
            operating_now = Some(operating);
        }
        let server = server.listener(Arc::new(Listener {
            latch: latch.clone(),
            drive,
            subscribed: subscribed.clone(),
        }));
        // Inside `block_on` the server finds this runtime as the current one.
        let handle = runtime
            .block_on(server.start())
            .map_err(|source| LiveError::Bind {
                addr: opts.addr,
                reason: source,
            })?;
        let addr = SocketAddr::new(opts.addr.ip(), handle.port());
        tracing::info!(%addr, "recorder: live view (Foxglove WebSocket) listening");
        let handle = Arc::new(handle);
        let mut tasks = Vec::new();
        if let Some(op) = operating_now {
            let task = publish_changes(op, Arc::downgrade(&handle), subscribed);
            tasks.push(runtime.spawn(task).abort_handle());
        }
        let slow = report_slow_viewers(ViewerReports::new(ctx), Arc::downgrade(&handle));
        tasks.push(runtime.spawn(slow).abort_handle());
        Ok(Self {
            runtime: Some(runtime),
            handle: Some(handle),
            tasks,
            addr,
            latch,
        })
    }

    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Closes the connections and stops the runtime. Idempotent.
    pub fn stop(&mut self) {
        for t in self.tasks.drain(..) {
            t.abort();
        }
        if let Some(mut h) = self.handle.take() {
            // The updates' task holds the handle only while it publishes: wait it out.
            for _ in 0..500 {
                match Arc::try_unwrap(h) {
                    Ok(h) => {
                        let closing = h.stop();
                        // A viewer that does not read blocks its connection's close: give
                        // them a second, then drop what is left (the tasks are aborted).
                        if let Some(rt) = &self.runtime {
                            let waited = rt.block_on(async {
                                tokio::time::timeout(CLOSE_GRACE, closing.wait()).await
                            });
                            if waited.is_err() {
                                tracing::warn!(
                                    "live view: a viewer did not close within {CLOSE_GRACE:?}; cut off"
                                );
                            }
                        }
                        break;
                    }
                    Err(still) => {
                        h = still;
                        std::thread::sleep(Duration::from_millis(2));
                    }
                }
            }
        }
        if let Some(rt) = self.runtime.take() {
            rt.shutdown_timeout(Duration::from_secs(1));
        }
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        self.stop();
    }
}
