//! The peg-board experiment (SPEC §5, thesis Fig. 4.6): slithering controllers on
//! seeded irregular peg boards, a trial ending when the front half of the body leaves
//! the board (as the thesis's did); success = it left across, by the far edge (a side
//! exit is counted apart); time to traverse in body-wave cycles per metre, and the
//! centre's signed progress across the board.

use super::LabError;
use super::board::{Board, Exit, Layout};
use super::experiment::{ExperimentModule, Goal};
use super::metrics::{MetricsConfig, TrialMetrics, trial_metrics};
use super::trial::{TrialRecord, front_half_centre, front_half_of};
use crate::emu::Plant;
use crate::emu::world::WorldSpec;
use crate::gait::GaitKind;

/// The experiment's entry.
pub struct Pegboard;

/// Its controllers, in report order: open loop, the ablations (each adds a compliant
/// parameter), the centralisation variants of the full controller, the CPG baseline,
/// and switching directional compliance (SPEC §8, calibrated on open ground first).
pub const CONTROLLERS: &[&str] = &[
    "open_loop",
    "a",
    "a_ws",
    "a_ws_omega",
    "a_ws_omega_central",
    "a_ws_omega_per_joint",
    "a_ws_omega_windowed_phase",
    "cpg",
    "dc_switching",
];

impl ExperimentModule for Pegboard {
    type Goal = Board;
    type Metrics = TrialMetrics;

    fn name(&self) -> &'static str {
        "pegboard"
    }
    fn summary(&self) -> &'static str {
        "slithering through seeded peg boards (SPEC §5): cycles per metre, success, time stuck"
    }
    fn gait(&self) -> GaitKind {
        GaitKind::Slithering
    }
    fn controllers(&self) -> &'static [&'static str] {
        CONTROLLERS
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, Board), LabError> {
        layout.world(modules, start)
    }

    fn metrics(&self, board: &Board, rec: &TrialRecord) -> TrialMetrics {
        // The trial ended at the sample it left the board: where the front half was then.
        let exit = if rec.success {
            board.exit(front_half_of(rec.end_links_m.iter().copied()))
        } else {
            None
        };
        let m = trial_metrics(
            &rec.centre_m,
            rec.sample_dt_s,
            rec.seconds,
            exit == Some(Exit::Far),
            rec.temporal_freq_rad_s,
            &MetricsConfig::for_wave(rec.temporal_freq_rad_s),
        );
        let progress_m = match (rec.centre_m.first(), rec.centre_m.last()) {
            (Some(a), Some(b)) => {
                let f = board.forward();
                (b[0] - a[0]) * f[0] + (b[1] - a[1]) * f[1]
            }
            _ => 0.0,
        };
        TrialMetrics {
            self_contacts: rec.self_contacts,
            side_exit: exit == Some(Exit::Side),
            progress_m,
            ..m
        }
    }
}

/// A trial is over when the front half of the body has crossed the board.
impl Goal for Board {
    fn reached(&self, plant: &dyn Plant) -> bool {
        self.crossed(front_half_centre(plant))
    }
}
