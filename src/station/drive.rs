//! The teleop channel's worker: twists from authorised clients, in order, become the
//! active gait's speed and steering ([`super::teleop`]); every 50 ms the dead-man looks
//! at how old the last twist is. It runs as one task on the live view's runtime; the
//! WebSocket callbacks only parse, check and queue (a full queue drops the twist: the
//! next one says the same). One operator drives at a time (`socket::driver`): a twist
//! from a client while another drives is refused with a status, and never feeds the
//! driver's dead-man; the dead-man stops only while its client still drives.

use std::sync::Arc;
use std::time::{Duration, Instant};

use foxglove::websocket::{Client, Status};
use serde_json::{Value, json};
use tokio::sync::mpsc;

use super::services::Operating;
use super::teleop::{Steer, Teleop, TeleopRequest, TeleopState, Twist};
use crate::gait::GaitKind;

/// Twists queued at most (a few of the panel's messages).
const QUEUE: usize = 16;
/// How often the dead-man looks.
const TICK: Duration = Duration::from_millis(50);

/// A twist from a client.
struct Sent {
    client: Client,
    twist: Twist,
}

/// The name the worker's own reads go by.
const STATION: &str = "station";

fn teleop_status(client: &Client, message: String) {
    client.send_status(Status::error(message).with_id("snaked.teleop"));
}

/// The WebSocket side of the teleop channel.
pub struct Drive {
    operating: Arc<Operating>,
    tx: mpsc::Sender<Sent>,
}

impl Drive {
    /// Starts the worker on the current runtime.
    pub fn start(operating: Arc<Operating>) -> Self {
        let (tx, rx) = mpsc::channel(QUEUE);
        tokio::spawn(work(operating.clone(), rx));
        Self { operating, tx }
    }

    pub fn topic(&self) -> &str {
        &self.operating.station.config.teleop.topic
    }

    /// A message on a client channel (any topic; only the teleop one is read).
    pub fn on_message(&self, client: &Client, topic: &str, payload: &[u8]) {
        if topic != self.topic() {
            return;
        }
        let id = u32::from(client.id());
        if !self.operating.access.may_operate(id) {
            teleop_status(
                client,
                "teleop refused: call the `auth` service with the token first".into(),
            );
            return;
        }
        let twist = match Twist::parse(payload) {
            Ok(twist) => twist,
            Err(e) => return teleop_status(client, format!("teleop: {e}")),
        };
        if let Err(e) = self
            .operating
            .station
            .claim_drive(&Operating::client_name(id))
        {
            return teleop_status(client, format!("teleop {e}"));
        }
        // Full: the worker is behind; the next twist says the same.
        let _ = self.tx.try_send(Sent {
            client: client.clone(),
            twist,
        });
    }
}

/// The active gait, from `status`, and how a turn steers it: by the nominal heading
/// where its engaged controller declares it steers by one now (its `capabilities`:
/// anti-compliant sidewinding, a heading hold that holds one), else by the gait's knob.
async fn active_gait(op: &Operating) -> Option<(GaitKind, Steer)> {
    let s = op.station.call(STATION, "status", json!({})).await.ok()?;
    let gait: GaitKind = serde_json::from_value(s.get("gait")?.clone()).ok()?;
    let by_heading = s["controller"]["capabilities"]["steers_by_heading"] == true;
    let steer = match (by_heading, s["body"]["heading_rad"].as_f64()) {
        (false, _) => Steer::Knob,
        (true, Some(h)) if s["body"]["valid"] == true => Steer::Heading(h),
        (true, _) => Steer::NoEstimate,
    };
    Some((gait, steer))
}

/// `r` without the parameters that already have their values (`None`: nothing left).
async fn changed_only(op: &Operating, mut r: TeleopRequest) -> Option<TeleopRequest> {
    if r.method != "params.set" {
        return Some(r);
    }
    let gait = r.params["gait"].clone();
    let Ok(live) = op
        .station
        .call(STATION, "params.get", json!({ "gait": gait }))
        .await
    else {
        return Some(r);
    };
    let fields = r.params.as_object_mut()?;
    fields.retain(|k, v| {
        k == "gait"
            || !matches!((live["params"][k].as_f64(), v.as_f64()), (Some(a), Some(b)) if (a - b).abs() < 1e-9)
    });
    (fields.len() > 1).then_some(r)
}

/// A teleop session starts: the operator drives, so a navigation in progress stops
/// (as it does before any driving request on the socket).
async fn stop_navigation(op: &Operating, client: &Client) {
    let navigating = op
        .station
        .call(STATION, "status", json!({}))
        .await
        .is_ok_and(|s| s["navigator"]["active"] == true);
    if navigating {
        let r = TeleopRequest {
            method: "navigate",
            params: json!({ "off": true }),
        };
        let who = Operating::client_name(u32::from(client.id()));
        send(op, &who, &r, Some(client)).await;
    }
}

/// Sends `r` as `who`; a refusal is logged, recorded and told to `client` (if any).
async fn send(op: &Operating, who: &str, r: &TeleopRequest, client: Option<&Client>) -> bool {
    let answer = op.station.call(who, r.method, r.params.clone()).await;
    let logged: Result<Value, String> = answer.clone().map_err(|e| e.to_string());
    op.actions.log(who, r.method, &r.params, &logged);
    if let Err(e) = &answer {
        tracing::warn!("station: {who}'s teleop {} refused: {e}", r.method);
        if let Some(c) = client {
            teleop_status(c, format!("teleop {} refused: {e}", r.method));
        }
    }
    answer.is_ok()
}

async fn work(op: Arc<Operating>, mut rx: mpsc::Receiver<Sent>) {
    let t0 = Instant::now();
    let mut teleop = Teleop::default();
    let mut driver: Option<Client> = None;
    let mut gait = GaitKind::Slithering;
    let config = op.station.config.teleop.clone();
    let mut tick = tokio::time::interval(TICK);
    loop {
        tokio::select! {
            sent = rx.recv() => {
                let Some(Sent { client, twist }) = sent else { return };
                let who = Operating::client_name(u32::from(client.id()));
                if teleop.state() != TeleopState::Driving {
                    stop_navigation(&op, &client).await;
                }
                let mut steer = Steer::Knob;
                if let Some((g, s)) = active_gait(&op).await {
                    (gait, steer) = (g, s);
                }
                let now = t0.elapsed().as_secs_f64();
                for r in teleop.on_twist(now, gait, twist, steer, &config) {
                    // A parameter change hands the joints back to the selector until
                    // its blend is done: send only what differs from what is live.
                    if let Some(r) = changed_only(&op, r).await {
                        send(&op, &who, &r, Some(&client)).await;
                    }
                }
                driver = Some(client);
            }
            _ = tick.tick() => {
                let now = t0.elapsed().as_secs_f64();
                let Some(r) = teleop.tick(now, &config) else { continue };
                let Some(client) = &driver else { continue };
                let name = Operating::client_name(u32::from(client.id()));
                // The dead-man is its driver's: another operator who took the drive
                // over is not stopped by it.
                if r.method == "gait.stop" && op.station.claim_drive(&name).is_err() {
                    teleop = Teleop::default();
                    continue;
                }
                let who = format!("dead-man ({name})");
                if !send(&op, &who, &r, Some(client)).await && r.method == "gait.stop" {
                    let hold = teleop.stop_refused();
                    send(&op, &who, &hold, Some(client)).await;
                }
            }
        }
    }
}
