//! The daemon's health and state as the node publishes them (pure, no DDS):
//! `/diagnostics` (`diagnostic_msgs/DiagnosticArray`, one status per part: the loop's
//! timing, the failsafe, the bus, the recorder, the node, the external pose input) and
//! `~/state` (`std_msgs/String`, JSON: gait, motion, controller, navigator), both from
//! the loop's snapshot. A counter that grew since the last report warns.

use serde_json::{Value, json};

use super::msg::{DiagnosticArray, DiagnosticStatus, Header, KeyValue, Time};
use crate::rt::telemetry::Snapshot;
use crate::safety::failsafe::Mode;

pub const OK: u8 = 0;
pub const WARN: u8 = 1;
pub const ERROR: u8 = 2;
pub const STALE: u8 = 3;

/// The node's own counters and its pose input's, as the diagnostics show them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NodeCounts {
    pub published: u64,
    pub dropped: u64,
    pub publish_errors: u64,
    /// External poses received and refused; the newest's age, s (`None`: none yet).
    pub poses_received: u64,
    pub poses_refused: u64,
    pub pose_age_s: Option<f64>,
}

/// The counters that warn when they grow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Growing {
    overruns: u64,
    bus_trouble: u64,
    record_dropped: u64,
    node_dropped: u64,
}

/// Builds the reports, remembering the counters of the last.
#[derive(Debug, Default)]
pub struct Diagnostics {
    last: Option<Growing>,
}

/// A pose older than this is stale, s.
pub const POSE_STALE_S: f64 = 1.0;

fn flat(prefix: &str, v: &Value, out: &mut Vec<KeyValue>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flat(&key, x, out);
            }
        }
        Value::String(s) => out.push(KeyValue {
            key: prefix.into(),
            value: s.clone(),
        }),
        other => out.push(KeyValue {
            key: prefix.into(),
            value: other.to_string(),
        }),
    }
}

fn status(level: u8, name: &str, message: String, values: Value) -> DiagnosticStatus {
    let mut kv = Vec::new();
    flat("", &values, &mut kv);
    DiagnosticStatus {
        level,
        name: format!("snaked: {name}"),
        message,
        hardware_id: "snaked".into(),
        values: kv,
    }
}

impl Diagnostics {
    /// The report on `s` and the node's `counts`, stamped `stamp`.
    pub fn report(&mut self, s: &Snapshot, counts: &NodeCounts, stamp: Time) -> DiagnosticArray {
        let b = &s.bus;
        let now = Growing {
            overruns: s.stats.overruns,
            bus_trouble: b.feedback_lost + b.send_errors + b.dropped + s.stats.bus_errors,
            record_dropped: s.record_dropped,
            node_dropped: counts.dropped,
        };
        let last = self.last.replace(now).unwrap_or(now);
        let grew = |f: fn(&Growing) -> u64| f(&now) > f(&last);
        let report = s.stats.report();
        let timing = status(
            if grew(|g| g.overruns) { WARN } else { OK },
            "loop",
            format!(
                "wake-up latency p99 {:.0} µs, {} overruns",
                report.wakeup_latency.p99_us, report.overruns
            ),
            json!({
                "cycles": report.cycles,
                "wakeup_latency_p50_us": report.wakeup_latency.p50_us,
                "wakeup_latency_p99_us": report.wakeup_latency.p99_us,
                "period_error_p50_us": report.period_error.p50_us,
                "period_error_p99_us": report.period_error.p99_us,
                "compute_p99_us": report.compute.p99_us,
                "bus_io_p99_us": report.bus_io.p99_us,
                "overruns": report.overruns,
                "skipped_periods": report.skipped_periods,
                "late_feedback": report.late_feedback,
            }),
        );
        let failsafe = status(
            match s.mode {
                Mode::Running => OK,
                Mode::Hold | Mode::Limp => WARN,
                Mode::EStop => ERROR,
            },
            "failsafe",
            format!("{:?} ({:?})", s.mode, s.reason).to_lowercase(),
            json!({ "mode": s.mode, "reason": s.reason }),
        );
        let bus = status(
            if grew(|g| g.bus_trouble) { WARN } else { OK },
            "bus",
            format!(
                "{} feedback received, {} lost, {} send errors",
                b.feedback_received, b.feedback_lost, b.send_errors
            ),
            json!(b),
        );
        let recorder = status(
            if grew(|g| g.record_dropped) { WARN } else { OK },
            "recorder",
            format!("{} items dropped", s.record_dropped),
            json!({ "dropped": s.record_dropped }),
        );
        let node = status(
            if grew(|g| g.node_dropped) { WARN } else { OK },
            "ros2 node",
            format!("{} published, {} dropped", counts.published, counts.dropped),
            json!({
                "published": counts.published,
                "dropped": counts.dropped,
                "publish_errors": counts.publish_errors,
            }),
        );
        let (level, message) = match counts.pose_age_s {
            None => (OK, "no external pose received".to_owned()),
            Some(age) if age > POSE_STALE_S => (STALE, format!("the last pose is {age:.1} s old")),
            Some(age) => (OK, format!("the last pose is {:.0} ms old", age * 1e3)),
        };
        let pose = status(
            level,
            "external pose",
            message,
            json!({
                "received": counts.poses_received,
                "refused": counts.poses_refused,
                "age_s": counts.pose_age_s,
            }),
        );
        DiagnosticArray {
            header: Header {
                stamp,
                frame_id: String::new(),
            },
            status: vec![timing, failsafe, bus, recorder, node, pose],
        }
    }
}

/// `~/state`: what the robot is doing, as JSON.
pub fn state(s: &Snapshot, controller: Value) -> String {
    json!({
        "mode": s.mode,
        "reason": s.reason,
        "gait": s.gait,
        "blend_progress": s.blend_progress,
        "motion": s.motion,
        "controller": controller,
        "progress": s.progress,
        "navigator": s.navigator,
    })
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::{GaitKind, GaitTable};

    fn level_of(a: &DiagnosticArray, name: &str) -> u8 {
        a.status
            .iter()
            .find(|s| s.name == format!("snaked: {name}"))
            .unwrap()
            .level
    }

    #[test]
    fn a_counter_that_grows_warns_once_and_modes_have_levels() {
        let mut s = Snapshot::new(4, GaitKind::Slithering, GaitTable::default(), 1.0);
        s.mode = Mode::Running;
        let mut d = Diagnostics::default();
        let counts = NodeCounts::default();
        let a = d.report(&s, &counts, Time::default());
        assert!(a.status.iter().all(|x| x.level == OK), "{a:?}");
        assert_eq!(a.status.len(), 6);
        s.record_dropped = 3;
        s.bus.feedback_lost = 1;
        let a = d.report(&s, &counts, Time::default());
        assert_eq!(level_of(&a, "recorder"), WARN);
        assert_eq!(level_of(&a, "bus"), WARN);
        assert_eq!(level_of(&a, "loop"), OK);
        let a = d.report(&s, &counts, Time::default());
        assert_eq!(level_of(&a, "recorder"), OK, "no longer growing");
        s.mode = Mode::EStop;
        let a = d.report(&s, &counts, Time::default());
        assert_eq!(level_of(&a, "failsafe"), ERROR);
        let kv = &a.status[2].values;
        assert!(
            kv.iter()
                .any(|k| k.key == "feedback_lost" && k.value == "1"),
            "{kv:?}"
        );
        let stale = NodeCounts {
            pose_age_s: Some(2.0),
            ..counts
        };
        assert_eq!(
            level_of(&d.report(&s, &stale, Time::default()), "external pose"),
            STALE
        );
    }

    #[test]
    fn the_state_names_the_gait_and_the_mode() {
        let s = Snapshot::new(4, GaitKind::Rolling, GaitTable::default(), 1.0);
        let v: Value = serde_json::from_str(&state(&s, Value::Null)).unwrap();
        assert_eq!(v["gait"], "rolling");
        assert_eq!(v["mode"], "limp");
    }
}
