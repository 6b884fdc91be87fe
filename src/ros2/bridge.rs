//! The node's thread (`snaked-ros2`): a ROS 2 node (`ros2-client`, RustDDS; no ROS
//! installation) publishing what the recorder's writer hands it. The writer offers
//! each cycle to a [`Sink`], which keeps one in every `1 / rate` and hands it over a
//! bounded channel without waiting (a full channel drops it, counted): neither the
//! loop nor the writer ever waits on DDS, which allocates and runs its own threads.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::thread::JoinHandle;
use std::time::Duration;

use ros2_client::ros2::{QosPolicies, QosPolicyBuilder, policy};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile,
};

use super::msg::{Header, JointState, StringMsg, Time};
use crate::record::cycle::{CycleRecord, RECORD_MAX_MODULES};

/// What `[ros2]` asks of the node.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Options {
    pub domain_id: u16,
    /// The node's namespace ("/" or e.g. "/snake"); topics are under it.
    pub namespace: String,
    pub node_name: String,
    /// `/joint_states` rate, Hz (up to the loop's).
    pub joint_states_rate_hz: f64,
}

/// One cycle's joints as the node publishes them.
#[derive(Debug, Clone, Copy)]
pub struct JointFrame {
    pub unix_ns: u64,
    pub modules: usize,
    pub position: [f64; RECORD_MAX_MODULES],
    pub velocity: [f64; RECORD_MAX_MODULES],
    pub effort: [f64; RECORD_MAX_MODULES],
}

/// What the node counts.
#[derive(Debug, Default)]
pub struct BridgeCounters {
    pub published: AtomicU64,
    /// Frames the node's channel had no room for.
    pub dropped: AtomicU64,
    pub publish_errors: AtomicU64,
}

/// The writer's end: decimates to the rate and hands frames over without waiting.
/// Dropping it (the recorder finishing) closes the channel, then ends and joins the
/// node's thread.
pub struct Sink {
    // Dropped before `node`: the closed channel is what ends the node's thread.
    tx: crossbeam_channel::Sender<JointFrame>,
    period_ns: u64,
    next_ns: u64,
    counters: Arc<BridgeCounters>,
    _node: Bridge,
}

impl crate::record::CycleSink for Sink {
    /// Offers one recorded cycle, `unix_ns` its wall-clock stamp.
    fn cycle(&mut self, rec: &CycleRecord, unix_ns: u64) {
        if rec.t_ns < self.next_ns {
            return;
        }
        // The next one due a period on, without drifting back after a gap.
        self.next_ns = (self.next_ns + self.period_ns).max(rec.t_ns + self.period_ns / 2);
        let n = rec.modules.min(RECORD_MAX_MODULES);
        let mut f = JointFrame {
            unix_ns,
            modules: n,
            position: [0.0; RECORD_MAX_MODULES],
            velocity: [0.0; RECORD_MAX_MODULES],
            effort: [0.0; RECORD_MAX_MODULES],
        };
        for (i, j) in rec.joints[..n].iter().enumerate() {
            f.position[i] = j.position_rad as f64;
            f.velocity[i] = j.velocity_rad_s as f64;
            f.effort[i] = j.torque_nm as f64;
        }
        if self.tx.try_send(f).is_err() {
            self.counters.dropped.fetch_add(1, Relaxed);
        }
    }
}

/// The node's thread; dropping it stops and joins the thread.
struct Bridge {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    #[error("ROS 2 node: {0}")]
    Create(String),
}

fn err(e: impl std::fmt::Debug) -> Ros2Error {
    Ros2Error::Create(format!("{e:?}"))
}

/// Sensor topics: best-effort, keep the last (REP-2003's sensor-data profile).
fn sensor_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth: 5 })
        .reliability(policy::Reliability::BestEffort)
        .durability(policy::Durability::Volatile)
        .build()
}

/// Latched state (`/robot_description`): reliable, transient-local, the last one.
fn latched_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .history(policy::History::KeepLast { depth: 1 })
        .reliability(policy::Reliability::Reliable {
            max_blocking_time: ros2_client::ros2::Duration::from_millis(100),
        })
        .durability(policy::Durability::TransientLocal)
        .build()
}

fn publisher<M: serde::Serialize>(
    node: &mut Node,
    ns: &str,
    topic: &str,
    (package, ty): (&str, &str),
    qos: &QosPolicies,
) -> Result<Publisher<M>, Ros2Error> {
    let name = Name::new(ns, topic).map_err(err)?;
    let t = node
        .create_topic(
            &name,
            MessageTypeName::new(package, ty),
            &QosProfile::from(qos),
        )
        .map_err(err)?;
    node.create_publisher::<M>(&t, None).map_err(err)
}

/// Starts the node: joint names `names` (the URDF's joints), `urdf` on
/// `/robot_description`. Errors (a bad name, DDS that cannot start) come back here.
/// The counters stay readable after the sink is gone.
pub fn start(
    opts: &Ros2Options,
    names: Vec<String>,
    urdf: String,
) -> Result<(Sink, Arc<BridgeCounters>), Ros2Error> {
    let context =
        Context::with_options(ContextOptions::new().domain_id(opts.domain_id)).map_err(err)?;
    let node_name = NodeName::new(&opts.namespace, &opts.node_name).map_err(err)?;
    let mut node = context
        .new_node(node_name, NodeOptions::new().enable_rosout(false))
        .map_err(err)?;
    let ns = opts.namespace.as_str();
    let joints: Publisher<JointState> = publisher(
        &mut node,
        ns,
        "joint_states",
        ("sensor_msgs", "JointState"),
        &sensor_qos(),
    )?;
    let description: Publisher<StringMsg> = publisher(
        &mut node,
        ns,
        "robot_description",
        ("std_msgs", "String"),
        &latched_qos(),
    )?;
    let spinner = node.spinner().map_err(err)?;
    let (tx, rx) = crossbeam_channel::bounded::<JointFrame>(64);
    let counters = Arc::new(BridgeCounters::default());
    let stop = Arc::new(AtomicBool::new(false));
    let (thread_stop, thread_counters) = (stop.clone(), counters.clone());
    let thread = std::thread::Builder::new()
        .name("snaked-ros2".into())
        .spawn(move || {
            // The node's background work (graph, discovery) on a runtime of its own.
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
                thread_counters.publish_errors.fetch_add(1, Relaxed);
            }
            let mut msg = JointState {
                header: Header {
                    stamp: Time::default(),
                    frame_id: String::new(),
                },
                name: names,
                ..JointState::default()
            };
            while !thread_stop.load(Relaxed) {
                let f = match rx.recv_timeout(Duration::from_millis(50)) {
                    Ok(f) => f,
                    Err(crossbeam_channel::RecvTimeoutError::Timeout) => continue,
                    Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
                };
                let n = f.modules.min(msg.name.len());
                msg.header.stamp = Time::from_unix_ns(f.unix_ns);
                msg.position = f.position[..n].to_vec();
                msg.velocity = f.velocity[..n].to_vec();
                msg.effort = f.effort[..n].to_vec();
                match joints.publish(msg.clone()) {
                    Ok(()) => thread_counters.published.fetch_add(1, Relaxed),
                    Err(_) => thread_counters.publish_errors.fetch_add(1, Relaxed),
                };
            }
            drop(node);
            rt.shutdown_timeout(Duration::from_millis(200));
        })
        .map_err(|e| Ros2Error::Create(format!("no thread: {e}")))?;
    let period_ns = (1e9 / opts.joint_states_rate_hz.max(1.0)) as u64;
    let sink = Sink {
        tx,
        period_ns,
        next_ns: 0,
        counters: counters.clone(),
        _node: Bridge {
            stop,
            thread: Some(thread),
        },
    };
    Ok((sink, counters))
}

impl Drop for Bridge {
    fn drop(&mut self) {
        self.stop.store(true, Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
