//! Figures every experiment may take from a recorded trial: pure functions of the body
//! centre's path (sampled at a fixed rate: smoothing, length, time stuck) and the
//! statistics of a set of trials, tested on synthetic paths. Definitions: `docs/lab.md`.

use std::f64::consts::TAU;

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

/// Distance between two ground-plane points, m.
pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
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
pub(crate) mod tests {
    use super::*;

    pub(crate) const DT: f64 = 0.05;

    /// Forward at `v` m/s along x with a lateral sway of `amp` m at `omega` rad/s.
    pub(crate) fn swaying(v: f64, amp: f64, omega: f64, seconds: f64) -> Vec<[f64; 2]> {
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
    fn statistics() {
        assert_eq!(mean_sd_median(&[]), None);
        assert_eq!(mean_sd_median(&[4.0]), Some((4.0, 0.0, 4.0)));
        let (m, sd, med) = mean_sd_median(&[1.0, 2.0, 3.0, 10.0]).unwrap();
        assert_eq!(m, 4.0);
        assert_eq!(med, 2.5);
        assert!((sd - (50.0_f64 / 3.0).sqrt()).abs() < 1e-12);
    }
}
