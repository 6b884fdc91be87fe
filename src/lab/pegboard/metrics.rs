//! The peg board's figures of a trial: time to traverse in body-wave cycles per metre
//! of the smoothed centre path, success and side exits, time stuck, progress across.
//! Definitions: `docs/lab.md`.

use std::f64::consts::TAU;

use crate::lab::metrics::{MetricsConfig, dist, moving_average, polyline_length_m, stuck_s};

/// Smoothed paths shorter than this count as this long, m: a trial that made no
/// progress gets a large (bad) but finite cycles-per-metre figure.
pub const MIN_PATH_M: f64 = 0.01;

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrialMetrics {
    /// The front half crossed the board, leaving it by the far edge, before the limit.
    pub success: bool,
    /// The front half left the board by a side edge (the trial ended; not a success).
    pub side_exit: bool,
    /// The centre's signed displacement across the board (towards its far edge), first
    /// to last position, m: negative when the body drifted back.
    pub progress_m: f64,
    /// Trial length: until success, or the limit, s.
    pub seconds: f64,
    /// Nominal body-wave cycles in that time, `ωT·t / 2π`.
    pub cycles: f64,
    /// Length of the smoothed centre path, m.
    pub path_m: f64,
    /// Straight distance between the centre's first and last positions, m.
    pub distance_m: f64,
    /// Time to traverse: `cycles / max(path_m, MIN_PATH_M)`, cycles per metre.
    pub cycles_per_m: f64,
    /// Time in stuck windows, s.
    pub stuck_s: f64,
    /// Contact onsets between non-adjacent links (set from the trial's record).
    pub self_contacts: u64,
}

/// The figures of a centre path sampled every `sample_dt_s` (sample 0 at t = 0).
pub fn trial_metrics(
    centre_m: &[[f64; 2]],
    sample_dt_s: f64,
    seconds: f64,
    success: bool,
    temporal_freq_rad_s: f64,
    config: &MetricsConfig,
) -> TrialMetrics {
    let half = (config.smooth_s / sample_dt_s / 2.0).round() as usize;
    let smooth = moving_average(centre_m, half);
    let path_m = polyline_length_m(&smooth);
    let cycles = temporal_freq_rad_s.abs() * seconds / TAU;
    TrialMetrics {
        success,
        seconds,
        cycles,
        path_m,
        distance_m: match (centre_m.first(), centre_m.last()) {
            (Some(a), Some(b)) => dist(*a, *b),
            _ => 0.0,
        },
        cycles_per_m: cycles / path_m.max(MIN_PATH_M),
        stuck_s: stuck_s(
            &smooth,
            sample_dt_s,
            config.stuck_window_s,
            config.stuck_move_m,
        ),
        self_contacts: 0,
        side_exit: false,
        progress_m: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::metrics::tests::{DT, swaying};

    #[test]
    fn smoothing_over_one_period_removes_the_sway() {
        // 5 cm of sway at 1 rad/s on 5 cm/s: the raw path is much longer than 3 m.
        let omega = 1.0;
        let p = swaying(0.05, 0.05, omega, 60.0);
        let raw = polyline_length_m(&p);
        let m = trial_metrics(&p, DT, 60.0, false, omega, &MetricsConfig::for_wave(omega));
        assert!(raw > 3.5, "raw {raw}");
        // What is left is the sway near the ends, where the window shrinks.
        assert!((m.path_m - 3.0).abs() < 0.05, "smoothed {}", m.path_m);
        assert!((m.distance_m - 3.0).abs() < 0.03);
        // 60 s at 1 rad/s = 9.55 cycles over 3 m.
        assert!((m.cycles - 60.0 / TAU).abs() < 1e-9);
        assert!((m.cycles_per_m - m.cycles / m.path_m).abs() < 1e-12);
        assert_eq!(m.stuck_s, 0.0);
    }

    #[test]
    fn no_progress_counts_with_the_minimum_path() {
        let p = vec![[0.3, 0.1]; 41];
        let m = trial_metrics(&p, DT, 2.0, false, 1.0, &MetricsConfig::for_wave(1.0));
        assert!(m.path_m < 1e-12);
        assert!((m.cycles_per_m - (2.0 / TAU) / MIN_PATH_M).abs() < 1e-9);
        assert!(m.cycles_per_m.is_finite());
    }
}
