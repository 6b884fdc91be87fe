//! One climbing trial's figures, from its recorded heights and the controller's
//! signals: whether the body got on the pole, reached the top, fell; how far it climbed
//! per gait cycle; its slips (downward slides); its grip.

use crate::lab::trial::TrialRecord;

/// The body got on the pole when its centre rose this high, m.
pub const ON_POLE_M: f64 = 0.2;
/// A fall: after getting on, the centre back below this height, m.
pub const FALLEN_M: f64 = 0.1;
/// A slip: the centre dropping by at least this much within [`SLIP_WINDOW_S`], m.
pub const SLIP_M: f64 = 0.03;
pub const SLIP_WINDOW_S: f64 = 1.0;

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Outcome {
    /// The centre reached the top.
    Top,
    /// It got on and fell back to the ground.
    Fell,
    /// On the pole, below the top, at the time limit.
    Stalled,
    /// Never got off the ground.
    NotOn,
}

impl Outcome {
    pub fn name(self) -> &'static str {
        match self {
            Self::Top => "top",
            Self::Fell => "fell",
            Self::Stalled => "stalled",
            Self::NotOn => "not_on",
        }
    }
}

/// One trial's figures.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoleMetrics {
    pub outcome: Outcome,
    /// Simulated time at the end, s.
    pub seconds: f64,
    /// When the centre reached the top, s.
    pub top_s: Option<f64>,
    /// Highest centre, m.
    pub max_height_m: f64,
    /// Height climbed per gait cycle while rolling on the pole: from getting on to the
    /// top (or the highest point), m per cycle of ωT.
    pub climb_per_cycle_m: f64,
    /// Downward slides of at least [`SLIP_M`] within [`SLIP_WINDOW_S`] (a fall counts
    /// once too).
    pub slips: usize,
    /// Total height lost in them, m.
    pub slid_m: f64,
    /// Mean of the controller's `grip_nm` signal while on the pole, N·m.
    pub grip_mean_nm: f64,
    /// Diameter changes the centre rose past.
    pub changes_passed: usize,
}

/// The figures of `rec` on a pole whose diameter changes at `changes_m`, its top at
/// `top_m`.
pub fn pole_metrics(rec: &TrialRecord, changes_m: &[f64], top_m: f64) -> PoleMetrics {
    let samples = rec.heights_m.len() / rec.start_links_m.len().max(1);
    let h: Vec<f64> = (0..samples).map(|k| rec.centre_height(k)).collect();
    let dt = rec.sample_dt_s;
    let on = h.iter().position(|&z| z >= ON_POLE_M);
    let top = h.iter().position(|&z| z >= top_m);
    let (max_k, max_height_m) =
        h.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |a, (k, &z)| if z > a.1 { (k, z) } else { a },
        );
    let fell = on.is_some_and(|k| h[k..].iter().any(|&z| z < FALLEN_M));
    let outcome = match (on, top, fell) {
        (None, _, _) => Outcome::NotOn,
        (_, Some(_), _) => Outcome::Top,
        (_, None, true) => Outcome::Fell,
        (_, None, false) => Outcome::Stalled,
    };
    let cycle_s = std::f64::consts::TAU / rec.temporal_freq_rad_s.abs().max(1e-9);
    // From getting on to the top or the highest point.
    let climb_per_cycle_m = match on {
        Some(k0) => {
            let k1 = top.unwrap_or(max_k).max(k0);
            let t = (k1 - k0) as f64 * dt;
            if t > 0.0 {
                (h[k1] - h[k0]) / (t / cycle_s)
            } else {
                0.0
            }
        }
        None => 0.0,
    };
    let (slips, slid_m) = slips(&h, dt);
    let grip = rec
        .signal_names
        .iter()
        .position(|n| n == "grip_nm")
        .map(|i| &rec.signals[i]);
    let grip_mean_nm = match (grip, on) {
        (Some(g), Some(k0)) => {
            let v: Vec<f64> = g[k0..].iter().copied().filter(|x| x.is_finite()).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        }
        _ => 0.0,
    };
    let changes_passed = changes_m.iter().filter(|&&z| max_height_m > z).count();
    PoleMetrics {
        outcome,
        seconds: rec.seconds,
        top_s: top.map(|k| k as f64 * dt),
        max_height_m,
        climb_per_cycle_m,
        slips,
        slid_m,
        grip_mean_nm,
        changes_passed,
    }
}

/// Downward slides in the centre's heights `h` sampled every `dt` s: a slide starts
/// when the height is [`SLIP_M`] below its highest over the last [`SLIP_WINDOW_S`],
/// and ends when it rises again; its depth is counted.
pub fn slips(h: &[f64], dt: f64) -> (usize, f64) {
    let w = (SLIP_WINDOW_S / dt).round().max(1.0) as usize;
    let (mut count, mut total) = (0, 0.0);
    // The window never reaches back past the last slide's bottom: one slide, one count.
    let (mut k, mut after) = (0, 0);
    while k < h.len() {
        let from = k.saturating_sub(w).max(after);
        let peak = h[from..=k]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        if peak - h[k] >= SLIP_M {
            // Follow the slide down to its bottom.
            let mut j = k;
            while j + 1 < h.len() && h[j + 1] <= h[j] + 1e-4 {
                j += 1;
            }
            count += 1;
            total += peak - h[j];
            after = j;
            k = j + 1;
        } else {
            k += 1;
        }
    }
    (count, total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slides_are_counted_once_with_their_depth() {
        let dt = 0.05;
        // Climbs 1 cm/s, slides 10 cm in 0.5 s at 3 s, climbs on.
        let h: Vec<f64> = (0..60).map(|k| 0.3 + 0.01 * k as f64 * dt).collect();
        let mut h2 = h.clone();
        for k in 0..10 {
            h2.push(h[59] - 0.01 * (k + 1) as f64);
        }
        let base = *h2.last().unwrap();
        for k in 0..40 {
            h2.push(base + 0.0005 * k as f64);
        }
        let (n, d) = slips(&h2, dt);
        assert_eq!(n, 1);
        assert!((d - 0.10).abs() < 0.011, "{d}");
        // A steady climb or a hold has none; a slow creep under 3 cm per second neither.
        assert_eq!(slips(&h, dt).0, 0);
        let creep: Vec<f64> = (0..200).map(|k| 1.0 - 0.001 * k as f64).collect();
        assert_eq!(slips(&creep, dt).0, 0);
    }
}
