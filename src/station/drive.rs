//! The teleop worker: twists from a client allowed to drive, in order, become the
//! active gait's speed and steering ([`super::teleop`]); every 50 ms the dead-man looks
//! at how old the last twist is. It runs as one task on the runtime that started it;
//! the edges (Foxglove's client channel here, ROS 2's `/cmd_vel`) only parse, check and
//! queue (a full queue drops the twist: the next one says the same). One operator
//! drives at a time (`operator::driver`): a twist from a client while another drives is
//! refused and never feeds the driver's dead-man; the dead-man stops only while its
//! client still drives.

use std::sync::Arc;
use std::time::{Duration, Instant};

use foxglove::websocket::{Client, Status};
use tokio::sync::mpsc;

use super::services::Operating;
use super::teleop::{Steer, Teleop, TeleopState, Twist, active_gait, changed_only};
use crate::gait::GaitKind;
use crate::operator::Act;

/// Twists queued at most (a few of the panel's messages).
const QUEUE: usize = 16;
/// How often the dead-man looks.
const TICK: Duration = Duration::from_millis(50);

/// Who sent a twist, and how a refusal reaches them.
pub trait TeleopClient: Clone + Send + Sync + 'static {
    /// The name it drives as (the drive lease, the recording).
    fn name(&self) -> String;
    /// Tells it a refusal (logged and recorded anyway).
    fn tell(&self, message: String);
}

/// A twist from a client.
struct Sent<C> {
    client: C,
    twist: Twist,
}

/// The edges' end of the worker.
pub struct DriveWorker<C> {
    operating: Arc<Operating>,
    tx: mpsc::Sender<Sent<C>>,
}

impl<C: TeleopClient> DriveWorker<C> {
    /// Starts the worker on the current runtime.
    pub fn start(operating: Arc<Operating>) -> Self {
        let (tx, rx) = mpsc::channel(QUEUE);
        tokio::spawn(work(operating.clone(), rx));
        Self { operating, tx }
    }

    /// A twist from `client`, who may operate: refused (and told) while another
    /// operator drives, else queued.
    pub fn offer(&self, client: C, twist: Twist) {
        if let Err(e) = self.operating.station.claim_drive(&client.name()) {
            return client.tell(format!("teleop {e}"));
        }
        // Full: the worker is behind; the next twist says the same.
        let _ = self.tx.try_send(Sent { client, twist });
    }
}

/// A Foxglove client, told by a status message.
#[derive(Clone)]
pub struct FoxgloveClient(pub Client);

impl TeleopClient for FoxgloveClient {
    fn name(&self) -> String {
        Operating::client_name(u32::from(self.0.id()))
    }

    fn tell(&self, message: String) {
        self.0
            .send_status(Status::error(message).with_id("snaked.teleop"));
    }
}

/// The Foxglove side of the teleop channel.
pub struct Drive {
    worker: DriveWorker<FoxgloveClient>,
}

impl Drive {
    /// Starts the worker on the current runtime.
    pub fn start(operating: Arc<Operating>) -> Self {
        Self {
            worker: DriveWorker::start(operating),
        }
    }

    pub fn topic(&self) -> &str {
        &self.worker.operating.station.config.teleop.topic
    }

    /// A message on a client channel (any topic; only the teleop one is read).
    pub fn on_message(&self, client: &Client, topic: &str, payload: &[u8]) {
        if topic != self.topic() {
            return;
        }
        let c = FoxgloveClient(client.clone());
        if !self
            .worker
            .operating
            .access
            .may_operate(u32::from(client.id()))
        {
            return c.tell("teleop refused: call the `auth` service with the token first".into());
        }
        match Twist::parse(payload) {
            Ok(twist) => self.worker.offer(c, twist),
            Err(e) => c.tell(format!("teleop: {e}")),
        }
    }
}

/// A teleop session starts: the operator drives, so a navigation in progress stops
/// (as it does before any driving request on the socket).
async fn stop_navigation<C: TeleopClient>(op: &Operating, client: &C) {
    if op.station.snapshot().is_some_and(|s| s.navigator.active) {
        send(op, &client.name(), Act::NavigateOff, Some(client)).await;
    }
}

/// Carries `act` out as `who`; a refusal is logged, recorded and told to `client` (if
/// any).
async fn send<C: TeleopClient>(op: &Operating, who: &str, act: Act, client: Option<&C>) -> bool {
    let method = act.method();
    let answer = op.act_logged(who, "teleop ", act).await;
    if let (Err(e), Some(c)) = (&answer, client) {
        c.tell(format!("teleop {method} refused: {e}"));
    }
    answer.is_ok()
}

async fn work<C: TeleopClient>(op: Arc<Operating>, mut rx: mpsc::Receiver<Sent<C>>) {
    let t0 = Instant::now();
    let mut teleop = Teleop::default();
    let mut driver: Option<C> = None;
    let mut gait = GaitKind::Slithering;
    let config = op.station.config.teleop.clone();
    let mut tick = tokio::time::interval(TICK);
    loop {
        tokio::select! {
            sent = rx.recv() => {
                let Some(Sent { client, twist }) = sent else { return };
                let who = client.name();
                if teleop.state() != TeleopState::Driving {
                    stop_navigation(&op, &client).await;
                }
                let snapshot = op.station.snapshot();
                let mut steer = Steer::Knob;
                if let Some(s) = &snapshot {
                    (gait, steer) = active_gait(s);
                }
                let now = t0.elapsed().as_secs_f64();
                for act in teleop.on_twist(now, gait, twist, steer, &config) {
                    // Send only what differs from what is live.
                    if let Some(act) = changed_only(op.station.snapshot().as_ref(), act) {
                        send(&op, &who, act, Some(&client)).await;
                    }
                }
                driver = Some(client);
            }
            _ = tick.tick() => {
                let now = t0.elapsed().as_secs_f64();
                let Some(act) = teleop.tick(now, &config) else { continue };
                let Some(client) = &driver else { continue };
                let name = client.name();
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
