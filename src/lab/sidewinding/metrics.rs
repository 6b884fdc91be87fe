//! A sidewinding trial's figures (thesis §4.3.7): whether and where the body passed
//! the peg array, how many openings it slid past first, when β reversed, and how far
//! the heading (true, and the estimate against the truth) was off. Pure functions of
//! the trial's record, tested on synthetic ones.

use std::f64::consts::{PI, TAU};

use super::fence::Fence;
use crate::controllers::sidewinding::wrap_pi;
use crate::lab::metrics::mean_sd_median;
use crate::lab::runner::TrialResult;
use crate::lab::trial::TrialRecord;

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Outcome {
    /// Every link passed the array.
    Through,
    /// The body went round an end of the array or back from it (a failed attempt).
    OffBoard,
    /// The time limit came first (also a failed attempt).
    Timeout,
}

impl Outcome {
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Through => "through",
            Outcome::OffBoard => "off_board",
            Outcome::Timeout => "timeout",
        }
    }
}

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SidewindingMetrics {
    pub outcome: Outcome,
    /// Simulated time of the trial (until through, off the board or the limit), s.
    pub seconds: f64,
    /// The opening the body first came up to (a link within touching distance of the
    /// array), and the one it went through.
    pub first_opening: Option<usize>,
    pub opening: Option<usize>,
    /// Openings between those two: passed over before entering one (through only).
    pub openings_passed: Option<usize>,
    /// Width of the opening it went through, m (NaN otherwise).
    pub opening_width_m: f64,
    /// β's crossings from one well to the other, and the time of the first (NaN if none).
    pub reversals: u64,
    pub first_reversal_s: f64,
    /// The time until the body had reversed beyond the array: through, and β reversed
    /// (NaN otherwise): the later of the two.
    pub reverse_beyond_s: f64,
    /// Heading error at the end: the true body heading (the true links' virtual chassis, over the last gait
    /// cycle) against the nominal one for the well β is in, rad, wrapped (NaN before a
    /// valid estimate).
    pub heading_error_end_rad: f64,
    /// The estimate's heading against the true one low-passed alike, aligned where the
    /// controller first had it: mean and largest absolute error over the trial, rad.
    pub estimate_error_mean_rad: f64,
    pub estimate_error_max_rad: f64,
    /// Centre's displacement towards the far side, m.
    pub progress_m: f64,
    pub self_contacts: u64,
}

impl SidewindingMetrics {
    /// A failed attempt: not through.
    pub fn failed(&self) -> bool {
        self.outcome != Outcome::Through
    }
}

fn series<'a>(rec: &'a TrialRecord, name: &str) -> Option<&'a [f64]> {
    let k = rec.signal_names.iter().position(|n| n == name)?;
    Some(&rec.signals[k])
}

/// The true heading at every sample: the virtual chassis's (docs/estimation.md) of the
/// true link positions, the frame the controller's estimate is of, continued from
/// sample to sample as the estimator continues it. (The tail-to-head chord is not that
/// heading: it sways with the wave and differs from the principal axis by up to about
/// 0.15 rad in sidewinding.)
fn true_headings(rec: &TrialRecord) -> Vec<f64> {
    use crate::estimation::chassis::{Chassis, chassis};
    use nalgebra::Vector3;
    let mut last: Option<Chassis> = None;
    let mut points = Vec::new();
    (0..rec.centre_m.len())
        .map(|k| {
            points.clear();
            points.extend(
                rec.links_at(k)
                    .iter()
                    .map(|p| Vector3::new(p[0], p[1], 0.0)),
            );
            if points.is_empty() {
                return f64::NAN;
            }
            let c = chassis(&points, last.as_ref());
            last = Some(c);
            c.heading_rad()
        })
        .collect()
}

/// `headings` low-passed with time constant `tau_s` as unit vectors (as the
/// controller filters its estimate).
fn low_passed(headings: &[f64], dt_s: f64, tau_s: f64) -> Vec<f64> {
    let a = if tau_s > 0.0 {
        (dt_s / tau_s).min(1.0)
    } else {
        1.0
    };
    let mut v: Option<[f64; 2]> = None;
    headings
        .iter()
        .map(|h| {
            let now = [h.cos(), h.sin()];
            let f = match v {
                None => now,
                Some(p) => [p[0] + a * (now[0] - p[0]), p[1] + a * (now[1] - p[1])],
            };
            v = Some(f);
            f[1].atan2(f[0])
        })
        .collect()
}

fn circular_mean(a: &[f64]) -> f64 {
    let (c, s) = a
        .iter()
        .filter(|x| x.is_finite())
        .fold((0.0, 0.0), |(c, s), x| (c + x.cos(), s + x.sin()));
    s.atan2(c)
}

/// The well β is nearest: 0 or π (recordings without the reversal count).
fn well_of(beta: f64) -> f64 {
    if wrap_pi(beta - PI).abs() < PI / 2.0 {
        PI
    } else {
        0.0
    }
}

/// A trial's headings in the true world frame, per sample.
pub struct HeadingTraces {
    /// The virtual chassis's of the true links ([`true_headings`]).
    pub raw: Vec<f64>,
    /// `raw` low-passed as the controller filters its estimate.
    pub truth: Vec<f64>,
    /// The controller's low-passed estimate, turned onto the truth where it first had
    /// one (the estimate's yaw is its own); NaN before.
    pub estimate: Vec<f64>,
    /// The heading the controller steers to: its nominal plus its well, turned alike;
    /// NaN before an estimate. The well is the controller's (0 after an even number of
    /// reported reversals, π after an odd one), which holds until β is within 0.2 rad of
    /// the other well, not the one β is nearest.
    pub target: Vec<f64>,
    pub beta: Vec<f64>,
}

impl HeadingTraces {
    /// Of `rec`, with the controller's heading low-pass `heading_filter_s`.
    pub fn of(rec: &TrialRecord, heading_filter_s: f64) -> Self {
        let raw = true_headings(rec);
        let truth = low_passed(&raw, rec.sample_dt_s, heading_filter_s);
        let est = series(rec, "heading_rad").unwrap_or(&[]);
        let nominal = series(rec, "heading_nominal_rad").unwrap_or(&[]);
        let beta: Vec<f64> = series(rec, "beta_rad").unwrap_or(&[]).to_vec();
        let reversals = series(rec, "reversals").unwrap_or(&[]);
        // π after an odd count, 0 after an even one.
        let well = |k: usize, b: f64| match reversals.get(k) {
            Some(r) if r.is_finite() => PI * r.round().rem_euclid(2.0),
            _ => well_of(b),
        };
        let n = truth.len();
        let (mut estimate, mut target) = (vec![f64::NAN; n], vec![f64::NAN; n]);
        if let Some(k0) = est.iter().position(|h| h.is_finite())
            && k0 < n
        {
            let offset = wrap_pi(truth[k0] - est[k0]);
            for k in k0..n.min(est.len()) {
                estimate[k] = wrap_pi(est[k] + offset);
                if let (Some(m), Some(b)) = (nominal.get(k), beta.get(k)) {
                    target[k] = wrap_pi(m + offset + well(k, *b));
                }
            }
        }
        Self {
            raw,
            truth,
            estimate,
            target,
            beta,
        }
    }
}

/// Per link, where (arc length along the array) it last crossed the line to the far
/// side; the opening most links went through.
fn opening_passed(fence: &Fence, rec: &TrialRecord) -> Option<usize> {
    let n = rec.start_links_m.len();
    let samples = rec.centre_m.len();
    let mut votes = vec![0usize; fence.openings.len()];
    for link in 0..n {
        let mut last = None;
        for k in 1..samples {
            let (a, b) = (rec.links_at(k - 1), rec.links_at(k));
            let ((ua, da), (ub, db)) = (fence.coords(a[link]), fence.coords(b[link]));
            if da < 0.0 && db >= 0.0 {
                let t = -da / (db - da);
                last = Some(ua + t * (ub - ua));
            }
        }
        if let Some(o) = last.and_then(|u| fence.opening_at(u)) {
            votes[o] += 1;
        }
    }
    (0..votes.len())
        .filter(|&o| votes[o] > 0)
        .max_by_key(|&o| (votes[o], std::cmp::Reverse(o)))
}

/// The opening nearest the first link to come within touching distance of the array.
fn first_opening(fence: &Fence, rec: &TrialRecord) -> Option<usize> {
    let touch = fence.clear_m + 0.02;
    (0..rec.centre_m.len()).find_map(|k| {
        rec.links_at(k)
            .iter()
            .map(|p| fence.coords(*p))
            .filter(|(_, d)| *d > -touch)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .and_then(|(u, _)| fence.opening_at(u))
    })
}

/// The figures of `rec` on `fence`; `heading_filter_s` is the controller's heading
/// low-pass (the true heading is filtered alike before comparing).
pub fn sidewinding_metrics(
    fence: &Fence,
    rec: &TrialRecord,
    heading_filter_s: f64,
) -> SidewindingMetrics {
    let last = rec.centre_m.len().saturating_sub(1);
    let through = rec.success && fence.through(rec.links_at(last).iter().copied());
    let outcome = if through {
        Outcome::Through
    } else if rec.success {
        Outcome::OffBoard
    } else {
        Outcome::Timeout
    };
    let opening = if through {
        opening_passed(fence, rec)
    } else {
        None
    };
    let first = first_opening(fence, rec);
    let openings_passed = match (first, opening) {
        (Some(a), Some(b)) => Some(a.abs_diff(b)),
        _ => None,
    };
    let dt = rec.sample_dt_s;
    let reversals_s = series(rec, "reversals").unwrap_or(&[]);
    let first_rev = reversals_s.iter().position(|&r| r >= 1.0);
    let reversals = reversals_s
        .iter()
        .rev()
        .find(|v| v.is_finite())
        .map_or(0, |&r| r as u64);
    let first_reversal_s = first_rev.map_or(f64::NAN, |k| k as f64 * dt);
    let reverse_beyond_s = if through && first_rev.is_some() {
        first_reversal_s.max(rec.seconds)
    } else {
        f64::NAN
    };

    let h = HeadingTraces::of(rec, heading_filter_s);
    let (mut sum, mut max, mut count) = (0.0, 0.0_f64, 0usize);
    for (e, t) in h.estimate.iter().zip(&h.truth) {
        if e.is_finite() {
            let e = wrap_pi(e - t).abs();
            sum += e;
            max = max.max(e);
            count += 1;
        }
    }
    let mut heading_error_end_rad = f64::NAN;
    if let Some(n) = h.target.last().filter(|n| n.is_finite()) {
        let cycle = ((TAU / rec.temporal_freq_rad_s.abs()) / dt)
            .round()
            .max(1.0) as usize;
        let from = h.raw.len().saturating_sub(cycle);
        heading_error_end_rad = wrap_pi(circular_mean(&h.raw[from..]) - n);
    }
    let progress_m = match (rec.centre_m.first(), rec.centre_m.last()) {
        (Some(a), Some(b)) => {
            let f = fence.forward();
            (b[0] - a[0]) * f[0] + (b[1] - a[1]) * f[1]
        }
        _ => 0.0,
    };
    SidewindingMetrics {
        outcome,
        seconds: rec.seconds,
        first_opening: first,
        opening,
        openings_passed,
        opening_width_m: opening.map_or(f64::NAN, |o| fence.openings[o].width_m()),
        reversals,
        first_reversal_s,
        reverse_beyond_s,
        heading_error_end_rad,
        estimate_error_mean_rad: if count > 0 {
            sum / count as f64
        } else {
            f64::NAN
        },
        estimate_error_max_rad: if count > 0 { max } else { f64::NAN },
        progress_m,
        self_contacts: rec.self_contacts,
    }
}

/// One controller's trials.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerSummary {
    pub controller: String,
    pub trials: usize,
    pub through: usize,
    pub off_board: usize,
    pub timeouts: usize,
    /// Openings passed before entering, over the trials that went through: mean, sd,
    /// median.
    pub openings_passed: Option<(f64, f64, f64)>,
    /// Time to reverse beyond the array, over the trials that did.
    pub reverse_beyond_s: Option<(f64, f64, f64)>,
    /// Trials whose β reversed at least once.
    pub reversed: usize,
    /// |heading error| at the end, mean over the trials that had an estimate.
    pub heading_error_end_rad: Option<(f64, f64, f64)>,
    /// Mean and worst estimate error over the trials.
    pub estimate_error_mean_rad: f64,
    pub estimate_error_max_rad: f64,
    pub progress_m: (f64, f64, f64),
}

/// Per controller, in the order they appear.
pub fn summarise(results: &[TrialResult<super::SidewindingPegs>]) -> Vec<ControllerSummary> {
    crate::lab::runner::controller_names(results)
        .into_iter()
        .map(|name| {
            let ms: Vec<&SidewindingMetrics> = results
                .iter()
                .filter(|r| r.controller == name)
                .map(|r| &r.metrics)
                .collect();
            let stat = |f: &dyn Fn(&SidewindingMetrics) -> f64| {
                let v: Vec<f64> = ms.iter().map(|m| f(m)).filter(|v| v.is_finite()).collect();
                mean_sd_median(&v)
            };
            let count = |o: Outcome| ms.iter().filter(|m| m.outcome == o).count();
            let est: Vec<f64> = ms
                .iter()
                .map(|m| m.estimate_error_mean_rad)
                .filter(|v| v.is_finite())
                .collect();
            ControllerSummary {
                controller: name.to_owned(),
                trials: ms.len(),
                through: count(Outcome::Through),
                off_board: count(Outcome::OffBoard),
                timeouts: count(Outcome::Timeout),
                openings_passed: stat(&|m| m.openings_passed.map_or(f64::NAN, |o| o as f64)),
                reverse_beyond_s: stat(&|m| m.reverse_beyond_s),
                reversed: ms.iter().filter(|m| m.reversals > 0).count(),
                heading_error_end_rad: stat(&|m| m.heading_error_end_rad.abs()),
                estimate_error_mean_rad: mean_sd_median(&est).map_or(f64::NAN, |s| s.0),
                estimate_error_max_rad: ms
                    .iter()
                    .map(|m| m.estimate_error_max_rad)
                    .filter(|v| v.is_finite())
                    .fold(f64::NAN, f64::max),
                progress_m: stat(&|m| m.progress_m).unwrap_or((f64::NAN, f64::NAN, f64::NAN)),
            }
        })
        .collect()
}

#[cfg(test)]
#[path = "metrics_tests.rs"]
mod tests;
