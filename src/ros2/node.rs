//! The node and its thread (`snaked-ros2`). The thread publishes each frame the sink
//! hands it (joints, and at their own rates the IMUs, odometry and transforms); a
//! one-worker tokio runtime beside it runs the node's background work (discovery, the
//! graph), `/diagnostics` and `~/state`, the external pose's subscription and, with
//! `operate`, the operator's edges (`super::operate`). RustDDS allocates and runs
//! threads of its own: none of it touches the loop.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, OnceLock};
use std::thread::JoinHandle;
use std::time::Duration;

use ros2_client::ros2::{QosPolicies, QosPolicyBuilder, policy};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Node, NodeName, NodeOptions, Publisher, QosProfile,
    Subscription,
};

use super::msg::{
    DiagnosticArray, Imu, JointState, Odometry, PoseStamped, StringMsg, TfMessage, Time,
};
use super::sink::{Frame, Sink};
use super::status::{Diagnostics, NodeCounts};
use super::{Ros2Handle, Ros2Options, operate, publish};
use crate::controller_interface::BodyEstimate;
use crate::estimation::external_pose::ExternalFix;
use crate::operator::Operator;

/// What the node counts.
#[derive(Debug, Default)]
pub struct BridgeCounters {
    /// Frames published (each one's joint states).
    pub published: AtomicU64,
    /// Frames the node's channel had no room for.
    pub dropped: AtomicU64,
    pub publish_errors: AtomicU64,
}

#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    #[error("ROS 2 node: {0}")]
    Create(String),
}

pub(super) fn err(e: impl std::fmt::Debug) -> Ros2Error {
    Ros2Error::Create(format!("{e:?}"))
}

/// Frames waiting for the node's thread at most.
const QUEUE: usize = 64;

/// Sensor topics: best-effort, keep the last (REP-2003's sensor-data profile).
pub(super) fn sensor_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth: 5 })
        .reliability(policy::Reliability::BestEffort)
        .durability(policy::Durability::Volatile)
        .build()
}

/// State topics: reliable, the last one kept for late subscribers (`/robot_description`,
/// `~/state`).
pub(super) fn latched_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth: 1 })
        .reliability(policy::Reliability::Reliable {
            max_blocking_time: ros2_client::ros2::Duration::from_millis(100),
        })
        .durability(policy::Durability::TransientLocal)
        .build()
}

/// Reliable, volatile, the last ten (`/diagnostics`, `/tf`, services).
pub(super) fn reliable_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth: 10 })
        .reliability(policy::Reliability::Reliable {
            max_blocking_time: ros2_client::ros2::Duration::from_millis(100),
        })
        .durability(policy::Durability::Volatile)
        .build()
}

fn topic(
    node: &mut Node,
    ns: &str,
    name: &str,
    (package, ty): (&str, &str),
    qos: &QosPolicies,
) -> Result<ros2_client::dds::rustdds::Topic, Ros2Error> {
    let name = super::name(ns, name).map_err(Ros2Error::Create)?;
    node.create_topic(
        &name,
        MessageTypeName::new(package, ty),
        &QosProfile::from(qos),
    )
    .map_err(err)
}

pub(super) fn publisher<M: serde::Serialize>(
    node: &mut Node,
    ns: &str,
    name: &str,
    ty: (&str, &str),
    qos: &QosPolicies,
) -> Result<Publisher<M>, Ros2Error> {
    let t = topic(node, ns, name, ty, qos)?;
    node.create_publisher::<M>(&t, None).map_err(err)
}

pub(super) fn subscription<M: 'static>(
    node: &mut Node,
    ns: &str,
    name: &str,
    ty: (&str, &str),
    qos: &QosPolicies,
) -> Result<Subscription<M>, Ros2Error> {
    let t = topic(node, ns, name, ty, qos)?;
    node.create_subscription::<M>(&t, None).map_err(err)
}

/// The topics the frames are published on.
struct FramePublishers {
    joints: Publisher<JointState>,
    imus: Vec<(Publisher<Imu>, String)>,
    odom: Publisher<Odometry>,
    tf: Publisher<TfMessage>,
}

/// What the runtime's tasks publish and read.
pub(super) struct Background {
    pub diagnostics: Publisher<DiagnosticArray>,
    pub state: Publisher<StringMsg>,
    pub pose: Option<Subscription<PoseStamped>>,
    pub operate: Option<operate::Edges>,
}

/// The node's thread; dropping it stops and joins the thread.
pub(super) struct NodeThread {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for NodeThread {
    fn drop(&mut self) {
        self.stop.store(true, Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Starts the node: joint names `names` (the URDF's joints), `urdf` on
/// `/robot_description`, external poses (`pose_topic`) into the operator API's pose
/// input once it is bound. Errors (a bad name, DDS that cannot start) come back here.
pub fn start(
    opts: &Ros2Options,
    names: Vec<String>,
    urdf: String,
) -> Result<(Sink, Ros2Handle), Ros2Error> {
    let context =
        Context::with_options(ContextOptions::new().domain_id(opts.domain_id)).map_err(err)?;
    let node_name = NodeName::new(&opts.namespace, &opts.node_name).map_err(err)?;
    let mut node = context
        .new_node(
            node_name.clone(),
            NodeOptions::new()
                .enable_rosout(false)
                .start_parameter_services(false),
        )
        .map_err(err)?;
    let ns = opts.namespace.as_str();
    // The node's own topics (`~/state`) and services are under its full name.
    let private = node_name.fully_qualified_name();
    let sensor = sensor_qos();
    let frames = FramePublishers {
        joints: publisher(
            &mut node,
            ns,
            "joint_states",
            ("sensor_msgs", "JointState"),
            &sensor,
        )?,
        imus: (0..names.len())
            .map(|k| {
                let topic = format!("imu/{}/data_raw", publish::topic_token(&names[k]));
                publisher(&mut node, ns, &topic, ("sensor_msgs", "Imu"), &sensor)
                    .map(|p| (p, publish::module_frame(k)))
            })
            .collect::<Result<_, _>>()?,
        odom: publisher(&mut node, ns, "odom", ("nav_msgs", "Odometry"), &sensor)?,
        tf: publisher(
            &mut node,
            "/",
            "tf",
            ("tf2_msgs", "TFMessage"),
            &reliable_qos(),
        )?,
    };
    let description: Publisher<StringMsg> = publisher(
        &mut node,
        ns,
        "robot_description",
        ("std_msgs", "String"),
        &latched_qos(),
    )?;
    let pose = match &opts.pose_topic {
        Some(topic) => Some(subscription(
            &mut node,
            ns,
            topic,
            ("geometry_msgs", "PoseStamped"),
            &sensor,
        )?),
        None => None,
    };
    let background = Background {
        diagnostics: publisher(
            &mut node,
            "/",
            "diagnostics",
            ("diagnostic_msgs", "DiagnosticArray"),
            &reliable_qos(),
        )?,
        state: publisher(
            &mut node,
            &private,
            "state",
            ("std_msgs", "String"),
            &latched_qos(),
        )?,
        pose,
        operate: if opts.operate {
            Some(operate::Edges::create(&mut node, ns, &private, opts)?)
        } else {
            None
        },
    };
    let spinner = node.spinner().map_err(err)?;
    let (tx, rx) = crossbeam_channel::bounded::<Box<Frame>>(QUEUE);
    let counters = Arc::new(BridgeCounters::default());
    let handle = Ros2Handle {
        counters: counters.clone(),
        operator: Arc::new(OnceLock::new()),
    };
    let actions = Arc::new(OnceLock::new());
    let stop = Arc::new(AtomicBool::new(false));
    let rates = Rates::new(opts);
    let (thread_stop, thread_handle, thread_actions) =
        (stop.clone(), handle.clone(), actions.clone());
    let thread = std::thread::Builder::new()
        .name("snaked-ros2".into())
        .spawn(move || {
            let rt = match tokio::runtime::Builder::new_multi_thread()
                .worker_threads(1)
                .thread_name("snaked-ros2-spin")
                .enable_all()
                .build()
            {
                Ok(rt) => rt,
                Err(e) => return tracing::error!("ROS 2 node: no runtime: {e}"),
            };
            rt.spawn(spinner.spin());
            if description.publish(StringMsg { data: urdf }).is_err() {
                thread_handle.counters.publish_errors.fetch_add(1, Relaxed);
            }
            let (end, ended) = tokio::sync::oneshot::channel();
            let background = rt.spawn(run_background(
                background,
                thread_handle.clone(),
                thread_actions,
                ended,
            ));
            publish_frames(
                &rx,
                &frames,
                names,
                rates,
                &thread_handle.counters,
                &thread_stop,
            );
            // Every reader, writer and task before the node, the node before its context.
            drop((frames, description));
            let _ = end.send(());
            let _ = rt.block_on(background);
            drop(node);
            rt.shutdown_timeout(Duration::from_millis(200));
        })
        .map_err(|e| Ros2Error::Create(format!("no thread: {e}")))?;
    let sink = Sink {
        tx,
        period_ns: rates.joints_ns,
        next_ns: 0,
        counters,
        stamps: Default::default(),
        actions,
        _node: NodeThread {
            stop,
            thread: Some(thread),
        },
    };
    Ok((sink, handle))
}

/// The topics' periods, ns of loop time.
#[derive(Debug, Clone, Copy)]
struct Rates {
    joints_ns: u64,
    imu_ns: u64,
    odometry_ns: u64,
}

impl Rates {
    fn new(o: &Ros2Options) -> Self {
        let ns = |hz: f64| (1e9 / hz.max(0.1)) as u64;
        let joints_ns = ns(o.joint_states_rate_hz);
        Self {
            joints_ns,
            imu_ns: ns(o.imu_rate_hz).max(joints_ns),
            odometry_ns: ns(o.odometry_rate_hz).max(joints_ns),
        }
    }
}

/// Whether a topic of period `period_ns` is due at `t_ns` (its next time moved on).
fn due(next_ns: &mut u64, t_ns: u64, period_ns: u64) -> bool {
    if t_ns + period_ns / 4 < *next_ns {
        return false;
    }
    *next_ns = (*next_ns + period_ns).max(t_ns + period_ns / 2);
    true
}

/// The frame loop: until the sink is dropped (or `stop`).
fn publish_frames(
    rx: &crossbeam_channel::Receiver<Box<Frame>>,
    p: &FramePublishers,
    names: Vec<String>,
    rates: Rates,
    counters: &BridgeCounters,
    stop: &AtomicBool,
) {
    let mut joints = JointState {
        name: names,
        ..JointState::default()
    };
    let (mut next_imu, mut next_odom) = (0u64, 0u64);
    let mut last_body: Option<(BodyEstimate, u64)> = None;
    let count = |ok: bool| {
        if !ok {
            counters.publish_errors.fetch_add(1, Relaxed);
        }
    };
    while !stop.load(Relaxed) {
        let f = match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(f) => f,
            Err(crossbeam_channel::RecvTimeoutError::Timeout) => continue,
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
        };
        let stamp = Time::from_unix_ns(f.unix_ns);
        let rec = &f.rec;
        publish::joint_state(rec, stamp, &mut joints);
        match p.joints.publish(joints.clone()) {
            Ok(()) => counters.published.fetch_add(1, Relaxed),
            Err(_) => counters.publish_errors.fetch_add(1, Relaxed),
        };
        if due(&mut next_imu, rec.t_ns, rates.imu_ns) {
            for (k, (imu, frame)) in p.imus.iter().enumerate().take(rec.joints().len()) {
                count(imu.publish(publish::imu(rec, k, stamp, frame)).is_ok());
            }
        }
        if due(&mut next_odom, rec.t_ns, rates.odometry_ns) {
            let twist = last_body.and_then(|(b, t)| {
                publish::chassis_twist(&b, &rec.body, rec.t_ns.saturating_sub(t) as f64 * 1e-9)
            });
            last_body = Some((rec.body, rec.t_ns));
            if let Some(o) = publish::odometry(&rec.body, twist, stamp) {
                count(p.odom.publish(o).is_ok());
                let transforms = publish::transforms(&rec.body, stamp);
                count(p.tf.publish(TfMessage { transforms }).is_ok());
            }
        }
    }
}

/// Wall-clock time, ns since the Unix epoch.
pub(super) fn unix_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// The runtime's work, once the operator API is bound: the pose input, diagnostics,
/// state and (with `operate`) the operator's edges. Until `stop`, when every task ends
/// (and drops its readers and writers) before this returns.
async fn run_background(
    b: Background,
    handle: Ros2Handle,
    actions: Arc<OnceLock<crate::station::actions::Actions>>,
    stop: tokio::sync::oneshot::Receiver<()>,
) {
    let mut tasks = tokio::task::JoinSet::new();
    let bound = async {
        loop {
            if let Some(op) = handle.operator.get() {
                break op.clone();
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    };
    tokio::pin!(stop);
    let operator = tokio::select! {
        op = bound => op,
        _ = &mut stop => return,
    };
    if let Some(sub) = b.pose {
        tasks.spawn(read_poses(sub, operator.clone()));
    }
    if let Some(edges) = b.operate {
        edges.start(operator.clone(), actions.get().cloned(), &mut tasks);
    }
    tasks.spawn(publish_state(operator.clone(), b.state));
    let counters = handle.counters.clone();
    tasks.spawn(publish_diagnostics(operator, b.diagnostics, counters));
    let _ = stop.await;
    tasks.shutdown().await;
}

/// Poses from the topic into the operator API's pose input (a refusal logged, at
/// most every few seconds: a source at 100 Hz would flood the log).
async fn read_poses(sub: Subscription<PoseStamped>, op: Operator) {
    let mut last_told = 0u64;
    loop {
        let Ok((m, _)) = sub.async_take().await else {
            continue;
        };
        let (p, q) = (m.pose.position, m.pose.orientation);
        let fix = ExternalFix {
            stamp_unix_ns: m.header.stamp.unix_ns(),
            position_m: [p.x, p.y, p.z],
            orientation_wxyz: Some([q.w, q.x, q.y, q.z]),
            position_sd_m: None,
            source: format!("ros2 ({})", m.header.frame_id),
        };
        if let Err(e) = op.external_pose(&fix) {
            let now = unix_ns();
            if now.saturating_sub(last_told) > 5_000_000_000 {
                last_told = now;
                tracing::warn!("{e}");
            }
        }
    }
}

async fn publish_diagnostics(
    op: Operator,
    publisher: Publisher<DiagnosticArray>,
    counters: Arc<BridgeCounters>,
) {
    let mut d = Diagnostics::default();
    let mut tick = tokio::time::interval(Duration::from_secs(1));
    loop {
        tick.tick().await;
        let now = unix_ns();
        let mut counts = NodeCounts {
            published: counters.published.load(Relaxed),
            dropped: counters.dropped.load(Relaxed),
            publish_errors: counters.publish_errors.load(Relaxed),
            ..NodeCounts::default()
        };
        if let Some(p) = op.pose_counters() {
            counts.poses_received = p.received.load(Relaxed);
            counts.poses_refused = p.refused.load(Relaxed);
            let last = p.last_unix_ns.load(Relaxed);
            counts.pose_age_s = (last > 0).then(|| now.saturating_sub(last) as f64 * 1e-9);
        }
        let report = d.report(&op.snapshot(), &counts, Time::from_unix_ns(now));
        if publisher.publish(report).is_err() {
            counters.publish_errors.fetch_add(1, Relaxed);
        }
    }
}

/// `~/state`, twice a second.
async fn publish_state(op: Operator, publisher: Publisher<StringMsg>) {
    let mut snapshots = op.subscribe(Duration::from_millis(500));
    while snapshots.changed().await.is_ok() {
        let s = snapshots.borrow_and_update().clone();
        let controller =
            crate::socket::controller_views::telemetry_view(&s.controller, op.catalog());
        let data = super::status::state(&s, controller);
        let _ = publisher.publish(StringMsg { data });
    }
}
