//! The experiment's figures from a recorded trial: pure functions of the body centre's
//! path (sampled at a fixed rate), tested on synthetic paths. Definitions: `docs/lab.md`.

use std::f64::consts::TAU;

/// Smoothed paths shorter than this count as this long, m: a trial that made no
/// progress gets a large (bad) but finite cycles-per-metre figure.
pub const MIN_PATH_M: f64 = 0.01;

/// How the figures are computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetricsConfig {
    /// Length of the centred moving average over the centre path, s.
    pub smooth_s: f64,
    /// Length of the windows the stuck time is counted in, s.
    pub stuck_window_s: f64,
    /// A window in which the (smoothed) centre moves less than this is stuck, m.
    pub stuck_move_m: f64,
}

impl MetricsConfig {
    /// The lab's defaults for a wave of temporal frequency `temporal_freq_rad_s`: smooth
    /// over one nominal wave period (which averages out the centre's sway at the wave's
    /// frequency), stuck = under 2 cm in 2 s.
    pub fn for_wave(temporal_freq_rad_s: f64) -> Self {
        let period = TAU / temporal_freq_rad_s.abs();
        Self {
            smooth_s: if period.is_finite() { period } else { 1.0 },
            stuck_window_s: 2.0,
            stuck_move_m: 0.02,
        }
    }
}

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
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

/// Centred moving average over `2·half + 1` samples; near the ends the window shrinks
/// symmetrically, so the first and last points are kept and the average stays centred.
pub fn moving_average(points: &[[f64; 2]], half: usize) -> Vec<[f64; 2]> {
    let n = points.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push([0.0, 0.0]);
    let mut acc = [0.0, 0.0];
    for p in points {
        acc = [acc[0] + p[0], acc[1] + p[1]];
        prefix.push(acc);
    }
    (0..n)
        .map(|i| {
            let h = half.min(i).min(n - 1 - i);
            let (a, b) = (i - h, i + h + 1);
            let k = (b - a) as f64;
            [
                (prefix[b][0] - prefix[a][0]) / k,
                (prefix[b][1] - prefix[a][1]) / k,
            ]
        })
        .collect()
}

/// Length of the polyline through `points`, m.
pub fn polyline_length_m(points: &[[f64; 2]]) -> f64 {
    points.windows(2).map(|w| dist(w[0], w[1])).sum()
}

/// Total time in consecutive windows of `window_s` (from t = 0; a last partial window
/// does not count) whose first and last points are less than `move_m` apart, s.
pub fn stuck_s(points: &[[f64; 2]], sample_dt_s: f64, window_s: f64, move_m: f64) -> f64 {
    let w = (window_s / sample_dt_s).round().max(1.0) as usize;
    let stuck = (0..)
        .map(|k| k * w)
        .take_while(|&a| a + w < points.len())
        .filter(|&a| dist(points[a], points[a + w]) < move_m)
        .count();
    stuck as f64 * w as f64 * sample_dt_s
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

/// Mean, sample standard deviation (0 for one value) and median; `None` when empty.
pub fn mean_sd_median(values: &[f64]) -> Option<(f64, f64, f64)> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    };
    Some((mean, sd, median))
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 0.05;

    /// Forward at `v` m/s along x with a lateral sway of `amp` m at `omega` rad/s.
    fn swaying(v: f64, amp: f64, omega: f64, seconds: f64) -> Vec<[f64; 2]> {
        let n = (seconds / DT).round() as usize;
        (0..=n)
            .map(|k| {
                let t = k as f64 * DT;
                [v * t, amp * (omega * t).sin()]
            })
            .collect()
    }

    #[test]
    fn straight_line_length_is_its_distance() {
        let p = swaying(0.1, 0.0, 1.0, 10.0);
        assert!((polyline_length_m(&p) - 1.0).abs() < 1e-9);
        let s = moving_average(&p, 20);
        assert!((polyline_length_m(&s) - 1.0).abs() < 1e-9, "endpoints kept");
    }

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
    fn moving_average_is_centred_and_keeps_its_ends() {
        let p: Vec<[f64; 2]> = [0.0, 1.0, 5.0, 1.0, 0.0]
            .iter()
            .map(|&x| [x, 0.0])
            .collect();
        let s = moving_average(&p, 1);
        assert_eq!(s[0], [0.0, 0.0]);
        assert_eq!(s[1], [2.0, 0.0]);
        assert_eq!(s[2], [7.0 / 3.0, 0.0]);
        assert_eq!(s[4], [0.0, 0.0]);
        assert!(moving_average(&[], 3).is_empty());
    }

    #[test]
    fn stuck_time_counts_windows_without_progress() {
        // 10 s moving at 5 cm/s, 10 s still, 10 s moving again.
        let mut p = Vec::new();
        for k in 0..=600 {
            let t = k as f64 * DT;
            let x = if t < 10.0 {
                0.05 * t
            } else if t < 20.0 {
                0.5
            } else {
                0.5 + 0.05 * (t - 20.0)
            };
            p.push([x, 0.0]);
        }
        let s = stuck_s(&p, DT, 2.0, 0.02);
        assert!((s - 10.0).abs() < 1e-9, "stuck {s}");
        // Slow progress (5 mm/s: 1 cm per window) counts as stuck, too.
        let slow = swaying(0.005, 0.0, 1.0, 20.0);
        assert!((stuck_s(&slow, DT, 2.0, 0.02) - 20.0).abs() < 1e-9);
    }

    #[test]
    fn no_progress_counts_with_the_minimum_path() {
        let p = vec![[0.3, 0.1]; 41];
        let m = trial_metrics(&p, DT, 2.0, false, 1.0, &MetricsConfig::for_wave(1.0));
        assert!(m.path_m < 1e-12);
        assert!((m.cycles_per_m - (2.0 / TAU) / MIN_PATH_M).abs() < 1e-9);
        assert!(m.cycles_per_m.is_finite());
    }

    #[test]
    fn statistics() {
        assert_eq!(mean_sd_median(&[]), None);
        assert_eq!(mean_sd_median(&[4.0]), Some((4.0, 0.0, 4.0)));
        let (m, sd, med) = mean_sd_median(&[1.0, 2.0, 3.0, 10.0]).unwrap();
        assert_eq!(m, 4.0);
        assert_eq!(med, 2.5);
        assert!((sd - (50.0_f64 / 3.0).sqrt()).abs() < 1e-12);
    }
}
