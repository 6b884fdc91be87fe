//! `pose.external`: a fix from an outside position source (motion capture, visual
//! odometry, a total station) into the daemon's pose input (`Operator::external_pose`,
//! the path ROS 2's pose topic takes too). Not an act: a source needs no drive, and
//! the loop never waits for it.

use serde_json::{Value, json};

use super::api::{OperatorError, Params};
use crate::estimation::external_pose::ExternalFix;
use crate::operator::Operator;

/// `N` numbers from a JSON array (absent: `None`).
pub(crate) fn numbers<const N: usize>(
    name: &str,
    v: Option<Value>,
) -> Result<Option<[f64; N]>, OperatorError> {
    let Some(v) = v else { return Ok(None) };
    let bad = || OperatorError::invalid_params(format!("`{name}` must be {N} numbers"));
    let a = v.as_array().filter(|a| a.len() == N).ok_or_else(bad)?;
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().ok_or_else(bad)?;
    }
    Ok(Some(out))
}

/// Reads the params into a fix from `who` (the source's name unless `source` says).
pub fn parse(who: &str, mut p: Params) -> Result<ExternalFix, OperatorError> {
    let position = p.take_json("position_m")?;
    let position_m = match position.as_ref().and_then(Value::as_array).map(Vec::len) {
        Some(2) => numbers::<2>("position_m", position)?.map(|[x, y]| [x, y, 0.0]),
        _ => numbers::<3>("position_m", position)?,
    }
    .ok_or_else(|| {
        OperatorError::invalid_params("missing `position_m` ([x, y] or [x, y, z], m)")
    })?;
    let quaternion = numbers::<4>("orientation_wxyz", p.take_json("orientation_wxyz")?)?;
    let yaw = p.take_f64("yaw_rad")?;
    let orientation_wxyz = match (quaternion, yaw) {
        (Some(_), Some(_)) => {
            return Err(OperatorError::invalid_params(
                "give `orientation_wxyz` or `yaw_rad`, not both",
            ));
        }
        (Some(q), None) => Some(q),
        (None, Some(y)) => Some([(y / 2.0).cos(), 0.0, 0.0, (y / 2.0).sin()]),
        (None, None) => None,
    };
    let position_sd_m = p.take_f64("position_sd_m")?;
    let stamp_unix_ns = match p.take_f64("stamp_unix_s")? {
        Some(s) if s.is_finite() && s > 0.0 => (s * 1e9).round() as u64,
        Some(s) => {
            return Err(OperatorError::invalid_params(format!(
                "`stamp_unix_s` must be a positive time, not {s}"
            )));
        }
        None => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64),
    };
    let source = p.take_str("source")?.unwrap_or_else(|| who.to_owned());
    p.finish(&[
        "position_m",
        "orientation_wxyz",
        "yaw_rad",
        "position_sd_m",
        "stamp_unix_s",
        "source",
    ])?;
    Ok(ExternalFix {
        stamp_unix_ns,
        position_m,
        orientation_wxyz,
        position_sd_m,
        source,
    })
}

/// Carries `pose.external` out for `who`.
pub fn call(op: &Operator, who: &str, p: Params) -> Result<Value, OperatorError> {
    let fix = parse(who, p)?;
    let (t_s, latency_s) = op.external_pose(&fix)?;
    let number = op
        .pose_counters()
        .map_or(0, |c| c.received.load(std::sync::atomic::Ordering::Relaxed));
    Ok(json!({ "accepted": true, "number": number, "t_s": t_s, "latency_s": latency_s }))
}
