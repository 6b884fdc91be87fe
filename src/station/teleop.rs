//! Teleop (pure, time as an argument): a twist in the shape Foxglove's Teleop panel
//! publishes (`geometry_msgs/Twist`: `linear.x` forward, `angular.z` turn left) becomes
//! the active gait's speed (its temporal frequency) and steering (slithering's lateral
//! offset, conical sidewinding's taper), as the operator API's typed acts
//! (`Act::SetParams`) — or, where the gait's controller declares it steers by a nominal
//! heading (anti-compliant sidewinding, a heading hold), the nominal heading led
//! `heading_lead_rad` per unit of turn ahead of the body's (`Act::SetHeading`); and a
//! **dead-man**: when twists stop coming for `timeout_s`
//! the gait makes a controlled stop (`gait.stop`: the whole body at rest within
//! `stop_s`, whatever the blend time), and after `hold_after_s` more the robot holds
//! (`arm` resumes). The next twist after a stop resumes the gait (`gait.resume`).

use serde::Deserialize;

use crate::gait::params::Field;
use crate::gait::{GaitKind, ParamPatch};
use crate::operator::Act;
use crate::rt::telemetry::Snapshot;

/// The teleop settings (`[foxglove]` `teleop_*`).
#[derive(Debug, Clone, PartialEq)]
pub struct TeleopConfig {
    /// The channel a client publishes twists on.
    pub topic: String,
    /// Twists expire after this long, s: the gait then runs at zero speed.
    pub timeout_s: f64,
    /// The dead-man's controlled stop brings the body to rest within this long, s.
    pub stop_s: f64,
    /// After that, the robot holds this much later, s.
    pub hold_after_s: f64,
    /// Temporal frequency per unit of `linear.x`, rad/s.
    pub speed_rad_s: f64,
    /// Largest |temporal frequency| a twist asks for, rad/s.
    pub max_speed_rad_s: f64,
    /// Slithering's lateral offset per unit of `angular.z`, rad (at most `max_offset_rad`).
    pub offset_rad: f64,
    pub max_offset_rad: f64,
    /// Sidewinding's taper per unit of `angular.z` (at most `max_taper`).
    pub taper: f64,
    pub max_taper: f64,
    /// Where the controller steers by a nominal heading: the nominal is the body's
    /// heading plus this per unit of `angular.z` (so holding "left" keeps it turning),
    /// rad, at most `max_heading_lead_rad`.
    pub heading_lead_rad: f64,
    pub max_heading_lead_rad: f64,
    /// A twist equal to the last one sent is re-sent no more often than this, s (the
    /// panel publishes at a fixed rate; the loop need not hear each).
    pub resend_s: f64,
}

impl Default for TeleopConfig {
    fn default() -> Self {
        Self {
            topic: "/cmd_vel".into(),
            timeout_s: 0.5,
            stop_s: crate::rt::gait_clock::DEFAULT_STOP_S,
            hold_after_s: 2.0,
            speed_rad_s: 1.0,
            max_speed_rad_s: 2.0,
            // The steering controller's limit: −4 to −15° a cycle on open ground.
            offset_rad: 0.2,
            max_offset_rad: 0.25,
            // ±0.4 turns sidewinding about 0.05 rad/s (docs/compliance.md).
            taper: 0.4,
            max_taper: 0.4,
            // Sidewinding turns back outside a 0.35 rad dead-band: lead past it.
            heading_lead_rad: 0.6,
            max_heading_lead_rad: 1.0,
            resend_s: 1.0,
        }
    }
}

impl TeleopConfig {
    pub fn check(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64, max: f64| {
            if v.is_finite() && v > 0.0 && v <= max {
                Ok(())
            } else {
                Err(format!("teleop {name} must be in (0, {max}], not {v}"))
            }
        };
        pos("timeout_s", self.timeout_s, 10.0)?;
        pos("hold_after_s", self.hold_after_s, 60.0)?;
        let (lo, hi) = crate::rt::gait_clock::STOP_TIME_RANGE_S;
        if !(lo..=hi).contains(&self.stop_s) {
            return Err(format!(
                "teleop stop_s must be in [{lo}, {hi}], not {}",
                self.stop_s
            ));
        }
        pos("speed_rad_s", self.speed_rad_s, 10.0)?;
        pos("max_speed_rad_s", self.max_speed_rad_s, 10.0)?;
        pos("offset_rad", self.offset_rad, 1.0)?;
        pos("max_offset_rad", self.max_offset_rad, 1.0)?;
        pos("taper", self.taper, 0.8)?;
        pos("max_taper", self.max_taper, 0.8)?;
        pos("heading_lead_rad", self.heading_lead_rad, 1.5)?;
        pos("max_heading_lead_rad", self.max_heading_lead_rad, 1.5)?;
        pos("resend_s", self.resend_s, 60.0)?;
        if !self.topic.starts_with('/') {
            return Err(format!(
                "teleop topic must start with '/', not {:?}",
                self.topic
            ));
        }
        Ok(())
    }
}

/// What a twist asks: forward speed and turn rate, in the panel's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Twist {
    pub forward: f64,
    pub turn: f64,
}

/// `geometry_msgs/Twist` as JSON, read strictly: unknown and duplicate keys refused.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TwistMsg {
    linear: Option<Vector3>,
    angular: Option<Vector3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Vector3 {
    x: Option<f64>,
    y: Option<f64>,
    z: Option<f64>,
}

impl Twist {
    /// From a JSON `geometry_msgs/Twist` (`{"linear": {"x": ..}, "angular": {"z": ..}}`;
    /// absent axes are 0, `y` and `z` of `linear` and `x`, `y` of `angular` are read
    /// and ignored). Refused: not JSON, not such an object (unknown or duplicate keys,
    /// neither `linear` nor `angular`), non-finite numbers.
    pub fn parse(payload: &[u8]) -> Result<Twist, String> {
        let m: TwistMsg = serde_json::from_slice(payload).map_err(|e| {
            format!(
                "a twist is JSON {{\"linear\": {{\"x\": ..}}, \"angular\": {{\"z\": ..}}}}: {e}"
            )
        })?;
        if m.linear.is_none() && m.angular.is_none() {
            return Err("a twist has `linear` or `angular` (or both)".into());
        }
        let axis =
            |v: &Option<Vector3>, part: &str, name: &str, pick: fn(&Vector3) -> Option<f64>| {
                let x = v.as_ref().and_then(pick).unwrap_or(0.0);
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(format!("twist {part}.{name} must be a finite number"))
                }
            };
        for (v, part) in [(&m.linear, "linear"), (&m.angular, "angular")] {
            axis(v, part, "x", |v| v.x)?;
            axis(v, part, "y", |v| v.y)?;
            axis(v, part, "z", |v| v.z)?;
        }
        Ok(Twist {
            forward: axis(&m.linear, "linear", "x", |v| v.x)?,
            turn: axis(&m.angular, "angular", "z", |v| v.z)?,
        })
    }
}

/// How a twist's turn steers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Steer {
    /// By the gait's steering parameter (slithering's offset, conical sidewinding's
    /// taper; other gaits take the speed only).
    Knob,
    /// The gait's controller steers by a nominal heading; the body heads this way now.
    Heading(f64),
    /// It does, but the pose estimate is not valid now: the turn waits.
    NoEstimate,
}

/// What teleop is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TeleopState {
    /// No twist yet, or held by the dead-man (an operator's `arm` resumes).
    Idle,
    /// Twists arrive.
    Driving,
    /// They stopped: the gait made a controlled stop and stands until the hold.
    Stopped,
}

/// The teleop state machine.
#[derive(Debug, Clone)]
pub struct Teleop {
    state: TeleopState,
    last_twist_s: f64,
    /// What was last sent, and when.
    sent: Option<(GaitKind, [f64; 3], f64)>,
}

impl Default for Teleop {
    fn default() -> Self {
        Self {
            state: TeleopState::Idle,
            last_twist_s: f64::NEG_INFINITY,
            sent: None,
        }
    }
}

/// The gait's steering parameter and how much of it a unit turn asks for.
fn steering(gait: GaitKind, c: &TeleopConfig) -> Option<(Field, f64, f64)> {
    match gait {
        // A positive offset or taper turns the body clockwise going forwards (measured:
        // controllers/steering, controllers/sidewinding/heading): left is negative.
        GaitKind::Slithering => Some((Field::OffsetLat, -c.offset_rad, c.max_offset_rad)),
        // Conical sidewinding is the turning one; the plain gait has no knob.
        GaitKind::ConicalSidewinding => Some((Field::Taper, -c.taper, c.max_taper)),
        _ => None,
    }
}

impl Teleop {
    pub fn state(&self) -> TeleopState {
        self.state
    }

    /// A twist at `now_s` while `gait` is active: the requests to send (none if it
    /// asks what was last sent, re-sent every `resend_s` only), the turn steering as
    /// `steer` says.
    pub fn on_twist(
        &mut self,
        now_s: f64,
        gait: GaitKind,
        twist: Twist,
        steer: Steer,
        c: &TeleopConfig,
    ) -> Vec<Act> {
        let steer_heading = match steer {
            Steer::Heading(h) => Some(h),
            _ => None,
        };
        self.last_twist_s = now_s;
        let mut out = Vec::new();
        if self.state != TeleopState::Driving {
            // A session starts (or restarts after the dead-man): the gait moves again.
            out.push(Act::ResumeGait { within_s: c.stop_s });
        }
        self.state = TeleopState::Driving;
        let speed = (twist.forward * c.speed_rad_s).clamp(-c.max_speed_rad_s, c.max_speed_rad_s);
        let mut patch = ParamPatch {
            temporal_freq_rad_s: Some(speed),
            ..ParamPatch::default()
        };
        let mut knob_value = 0.0;
        let knob = steering(gait, c).filter(|_| steer == Steer::Knob);
        if let Some((name, per_unit, max)) = knob {
            // Backing along an arc turns the other way: keep "left" left.
            let dir = if speed < 0.0 { -1.0 } else { 1.0 };
            knob_value = (dir * twist.turn * per_unit).clamp(-max, max);
            name.set_in_patch(&mut patch, knob_value);
        }
        let lead = (twist.turn * c.heading_lead_rad)
            .clamp(-c.max_heading_lead_rad, c.max_heading_lead_rad);
        let now = [
            speed,
            knob_value,
            if steer_heading.is_some() { lead } else { 0.0 },
        ];
        let fresh = match self.sent {
            Some((g, was, at)) => {
                g != gait
                    || was.iter().zip(&now).any(|(a, b)| (a - b).abs() > 1e-6)
                    || now_s - at >= c.resend_s
            }
            None => true,
        };
        if fresh {
            self.sent = Some((gait, now, now_s));
            out.push(Act::SetParams { gait, patch });
        }
        // A turn follows the body (each twist); a straight twist holds the heading once.
        if let Some(h) = steer_heading
            && (lead != 0.0 || fresh)
        {
            let nominal = crate::num::wrap_pi(h + lead);
            out.push(Act::SetHeading {
                gait: Some(gait),
                heading_rad: Some(nominal),
            });
        }
        out
    }

    /// The dead-man at `now_s`: a controlled stop (the body at rest within `stop_s`)
    /// once the twists are `timeout_s` old, hold `hold_after_s` later.
    pub fn tick(&mut self, now_s: f64, c: &TeleopConfig) -> Option<Act> {
        let age = now_s - self.last_twist_s;
        match self.state {
            TeleopState::Driving if age >= c.timeout_s => {
                self.state = TeleopState::Stopped;
                Some(Act::StopGait { within_s: c.stop_s })
            }
            TeleopState::Stopped if age >= c.timeout_s + c.hold_after_s => {
                self.state = TeleopState::Idle;
                Some(Act::Hold)
            }
            _ => None,
        }
    }

    /// The stop was refused: hold at once.
    pub fn stop_refused(&mut self) -> Act {
        self.state = TeleopState::Idle;
        Act::Hold
    }
}

/// The active gait in the loop's snapshot `s`, and how a turn steers it: by the nominal
/// heading where its engaged controller declares it steers by one now (its
/// `capabilities`: anti-compliant sidewinding, a heading hold that holds one), else by
/// the gait's knob.
pub fn active_gait(s: &Snapshot) -> (GaitKind, Steer) {
    let steer = match (s.controller.capabilities.steers_by_heading, s.body.valid) {
        (false, _) => Steer::Knob,
        (true, true) if s.body.heading_rad.is_finite() => Steer::Heading(s.body.heading_rad),
        (true, _) => Steer::NoEstimate,
    };
    (s.gait, steer)
}

/// `act` without the parameters that already have their values in `s` (`None`:
/// nothing left to send).
pub fn changed_only(s: Option<&Snapshot>, act: Act) -> Option<Act> {
    let Act::SetParams { gait, mut patch } = act else {
        return Some(act);
    };
    let Some(s) = s else {
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

#[cfg(test)]
#[path = "teleop_tests.rs"]
mod tests;
