//! What the navigator is doing, as the loop publishes it (`status.navigation`,
//! telemetry, the recording's and the live view's `/navigation`): whoever runs the
//! navigator (the daemon's control side, a lab trial) tells the loop with a
//! `LoopRequest::Navigation` at each change, so everything that reports the loop's
//! cycles reports the navigator with them, and the request itself is an event in the
//! recording.

use serde::{Deserialize, Serialize};

use super::navigator::{Choice, Navigator, Why};

/// Why navigation stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The operator turned it off (`navigate` `off`).
    Off,
    /// The operator sent a request that drives the robot (gait, controller, heading,
    /// hold, limp, e-stop): theirs wins.
    Operator,
    /// The pose estimate was not valid for too long: the navigator cannot steer.
    EstimateInvalid,
    /// The loop stopped running the gait (hold, limp, e-stop or the failsafe).
    NotRunning,
    /// The loop refused one of the navigator's requests.
    Refused,
    /// It reached the goal (by position); the robot holds.
    Arrived,
}

impl StopReason {
    pub fn explain(self) -> &'static str {
        match self {
            StopReason::Off => "turned off by the operator",
            StopReason::Operator => "the operator took over (a request that drives the robot)",
            StopReason::EstimateInvalid => {
                "the pose estimate is not valid: the navigator cannot steer"
            }
            StopReason::NotRunning => {
                "the loop stopped running the gait (hold, limp, e-stop or the failsafe)"
            }
            StopReason::Refused => "the loop refused one of the navigator's requests",
            StopReason::Arrived => "it reached the goal: the robot holds",
        }
    }
}

/// The navigator's state as the loop reports it. `Copy`, so it crosses the loop's
/// channel and sits in every cycle's record without allocating.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NavigatorState {
    /// Navigating now.
    pub active: bool,
    /// The direction of travel, the pose estimate's world, rad (NaN before the first
    /// `navigate`; reported as null).
    #[serde(with = "nan_as_null")]
    pub travel_rad: f64,
    /// What it runs and why (none before its first decision).
    pub choice: Option<Choice>,
    pub why: Option<Why>,
    /// Changes of gait or controller since it started.
    pub switches: u32,
    /// Why it stopped (while not active; none if it never ran).
    pub stopped: Option<StopReason>,
    /// The goal, the position source's world, m (none: a direction only).
    pub goal_m: Option<[f64; 2]>,
    /// It steers by position now (a goal and a valid position); false: by heading only.
    pub by_position: bool,
    /// To the goal, and left of the line to it, m (null while not by position).
    #[serde(with = "nan_as_null")]
    pub distance_m: f64,
    #[serde(with = "nan_as_null")]
    pub cross_track_m: f64,
}

impl NavigatorState {
    pub const OFF: Self = Self {
        active: false,
        travel_rad: f64::NAN,
        choice: None,
        why: None,
        switches: 0,
        stopped: None,
        goal_m: None,
        by_position: false,
        distance_m: f64::NAN,
        cross_track_m: f64::NAN,
    };

    /// What `nav` does: running (`active`) or stopped for `stopped`.
    pub fn of(nav: &Navigator, active: bool, stopped: Option<StopReason>) -> Self {
        let current = nav.current();
        let course = nav.course();
        Self {
            active,
            travel_rad: nav.travel_rad(),
            choice: current.map(|c| c.0),
            why: current.map(|c| c.1),
            switches: nav.switches(),
            stopped,
            goal_m: nav.goal(),
            by_position: course.is_some(),
            distance_m: course.map_or(f64::NAN, |c| c.distance_m),
            cross_track_m: course.map_or(f64::NAN, |c| c.cross_track_m),
        }
    }

    /// A number for plots: [`Choice::code`] while active, else 0.
    pub fn choice_code(&self) -> f64 {
        match (self.active, self.choice) {
            (true, Some(c)) => c.code(),
            _ => 0.0,
        }
    }
}

impl Default for NavigatorState {
    fn default() -> Self {
        Self::OFF
    }
}

mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        match v.is_finite() {
            true => s.serialize_some(v),
            false => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serialises_without_nan_and_reads_back() {
        let off = serde_json::to_value(NavigatorState::OFF).unwrap();
        assert_eq!(off["travel_rad"], serde_json::Value::Null);
        assert_eq!(off["active"], false);
        let on = NavigatorState {
            active: true,
            travel_rad: 0.5,
            choice: Some(Choice::Sidewind),
            why: Some(Why::Start),
            switches: 2,
            stopped: None,
            goal_m: Some([3.0, -1.0]),
            by_position: true,
            distance_m: 2.5,
            cross_track_m: -0.25,
        };
        let v = serde_json::to_value(on).unwrap();
        assert_eq!(v["choice"], "sidewind");
        assert_eq!(v["why"], "start");
        let back: NavigatorState = serde_json::from_value(v).unwrap();
        assert_eq!(back, on);
        assert_eq!(on.choice_code(), Choice::Sidewind.code());
        assert_eq!(NavigatorState::OFF.choice_code(), 0.0);
    }
}
