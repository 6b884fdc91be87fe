//! Failsafe state machine (in the spirit of PX4's failsafe framework): pure, time is an
//! argument, nothing allocates. The loop feeds it the feedback health once per cycle
//! and the operator's events at cycle boundaries; it answers what to do with the
//! joints. The transition table is in `docs/failsafe.md`.
//!
//! Two rules carry the safety argument:
//! - The joints are only driven from set-points that started at the measured pose:
//!   every way into `Running` (and into a hold from a limp state) passes through
//!   [`Output::Resync`], and the loop confirms with [`Failsafe::resynced`].
//! - A fault is only trusted to be gone after feedback has stayed healthy for
//!   `limp_after_s`, as long as it takes to give up on it; a fault that flickers
//!   therefore escalates to limp instead of thrashing between hold and run.
use serde::Serialize;

use crate::num::Num;

/// Why the failsafe refused an event (the loop answers the request with it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    #[error("e-stop is latched: send arm first")]
    EStopLatched,
    #[error("feedback is not healthy; cannot arm")]
    FeedbackUnhealthy,
    #[error("shutting down")]
    ShuttingDown,
}

/// What the loop does with the joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Running (or blending into) the active gait.
    Running,
    /// Set-points frozen where they were.
    Hold,
    /// Joints not driven.
    Limp,
    /// Limp and latched until the operator arms.
    EStop,
}

/// Why the loop is in its mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    Startup,
    Operator,
    FeedbackTimeout,
    NonFiniteFeedback,
    /// A controller produced a non-finite set-point; it was not sent.
    NonFiniteSetpoint,
    EStop,
    Shutdown,
    /// Running again by itself after a fault cleared (`auto_resume`).
    AutoResume,
}

/// Failsafe tuning. Every value has a default; see `docs/failsafe.md`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailsafeConfig {
    /// Feedback older than this (from any module) is a fault, s. Default 0.05
    /// (50 cycles at 1 kHz: long enough to ride out a few lost packets).
    pub feedback_timeout_s: f64,
    /// A fault that lasts this long while holding goes limp, s; feedback must also
    /// stay healthy this long before a fault counts as cleared. Default 0.5.
    pub limp_after_s: f64,
    /// Resume from a failsafe hold by itself once the fault has cleared. Default false:
    /// only the operator's `Arm` resumes.
    pub auto_resume: bool,
    /// How long a shutdown holds before going limp, s. Default 0.2.
    pub shutdown_hold_s: f64,
}

impl Default for FailsafeConfig {
    fn default() -> Self {
        FailsafeConfig {
            feedback_timeout_s: 0.05,
            limp_after_s: 0.5,
            auto_resume: false,
            shutdown_hold_s: 0.2,
        }
    }
}

/// A [`FailsafeConfig`] value that cannot work.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "failsafe.{field} = {} must be finite and within [{}, {}] s",
    Num(*.value),
    Num(*.min),
    Num(*.max)
)]
pub struct FailsafeConfigError {
    pub field: &'static str,
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

impl FailsafeConfig {
    /// Every time finite and within a sane range (1 ms .. 60 s; the shutdown hold may
    /// be 0).
    pub fn validate(&self) -> Result<(), FailsafeConfigError> {
        let checks = [
            ("feedback_timeout_s", self.feedback_timeout_s, 0.001),
            ("limp_after_s", self.limp_after_s, 0.001),
            ("shutdown_hold_s", self.shutdown_hold_s, 0.0),
        ];
        for (field, value, min) in checks {
            let max = 60.0;
            if !(min..=max).contains(&value) {
                return Err(FailsafeConfigError {
                    field,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(())
    }
}

/// The feedback's health this cycle, as the loop measured it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Health {
    /// Age of the oldest module's newest feedback, s (`INFINITY` if a module never
    /// reported).
    pub oldest_feedback_age_s: f64,
    /// Some module reported a non-finite value.
    pub non_finite: bool,
}

impl Health {
    /// The fault this health shows under `config`, if any (non-finite data first).
    pub fn fault(&self, config: &FailsafeConfig) -> Option<Reason> {
        if self.non_finite {
            Some(Reason::NonFiniteFeedback)
        } else if self.oldest_feedback_age_s.is_nan()
            || self.oldest_feedback_age_s > config.feedback_timeout_s
        {
            // NaN ages count as stale.
            Some(Reason::FeedbackTimeout)
        } else {
            None
        }
    }
}

/// An operator event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    Hold,
    Limp,
    EStop,
    Arm,
    Shutdown,
}

/// What the loop does this cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// Run the gait selector and send its set-points.
    Run,
    /// Send the set-points of the last cycle again (do not advance the selector).
    Hold,
    /// Send limp commands (no set-points).
    Limp,
    /// Set the selector's set-points to the measured positions now
    /// ([`crate::gait::GaitSelector::resync`]), send them, then call
    /// [`Failsafe::resynced`].
    Resync,
    /// Shutdown complete: send limp and leave the loop.
    Finished,
}

/// Where a resync leads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Then {
    Run(Reason),
    Hold,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    /// Limp until feedback is healthy.
    Startup,
    /// Waiting for the loop to resync; `driven`: the joints were held before (so a
    /// fault meanwhile falls back to a hold, not limp).
    Resync {
        then: Then,
        driven: bool,
    },
    Running,
    /// Holding; `operator`: the operator asked for it (never auto-resumed).
    Hold {
        operator: bool,
    },
    Limp,
    EStop,
    /// Holding for the shutdown, which began at `start_s`.
    ShutdownHold {
        start_s: f64,
    },
    ShutdownLimp,
    Finished,
}

/// The failsafe state machine.
#[derive(Debug, Clone)]
pub struct Failsafe {
    config: FailsafeConfig,
    state: State,
    mode: Mode,
    reason: Reason,
    since_s: f64,
    /// Health seen by the last update (false before the first).
    healthy: bool,
    /// Start of the current fault episode (ends after `limp_after_s` of health).
    episode_start_s: Option<f64>,
    healthy_since_s: Option<f64>,
    /// The last update answered `Resync` and nothing has changed the state since:
    /// only then does `resynced` count.
    resync_asked: bool,
}

impl Failsafe {
    /// Starts limp (reason `Startup`) at time 0, waiting for healthy feedback.
    pub fn new(config: FailsafeConfig) -> Self {
        Failsafe {
            config,
            state: State::Startup,
            mode: Mode::Limp,
            reason: Reason::Startup,
            since_s: 0.0,
            healthy: false,
            episode_start_s: None,
            healthy_since_s: None,
            resync_asked: false,
        }
    }

    pub fn config(&self) -> &FailsafeConfig {
        &self.config
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    pub fn reason(&self) -> Reason {
        self.reason
    }

    /// When the current mode and reason began, s.
    pub fn since_s(&self) -> f64 {
        self.since_s
    }

    /// The shutdown sequence has completed.
    pub fn is_finished(&self) -> bool {
        self.state == State::Finished
    }

    /// Whether the last update saw healthy feedback.
    pub fn feedback_healthy(&self) -> bool {
        self.healthy
    }

    fn enter(&mut self, state: State, mode: Mode, reason: Reason, now_s: f64) {
        self.state = state;
        if (mode, reason) != (self.mode, self.reason) {
            self.since_s = now_s;
        }
        self.mode = mode;
        self.reason = reason;
    }

    fn shutting_down(&self) -> bool {
        matches!(
            self.state,
            State::ShutdownHold { .. } | State::ShutdownLimp | State::Finished
        )
    }

    /// Applies an operator event at a cycle boundary.
    pub fn request(&mut self, now_s: f64, event: Event) -> Result<(), Refusal> {
        let before = self.state;
        let result = self.apply(now_s, event);
        if self.state != before {
            self.resync_asked = false;
        }
        result
    }

    fn apply(&mut self, now_s: f64, event: Event) -> Result<(), Refusal> {
        if self.shutting_down() {
            // An e-stop still cuts a shutdown's hold short: limp at once.
            if event == Event::EStop && self.state != State::Finished {
                self.enter(State::ShutdownLimp, Mode::EStop, Reason::EStop, now_s);
                return Ok(());
            }
            return Err(Refusal::ShuttingDown);
        }
        match event {
            Event::EStop => {
                self.enter(State::EStop, Mode::EStop, Reason::EStop, now_s);
                Ok(())
            }
            Event::Shutdown => {
                let driven = match self.state {
                    State::Running | State::Hold { .. } => true,
                    State::Resync { driven, .. } => driven,
                    _ => false,
                };
                if driven {
                    let state = State::ShutdownHold { start_s: now_s };
                    self.enter(state, Mode::Hold, Reason::Shutdown, now_s);
                } else if self.state == State::EStop {
                    self.state = State::ShutdownLimp; // stays visibly e-stopped
                } else {
                    self.enter(State::ShutdownLimp, Mode::Limp, Reason::Shutdown, now_s);
                }
                Ok(())
            }
            _ if self.state == State::EStop && event != Event::Arm => Err(Refusal::EStopLatched),
            Event::Limp => {
                self.enter(State::Limp, Mode::Limp, Reason::Operator, now_s);
                Ok(())
            }
            Event::Hold => match self.state {
                State::Running | State::Hold { .. } => {
                    let held = State::Hold { operator: true };
                    self.enter(held, Mode::Hold, Reason::Operator, now_s);
                    Ok(())
                }
                State::Resync { driven, .. } => {
                    self.state = State::Resync {
                        then: Then::Hold,
                        driven,
                    };
                    Ok(())
                }
                // From limp the set-points are stale: hold where the joints are.
                _ => self.start_resync(Then::Hold),
            },
            Event::Arm => match self.state {
                State::Running => Ok(()),
                State::Resync { driven, .. } => {
                    self.state = State::Resync {
                        then: Then::Run(Reason::Operator),
                        driven,
                    };
                    Ok(())
                }
                _ => self.start_resync(Then::Run(Reason::Operator)),
            },
        }
    }

    /// The loop refused to send a non-finite set-point this cycle: hold the last
    /// set-points sent, until the operator arms (never auto-resumed: the same
    /// controller would do it again). Ignored unless the gait is being run.
    pub fn setpoint_fault(&mut self, now_s: f64) {
        if matches!(self.state, State::Running | State::Resync { .. }) {
            let held = State::Hold { operator: true };
            self.enter(held, Mode::Hold, Reason::NonFiniteSetpoint, now_s);
            self.resync_asked = false;
        }
    }

    /// Asks the loop for a resync leading to `then`, if feedback is healthy.
    fn start_resync(&mut self, then: Then) -> Result<(), Refusal> {
        if !self.healthy {
            return Err(Refusal::FeedbackUnhealthy);
        }
        // The operator vouches for the feedback: a new fault starts a new episode.
        self.episode_start_s = None;
        let driven = matches!(self.state, State::Hold { .. });
        self.state = State::Resync { then, driven };
        Ok(())
    }

    /// The loop has set its set-points to the measured positions after the last
    /// update answered [`Output::Resync`]. Ignored otherwise (also when a request
    /// changed the state in between), so nothing runs on set-points that were not
    /// resynced.
    pub fn resynced(&mut self, now_s: f64) {
        if !std::mem::take(&mut self.resync_asked) {
            return;
        }
        if let State::Resync { then, .. } = self.state {
            match then {
                Then::Run(reason) => self.enter(State::Running, Mode::Running, reason, now_s),
                Then::Hold => {
                    let held = State::Hold { operator: true };
                    self.enter(held, Mode::Hold, Reason::Operator, now_s);
                }
            }
        }
    }

    /// Once per cycle, with this cycle's feedback health: transitions, then what to do.
    pub fn update(&mut self, now_s: f64, health: &Health) -> Output {
        let fault = health.fault(&self.config);
        self.track_episode(now_s, fault.is_some());
        let overdue = self
            .episode_start_s
            .is_some_and(|start| now_s - start >= self.config.limp_after_s);
        match (self.state, fault) {
            (State::Startup, None) => {
                self.state = State::Resync {
                    then: Then::Run(Reason::Startup),
                    driven: false,
                };
            }
            // A fault before the loop resynced: back to where it came from.
            (
                State::Resync {
                    then: Then::Run(Reason::Startup),
                    ..
                },
                Some(_),
            ) => self.state = State::Startup,
            (State::Resync { driven: true, .. }, Some(why)) => {
                let held = State::Hold { operator: false };
                self.enter(held, Mode::Hold, why, now_s);
            }
            (State::Resync { driven: false, .. }, Some(why)) => {
                self.enter(State::Limp, Mode::Limp, why, now_s);
            }
            (State::Running, Some(why)) => {
                let held = State::Hold { operator: false };
                self.enter(held, Mode::Hold, why, now_s);
            }
            (State::Hold { .. }, Some(why)) if overdue => {
                self.enter(State::Limp, Mode::Limp, why, now_s);
            }
            (State::Hold { operator: false }, None)
                if self.config.auto_resume && self.episode_start_s.is_none() =>
            {
                self.state = State::Resync {
                    then: Then::Run(Reason::AutoResume),
                    driven: true,
                };
            }
            // Holding without feedback is blind: a fault ends the shutdown hold early.
            (State::ShutdownHold { start_s }, _)
                if fault.is_some() || now_s - start_s >= self.config.shutdown_hold_s =>
            {
                self.enter(State::ShutdownLimp, Mode::Limp, Reason::Shutdown, now_s);
            }
            (State::ShutdownLimp, _) => self.state = State::Finished,
            _ => {}
        }
        let out = match self.state {
            State::Running => Output::Run,
            State::Hold { .. } | State::ShutdownHold { .. } => Output::Hold,
            State::Startup | State::Limp | State::EStop | State::ShutdownLimp => Output::Limp,
            State::Resync { .. } => Output::Resync,
            State::Finished => Output::Finished,
        };
        self.resync_asked = out == Output::Resync;
        out
    }

    fn track_episode(&mut self, now_s: f64, faulty: bool) {
        self.healthy = !faulty;
        if faulty {
            self.healthy_since_s = None;
            self.episode_start_s.get_or_insert(now_s);
        } else {
            let since = *self.healthy_since_s.get_or_insert(now_s);
            if now_s - since >= self.config.limp_after_s {
                self.episode_start_s = None;
            }
        }
    }
}

#[cfg(test)]
#[path = "failsafe_tests.rs"]
mod tests;
