//! What the methods answer: JSON views of the loop's latest snapshot.
//! Non-finite numbers (a limp joint's NaN set-point, the infinite feedback age
//! before the first feedback) come out as `null`.
use serde_json::{Value, json};

use super::DaemonInfo;
use super::controller_views::telemetry_view;
use crate::controller_interface::catalog::Catalog;
use crate::gait::{GaitKind, GaitTable};
use crate::rt::telemetry::Snapshot;

/// `status`: mode, gait, blend, loop time, counters and a compact joint summary.
pub(crate) fn status(s: &Snapshot, info: &DaemonInfo, catalog: &Catalog) -> Value {
    json!({
        "mode": s.mode,
        "reason": s.reason,
        "gait": s.gait,
        "blend_progress": s.blend_progress,
        "blend_time_s": s.blend_time_s,
        "motion": motion_view(s),
        "t_s": s.t_s,
        "cycle": s.cycle,
        "modules": s.joints.len(),
        "requests_applied": s.requests_applied,
        "requests_refused": s.requests_refused,
        "joints": joints_summary(s),
        "controller": telemetry_view(&s.controller, catalog),
        "body": body_view(&s.body),
        "external_pose": s.body.fix,
        "world": s.body.world,
        "progress": s.progress,
        "navigator": s.navigator,
        "guard": s.guard,
        "daemon": info,
    })
}

/// Who drives (`operator::driver`): `null` when nobody does.
pub(crate) fn driver(d: Option<&crate::operator::driver::Driver>) -> Value {
    match d {
        None => Value::Null,
        Some(d) => json!({ "client": d.who, "idle_s": d.idle_s, "expires_in_s": d.expires_in_s }),
    }
}

/// Whether the gait moves (`gait.stop`, the dead-man's controlled stop).
fn motion_view(s: &Snapshot) -> Value {
    json!({ "state": s.motion, "rate": s.gait_rate })
}

/// The body estimate (docs/estimation.md): its frame and heading while valid; only
/// `valid: false` before the estimator has settled or when its input was not finite.
/// The outside source's fix and position are `external_pose` and `world` of `status`.
fn body_view(b: &crate::controller_interface::BodyEstimate) -> Value {
    if !b.valid {
        return json!({ "valid": false });
    }
    let mut v = json!(b);
    if let Some(o) = v.as_object_mut() {
        o.remove("fix");
        o.remove("world");
    }
    v
}

/// Extremes over the joints plus their positions and torques as plain arrays.
fn joints_summary(s: &Snapshot) -> Value {
    let max_abs = |f: fn(&crate::rt::telemetry::JointTelemetry) -> f64| {
        s.joints
            .iter()
            .map(|j| f(j).abs())
            .filter(|v| !v.is_nan())
            .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
    };
    let tracking = s
        .joints
        .iter()
        .map(|j| (j.setpoint_rad - j.position_rad).abs())
        .filter(|v| v.is_finite())
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))));
    json!({
        "position_rad": s.joints.iter().map(|j| j.position_rad).collect::<Vec<_>>(),
        "torque_nm": s.joints.iter().map(|j| j.torque_nm).collect::<Vec<_>>(),
        "max_abs_torque_nm": max_abs(|j| j.torque_nm),
        "max_abs_velocity_rad_s": max_abs(|j| j.velocity_rad_s),
        "max_tracking_error_rad": tracking,
        "max_feedback_age_s": max_abs(|j| j.feedback_age_s),
    })
}

/// `gait.list`: every gait, which one is active, and its params.
pub(crate) fn gait_list(s: &Snapshot) -> Value {
    let gaits: Vec<Value> = GaitKind::ALL
        .iter()
        .map(|&k| {
            json!({
                "name": k.name(),
                "active": k == s.gait,
                "params": s.params.get(k),
            })
        })
        .collect();
    json!({ "active": s.gait, "gaits": gaits })
}

/// `params.get`: one gait's params, or all of them, plus the blend time.
pub(crate) fn params(table: &GaitTable, blend_time_s: f64, gait: Option<GaitKind>) -> Value {
    match gait {
        Some(k) => json!({
            "gait": k,
            "params": table.get(k),
            "blend_time_s": blend_time_s,
        }),
        None => {
            let all: serde_json::Map<String, Value> = GaitKind::ALL
                .iter()
                .map(|&k| (k.name().to_owned(), json!(table.get(k))))
                .collect();
            json!({ "gaits": all, "blend_time_s": blend_time_s })
        }
    }
}

/// `stats`: the loop's timing report, the bus counters, loop time.
pub(crate) fn stats(s: &Snapshot) -> Value {
    json!({
        "cycles": s.stats.cycles,
        "t_s": s.t_s,
        "loop": s.stats.report(),
        "bus": s.bus,
        "requests_applied": s.requests_applied,
        "requests_refused": s.requests_refused,
        "guard": s.guard,
        "record_dropped": s.record_dropped,
    })
}

/// The params of one `telemetry` stream message.
pub(crate) fn telemetry(s: &Snapshot, catalog: &Catalog) -> Value {
    json!({
        "t_s": s.t_s,
        "cycle": s.cycle,
        "mode": s.mode,
        "reason": s.reason,
        "gait": s.gait,
        "blend_progress": s.blend_progress,
        "motion": motion_view(s),
        "joints": s.joints,
        "controller": telemetry_view(&s.controller, catalog),
        "body": body_view(&s.body),
        "progress": s.progress,
        "navigator": s.navigator,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::GaitParams;
    use crate::rt::telemetry::JointTelemetry;

    fn snapshot() -> Snapshot {
        let table = GaitTable {
            gaits: [GaitParams::default(); 6],
        };
        let mut s = Snapshot::new(3, GaitKind::Rolling, table, 2.0);
        s.joints[0] = JointTelemetry {
            setpoint_rad: f64::NAN,
            position_rad: 0.1,
            velocity_rad_s: -0.5,
            torque_nm: -2.0,
            feedback_age_s: f64::INFINITY,
        };
        s.joints[1].setpoint_rad = 0.3;
        s.joints[1].torque_nm = 1.0;
        s
    }

    #[test]
    fn status_summarises_joints_and_hides_non_finite_values() {
        let info = DaemonInfo::default();
        let v = status(&snapshot(), &info, &Catalog::default());
        assert_eq!(v["mode"], "limp");
        assert_eq!(v["gait"], "rolling");
        assert_eq!(v["modules"], 3);
        assert_eq!(v["joints"]["max_abs_torque_nm"], 2.0);
        assert_eq!(v["joints"]["max_tracking_error_rad"], 0.3);
        assert_eq!(v["joints"]["max_feedback_age_s"], Value::Null, "inf → null");
        assert_eq!(v["body"], json!({"valid": false}), "no estimate yet");
        assert_eq!(
            v["progress"],
            json!({"stuck": false, "reason": "measuring", "repeat_error": null, "measuring_s": 0.0}),
            "nothing measured: NaN → null"
        );
        let line = serde_json::to_string(&v).unwrap();
        assert!(!line.contains("NaN") && !line.contains("inf"), "{line}");
    }

    #[test]
    fn gait_list_marks_the_active_gait() {
        let v = gait_list(&snapshot());
        let gaits = v["gaits"].as_array().unwrap();
        assert_eq!(gaits.len(), GaitKind::ALL.len());
        let active: Vec<_> = gaits.iter().filter(|g| g["active"] == true).collect();
        assert_eq!(active.len(), 1);
        assert_eq!(active[0]["name"], "rolling");
        assert!(active[0]["params"]["taper"].is_number());
    }

    #[test]
    fn params_one_or_all() {
        let s = snapshot();
        let one = params(&s.params, 2.0, Some(GaitKind::Slithering));
        assert_eq!(one["gait"], "slithering");
        assert_eq!(one["blend_time_s"], 2.0);
        let all = params(&s.params, 2.0, None);
        assert_eq!(all["gaits"].as_object().unwrap().len(), 6);
    }
}
