//! Driving and tuning from ROS 2 (`[ros2] operate`): `/cmd_vel`, the services and the
//! parameters, each a thin edge over the operator API as the socket and Foxglove are.
//! Everything reaches the loop through `Operator::act` (the drive lease, the checks, the
//! loop's queue) and is recorded on `/operator` like the station's actions. DDS says
//! nothing of who sent a request: every ROS 2 client acts as the one operator
//! [`WHO`]. DDS has no authentication either: whoever reaches the DDS domain may
//! operate (the daemon warns at start when discovery reaches beyond localhost).
//!
//! - `/cmd_vel` (`geometry_msgs/Twist`): the station's teleop (`station::drive`): the
//!   same mapping to speed and steering, the same dead-man.
//! - `std_srvs/Trigger` services under the node's name: `hold`, `limp`, `arm`,
//!   `estop`, `take_over`, `stop` / `resume` (the gait's controlled stop), `calibrate`
//!   (the running gait's controller), `gait/<gait>` (switch to it);
//!   `std_srvs/SetBool` `navigate` (true: along the heading now; false: off).
//! - `goal_pose` (`geometry_msgs/PoseStamped`, rviz2's "2D Goal Pose"): navigate to its
//!   x, y in the position source's world (`navigate` with `goal_m`).
//! - the parameters (`super::parameters`).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use ros2_client::service::Server;
use ros2_client::{Node, QosProfile, ServiceMapping, ServiceTypeName, Subscription};
use serde_json::{Value, json};
use tokio::task::JoinSet;

use super::Ros2Options;
use super::msg::{Empty, PoseStamped, ServiceAnswer, SetBoolRequest, Twist};
use super::node::{Ros2Error, err, reliable_qos, sensor_qos, subscription, unix_ns};
use super::parameters::ParameterServers;
use crate::gait::GaitKind;
use crate::operator::{Operator, OperatorError};
use crate::station::actions::Actions;
use crate::station::drive::{DriveWorker, TeleopClient};
use crate::station::services::Operating;
use crate::station::{Access, Station, StationConfig, TeleopConfig, teleop};

/// The operator every ROS 2 client acts as.
pub const WHO: &str = "ros2";

/// The Trigger services: name under the node, the socket's method, its params.
fn triggers() -> Vec<(String, &'static str, Value)> {
    let mut out: Vec<(String, &'static str, Value)> = [
        ("hold", "hold"),
        ("limp", "limp"),
        ("arm", "arm"),
        ("estop", "estop"),
        ("take_over", "take_over"),
        ("stop", "gait.stop"),
        ("resume", "gait.resume"),
        ("calibrate", "controller.calibrate"),
    ]
    .into_iter()
    .map(|(name, method)| (name.to_owned(), method, json!({})))
    .collect();
    for g in GaitKind::ALL {
        out.push((
            format!("gait/{}", g.name()),
            "gait.set",
            json!({ "gait": g.name() }),
        ));
    }
    out
}

type Trigger = Server<Empty, ServiceAnswer>;

/// The operator's edges, made with the node, started once the operator API is bound.
pub(super) struct Edges {
    cmd_vel: Subscription<Twist>,
    goal: Subscription<PoseStamped>,
    triggers: Vec<(Trigger, &'static str, Value)>,
    navigate: Server<SetBoolRequest, ServiceAnswer>,
    parameters: ParameterServers,
    teleop: TeleopConfig,
}

pub(super) fn server<Q, A>(
    node: &mut Node,
    private: &str,
    name: &str,
    (package, ty): (&str, &str),
) -> Result<Server<Q, A>, Ros2Error>
where
    Q: ros2_client::Message + Clone + 'static,
    A: ros2_client::Message + 'static,
{
    let qos = QosProfile::from(&reliable_qos());
    node.create_server(
        ServiceMapping::Enhanced,
        &super::name(private, name).map_err(Ros2Error::Create)?,
        &ServiceTypeName::new(package, ty),
        qos.clone(),
        qos,
    )
    .map_err(err)
}

impl Edges {
    pub fn create(
        node: &mut Node,
        ns: &str,
        private: &str,
        opts: &Ros2Options,
    ) -> Result<Self, Ros2Error> {
        // Best effort takes both kinds of publisher (teleop_twist_keyboard's is reliable).
        let cmd_vel = subscription(
            node,
            ns,
            "cmd_vel",
            ("geometry_msgs", "Twist"),
            &sensor_qos(),
        )?;
        let goal = subscription(
            node,
            ns,
            "goal_pose",
            ("geometry_msgs", "PoseStamped"),
            &sensor_qos(),
        )?;
        let triggers = triggers()
            .into_iter()
            .map(|(name, method, params)| {
                server(node, private, &name, ("std_srvs", "Trigger")).map(|s| (s, method, params))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            cmd_vel,
            goal,
            triggers,
            navigate: server(node, private, "navigate", ("std_srvs", "SetBool"))?,
            parameters: ParameterServers::create(node, private)?,
            teleop: opts.teleop.clone(),
        })
    }

    /// Serves them in `tasks` as `operator`'s edges, recording on `actions`.
    pub fn start(self, operator: Operator, actions: Option<Actions>, tasks: &mut JoinSet<()>) {
        let station = Station::new(StationConfig {
            token: None,
            teleop: self.teleop,
        });
        station.bind(operator);
        let op = Arc::new(Operating {
            station,
            // DDS has no authentication: whoever reaches the domain may operate.
            access: Access::new(None),
            actions: actions.unwrap_or_else(Actions::off),
        });
        for (server, method, params) in self.triggers {
            tasks.spawn(serve_trigger(server, op.clone(), method, params));
        }
        tasks.spawn(serve_navigate(self.navigate, op.clone()));
        tasks.spawn(read_goals(self.goal, op.clone()));
        self.parameters.start(op.clone(), tasks);
        tasks.spawn(drive(self.cmd_vel, op));
    }
}

fn answer(a: Result<Value, OperatorError>) -> ServiceAnswer {
    match a {
        Ok(v) => ServiceAnswer {
            success: true,
            message: v.to_string(),
        },
        Err(e) => ServiceAnswer {
            success: false,
            message: e.to_string(),
        },
    }
}

/// Answers `server`'s requests with `answer`, one at a time, while the task runs. A
/// request that cannot be read is skipped; a client gone before its answer is no reason
/// to stop serving.
pub(super) async fn serve<Q, A, F, Fut>(server: Server<Q, A>, mut answer: F)
where
    Q: ros2_client::Message + Clone + 'static,
    A: ros2_client::Message + 'static,
    F: FnMut(Q) -> Fut,
    Fut: std::future::Future<Output = A>,
{
    loop {
        let Ok((id, req)) = server.async_receive_request().await else {
            continue;
        };
        let a = answer(req).await;
        let _ = server.async_send_response(id, a).await;
    }
}

async fn serve_trigger(server: Trigger, op: Arc<Operating>, method: &'static str, params: Value) {
    serve(server, |_: Empty| {
        let (op, params) = (op.clone(), params.clone());
        async move { answer(op.call_as(WHO, method, params).await) }
    })
    .await;
}

async fn serve_navigate(server: Server<SetBoolRequest, ServiceAnswer>, op: Arc<Operating>) {
    serve(server, |req: SetBoolRequest| {
        let op = op.clone();
        async move {
            let params = if req.data {
                // Along the body's heading now (the socket's `navigate` takes any).
                match op.station.snapshot() {
                    Some(s) if s.body.valid => json!({ "heading_rad": s.body.heading_rad }),
                    _ => json!({ "heading_rad": null }),
                }
            } else {
                json!({ "off": true })
            };
            answer(op.call_as(WHO, "navigate", params).await)
        }
    })
    .await;
}

/// `goal_pose`: each goal starts navigating to its x, y (the position source's world;
/// its frame is logged, not checked: the daemon knows no frame but the source's).
async fn read_goals(sub: Subscription<PoseStamped>, op: Arc<Operating>) {
    loop {
        let Ok((m, _)) = sub.async_take().await else {
            continue;
        };
        let (x, y) = (m.pose.position.x, m.pose.position.y);
        let params = json!({ "goal_m": [x, y] });
        match op.call_as(WHO, "navigate", params).await {
            Ok(_) => tracing::info!(
                "navigating to the goal ({x:.3}, {y:.3}) from goal_pose (frame {:?})",
                m.header.frame_id
            ),
            Err(e) => tracing::warn!("goal_pose ({x}, {y}): {e}"),
        }
    }
}

/// `/cmd_vel`'s client: every ROS 2 publisher is [`WHO`]; a refusal is logged, at most
/// every few seconds.
#[derive(Clone, Default)]
struct CmdVel {
    last_told_ns: Arc<AtomicU64>,
}

/// Refusals to `/cmd_vel` are logged at most this often, ns.
const TELL_EVERY_NS: u64 = 5_000_000_000;

impl TeleopClient for CmdVel {
    fn name(&self) -> String {
        WHO.into()
    }

    fn tell(&self, message: String) {
        let now = unix_ns();
        let last = self.last_told_ns.load(Relaxed);
        if now.saturating_sub(last) >= TELL_EVERY_NS {
            self.last_told_ns.store(now, Relaxed);
            tracing::warn!("ros2 /cmd_vel: {message}");
        }
    }
}

/// A `geometry_msgs/Twist` as the station's twist (refused: not finite).
fn twist(m: &Twist) -> Result<teleop::Twist, String> {
    let (l, a) = (m.linear, m.angular);
    if [l.x, l.y, l.z, a.x, a.y, a.z].iter().all(|x| x.is_finite()) {
        Ok(teleop::Twist {
            forward: l.x,
            turn: a.z,
        })
    } else {
        Err("a twist with a non-finite number is refused".into())
    }
}

async fn drive(sub: Subscription<Twist>, op: Arc<Operating>) {
    let worker = DriveWorker::start(op);
    let client = CmdVel::default();
    loop {
        let Ok((m, _)) = sub.async_take().await else {
            continue;
        };
        match twist(&m) {
            Ok(t) => worker.offer(client.clone(), t),
            Err(e) => client.tell(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros2::msg::Vector3;

    #[test]
    fn every_gait_has_a_service_and_a_twist_must_be_finite() {
        let t = triggers();
        assert!(
            t.iter()
                .any(|(n, m, p)| n == "gait/rolling" && *m == "gait.set" && p["gait"] == "rolling")
        );
        assert!(t.iter().any(|(n, m, _)| n == "stop" && *m == "gait.stop"));
        assert_eq!(t.len(), 8 + GaitKind::ALL.len());
        let mut m = Twist::default();
        m.linear.x = 0.5;
        m.angular.z = -0.2;
        let tw = twist(&m).unwrap();
        assert_eq!((tw.forward, tw.turn), (0.5, -0.2));
        m.angular = Vector3 {
            x: f64::NAN,
            ..Vector3::default()
        };
        assert!(twist(&m).is_err());
    }
}
