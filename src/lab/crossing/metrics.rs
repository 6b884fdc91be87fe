//! A crossing trial's figures: how it ended (across, by a side, or not at the limit),
//! how long it took, how far it got along +x and how long it was stuck. Definitions:
//! docs/lab.md, "Crossing".

use super::CrossingGoal;
use super::starts::StartKind;
use crate::lab::metrics::stuck_s;
use crate::lab::pegboard::board::Exit;
use crate::lab::trial::{TrialRecord, front_half_of};

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Outcome {
    /// The front half left by the far edge.
    Crossed,
    /// The front half left by a side edge.
    Side,
    /// Still on (or back behind) the board at the limit.
    Timeout,
}

impl Outcome {
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Crossed => "crossed",
            Outcome::Side => "side",
            Outcome::Timeout => "timeout",
        }
    }
}

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CrossingMetrics {
    pub kind: StartKind,
    pub outcome: Outcome,
    /// Until it left the board, or the limit, s.
    pub seconds: f64,
    /// The body centre's displacement along +x, first to last sample, m.
    pub progress_m: f64,
    /// Its displacement across (along +y), first to last sample, m: which side a body
    /// drifts to.
    pub lateral_m: f64,
    /// Time in 2 s windows in which the centre moved under 2 cm, s.
    pub stuck_s: f64,
    pub self_contacts: u64,
    /// Changes of gait or controller (the navigator's; 0 for a single controller).
    pub gait_switches: u32,
}

/// The figures of `rec` on `goal`'s board.
pub fn crossing_metrics(goal: &CrossingGoal, rec: &TrialRecord) -> CrossingMetrics {
    let exit = if rec.success {
        goal.board
            .exit(front_half_of(rec.end_links_m.iter().copied()))
    } else {
        None
    };
    let outcome = match exit {
        Some(Exit::Far) => Outcome::Crossed,
        Some(Exit::Side) => Outcome::Side,
        None => Outcome::Timeout,
    };
    let (progress_m, lateral_m) = match (rec.centre_m.first(), rec.centre_m.last()) {
        (Some(a), Some(b)) => (b[0] - a[0], b[1] - a[1]),
        _ => (0.0, 0.0),
    };
    CrossingMetrics {
        kind: goal.kind,
        outcome,
        seconds: rec.seconds,
        progress_m,
        lateral_m,
        stuck_s: stuck_s(&rec.centre_m, rec.sample_dt_s, 2.0, 0.02),
        self_contacts: rec.self_contacts,
        gait_switches: rec.gait_switches,
    }
}
