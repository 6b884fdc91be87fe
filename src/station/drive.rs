//! The teleop channel's worker: twists from authorised clients, in order, become the
//! active gait's speed and steering ([`super::teleop`]); every 50 ms the dead-man looks
//! at how old the last twist is. It runs as one task on the live view's runtime; the
//! WebSocket callbacks only parse, check and queue (a full queue drops the twist: the
//! next one says the same). One operator drives at a time (`operator::driver`): a twist
//! from a client while another drives is refused with a status, and never feeds the
//! driver's dead-man; the dead-man stops only while its client still drives.

use std::sync::Arc;
use std::time::{Duration, Instant};

use foxglove::websocket::{Client, Status};
use tokio::sync::mpsc;

use super::services::Operating;
use super::teleop::{Steer, Teleop, TeleopState, Twist};
use crate::gait::GaitKind;
use crate::gait::params::Field;
use crate::operator::Act;

/// Twists queued at most (a few of the panel's messages).
const QUEUE: usize = 16;
/// How often the dead-man looks.
const TICK: Duration = Duration::from_millis(50);

/// A twist from a client.
struct Sent {
    client: Client,
    twist: Twist,
}

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

/// The active gait, from the loop's snapshot, and how a turn steers it: by the nominal
/// heading where its engaged controller declares it steers by one now (its
/// `capabilities`: anti-compliant sidewinding, a heading hold that holds one), else by
/// the gait's knob.
fn active_gait(op: &Operating) -> Option<(GaitKind, Steer)> {
    let s = op.station.snapshot()?;
    let steer = match (s.controller.capabilities.steers_by_heading, s.body.valid) {
        (false, _) => Steer::Knob,
        (true, true) if s.body.heading_rad.is_finite() => Steer::Heading(s.body.heading_rad),
        (true, _) => Steer::NoEstimate,
    };
    Some((s.gait, steer))
}

/// `act` without the parameters that already have their values (`None`: nothing left).
fn changed_only(op: &Operating, act: Act) -> Option<Act> {
    let Act::SetParams { gait, mut patch } = act else {
        return Some(act);
    };
    let Some(s) = op.station.snapshot() else {
        return Some(Act::SetParams { gait, patch });
    };
    let live = s.params.get(gait);
    let mut left = false;
    for f in Field::ALL {
        match f.in_patch(&patch) {
            Some(v) if (f.get(live) - v).abs() < 1e-9 => f.clear_in_patch(&mut patch),
            Some(_) => left = true,
            None => {}
        }
    }
    left.then_some(Act::SetParams { gait, patch })
}

/// A teleop session starts: the operator drives, so a navigation in progress stops
/// (as it does before any driving request on the socket).
async fn stop_navigation(op: &Operating, client: &Client) {
    if op.station.snapshot().is_some_and(|s| s.navigator.active) {
        let who = Operating::client_name(u32::from(client.id()));
        send(op, &who, Act::NavigateOff, Some(client)).await;
    }
}

/// Carries `act` out as `who`; a refusal is logged, recorded and told to `client` (if
/// any).
async fn send(op: &Operating, who: &str, act: Act, client: Option<&Client>) -> bool {
    let method = act.method();
    let answer = op.act_logged(who, "teleop ", act).await;
    if let (Err(e), Some(c)) = (&answer, client) {
        teleop_status(c, format!("teleop {method} refused: {e}"));
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
                if let Some((g, s)) = active_gait(&op) {
                    (gait, steer) = (g, s);
                }
                let now = t0.elapsed().as_secs_f64();
                for act in teleop.on_twist(now, gait, twist, steer, &config) {
                    // Send only what differs from what is live.
                    if let Some(act) = changed_only(&op, act) {
                        send(&op, &who, act, Some(&client)).await;
                    }
                }
                driver = Some(client);
            }
            _ = tick.tick() => {
                let now = t0.elapsed().as_secs_f64();
                let Some(act) = teleop.tick(now, &config) else { continue };
                let Some(client) = &driver else { continue };
                let name = Operating::client_name(u32::from(client.id()));
                let stopping = matches!(act, Act::StopGait { .. });
                // The dead-man is its driver's: another operator who took the drive
                // over is not stopped by it.
                if stopping && op.station.claim_drive(&name).is_err() {
                    teleop = Teleop::default();
                    continue;
                }
                let who = format!("dead-man ({name})");
                if !send(&op, &who, act, Some(client)).await && stopping {
                    let hold = teleop.stop_refused();
                    send(&op, &who, hold, Some(client)).await;
                }
            }
        }
    }
}
