//! A displacement trial's figures and their summaries: per trial, per pose (the mean of
//! its repeats) and per controller (mean and spread over trials and over poses).

use crate::lab::metrics::mean_sd_median;
use crate::lab::runner::TrialResult;
use crate::lab::trial::TrialRecord;

use super::Displacement;

/// One trial's figures.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DisplacementMetrics {
    /// Simulated time of the trial, s.
    pub seconds: f64,
    /// Straight-line displacement of the body's centre from start to end, m.
    pub displacement_m: f64,
    /// `displacement / body length / minutes` (body length: the modules' total length).
    pub velocity_bl_min: f64,
    /// The centre's displacement along the body's start heading (tail to head), signed
    /// (negative: it slid tail first), per body length per minute. The reference's
    /// metric has no sign, so a body drifting backwards scores as if it travelled.
    pub forward_bl_min: f64,
    /// The body's centre left the obstacle field before the time limit (the trial
    /// ended there; `seconds` is the time it took).
    pub left_field: bool,
    /// Contact onsets between non-adjacent links.
    pub self_contacts: u64,
    /// Window mode switches the controller reported (NaN if it reports none).
    pub mode_switches: f64,
    /// Share of the controller's samples with some window in PDC or NDC (NaN if it
    /// reports none).
    pub directional_share: f64,
}

/// The last finite value of signal `name`, if reported.
fn last(rec: &TrialRecord, name: &str) -> Option<f64> {
    let k = rec.signal_names.iter().position(|n| n == name)?;
    rec.signals[k].iter().rev().copied().find(|v| v.is_finite())
}

/// Unit vector from the tail to the head at the start, if the body had length.
fn start_heading(rec: &TrialRecord) -> Option<[f64; 2]> {
    let (h, t) = (rec.start_links_m.first()?, rec.start_links_m.last()?);
    let d = [h[0] - t[0], h[1] - t[1]];
    let l = d[0].hypot(d[1]);
    (l > 1e-9).then(|| [d[0] / l, d[1] / l])
}

/// The figures of `rec` for a body `body_length_m` long.
pub fn displacement_metrics(rec: &TrialRecord, body_length_m: f64) -> DisplacementMetrics {
    let (a, b) = (
        rec.centre_m.first().copied().unwrap_or_default(),
        rec.centre_m.last().copied().unwrap_or_default(),
    );
    let displacement_m = (b[0] - a[0]).hypot(b[1] - a[1]);
    let forward_m =
        start_heading(rec).map_or(f64::NAN, |h| (b[0] - a[0]) * h[0] + (b[1] - a[1]) * h[1]);
    let minutes = (rec.seconds / 60.0).max(1e-9);
    let series = |name: &str| {
        rec.signal_names
            .iter()
            .position(|n| n == name)
            .map(|k| &rec.signals[k])
    };
    let directional_share = match (series("windows_pdc"), series("windows_ndc")) {
        (Some(p), Some(n)) => {
            let both = p
                .iter()
                .zip(n)
                .filter(|(x, y)| x.is_finite() && y.is_finite());
            let (mut on, mut all) = (0usize, 0usize);
            for (x, y) in both {
                all += 1;
                on += usize::from(x + y > 0.0);
            }
            if all == 0 {
                f64::NAN
            } else {
                on as f64 / all as f64
            }
        }
        _ => f64::NAN,
    };
    DisplacementMetrics {
        seconds: rec.seconds,
        displacement_m,
        velocity_bl_min: displacement_m / body_length_m / minutes,
        forward_bl_min: forward_m / body_length_m / minutes,
        left_field: rec.success,
        self_contacts: rec.self_contacts,
        mode_switches: last(rec, "mode_switches").unwrap_or(f64::NAN),
        directional_share,
    }
}

/// One pose's trials of one controller.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSummary {
    pub layout: String,
    pub start: usize,
    pub trials: usize,
    /// Mean and sample sd of the velocity over the pose's repeats, BL/min.
    pub velocity: (f64, f64),
}

/// One controller's trials.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerSummary {
    pub controller: String,
    pub trials: usize,
    /// Mean, sample sd and median of the velocity over every trial, BL/min.
    pub velocity: (f64, f64, f64),
    /// Mean and sample sd of the signed forward velocity over every trial, BL/min.
    pub forward: (f64, f64),
    /// The pose means in plan order, and their sample sd (the spread across poses).
    pub poses: Vec<PoseSummary>,
    pub pose_sd: f64,
    /// Lowest pose mean, BL/min.
    pub worst_pose: f64,
    /// Trials whose body's centre left the obstacle field.
    pub left_field: usize,
    pub self_contacts_mean: f64,
    pub mode_switches_mean: f64,
    pub directional_share_mean: f64,
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Per controller, in the order they first appear.
pub fn summarise(results: &[TrialResult<Displacement>]) -> Vec<ControllerSummary> {
    crate::lab::runner::controller_names(results)
        .into_iter()
        .map(|name| {
            let mine: Vec<_> = results.iter().filter(|r| r.controller == name).collect();
            let v: Vec<f64> = mine.iter().map(|r| r.metrics.velocity_bl_min).collect();
            let velocity = mean_sd_median(&v).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            let f: Vec<f64> = mine.iter().map(|r| r.metrics.forward_bl_min).collect();
            let forward = mean_sd_median(&f).map_or((f64::NAN, f64::NAN), |(m, sd, _)| (m, sd));
            let mut poses: Vec<PoseSummary> = Vec::new();
            for r in &mine {
                if poses
                    .iter()
                    .any(|p| p.layout == r.layout && p.start == r.start)
                {
                    continue;
                }
                let pv: Vec<f64> = mine
                    .iter()
                    .filter(|o| o.layout == r.layout && o.start == r.start)
                    .map(|o| o.metrics.velocity_bl_min)
                    .collect();
                let (m, sd, _) = mean_sd_median(&pv).unwrap_or_default();
                poses.push(PoseSummary {
                    layout: r.layout.clone(),
                    start: r.start,
                    trials: pv.len(),
                    velocity: (m, sd),
                });
            }
            let pose_means: Vec<f64> = poses.iter().map(|p| p.velocity.0).collect();
            let (_, pose_sd, _) = mean_sd_median(&pose_means).unwrap_or_default();
            ControllerSummary {
                controller: name.to_owned(),
                trials: mine.len(),
                velocity,
                forward,
                pose_sd,
                worst_pose: pose_means.iter().copied().fold(f64::INFINITY, f64::min),
                poses,
                left_field: mine.iter().filter(|r| r.metrics.left_field).count(),
                self_contacts_mean: mean(mine.iter().map(|r| r.metrics.self_contacts as f64)),
                mode_switches_mean: mean(mine.iter().map(|r| r.metrics.mode_switches)),
                directional_share_mean: mean(mine.iter().map(|r| r.metrics.directional_share)),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::experiment::Experiment;

    fn record(centre: Vec<[f64; 2]>, seconds: f64) -> TrialRecord {
        TrialRecord {
            links_m: Vec::new(),
            sample_dt_s: 0.05,
            centre_m: centre,
            start_links_m: vec![[0.0; 2]; 17],
            end_links_m: vec![[0.0; 2]; 17],
            signal_names: vec![
                "windows_pdc".into(),
                "windows_ndc".into(),
                "mode_switches".into(),
            ],
            signals: vec![
                vec![f64::NAN, 0.0, 1.0, 0.0],
                vec![f64::NAN, 0.0, 0.0, 2.0],
                vec![f64::NAN, 0.0, 3.0, 5.0],
            ],
            seconds,
            success: false,
            temporal_freq_rad_s: 1.0,
            cycles_not_running: 0,
            self_contacts: 7,
            heights_m: Vec::new(),
            windows: Vec::new(),
            strain: Default::default(),
            stuck_reported: Vec::new(),
            estimate: Vec::new(),
            position_error_m: Vec::new(),
            gait_switches: 0,
        }
    }

    #[test]
    fn displacement_is_start_to_end_in_body_lengths_per_minute() {
        // 0.5 m sideways and 1.2 m on in 120 s: 1.3 m.
        let rec = record(vec![[0.0, 0.0], [3.0, 3.0], [1.2, 0.5]], 120.0);
        let m = displacement_metrics(&rec, 1.024);
        assert!((m.displacement_m - 1.3).abs() < 1e-12);
        assert!((m.velocity_bl_min - 1.3 / 1.024 / 2.0).abs() < 1e-12);
        assert_eq!(m.self_contacts, 7);
        assert_eq!(m.mode_switches, 5.0);
        assert!((m.directional_share - 2.0 / 3.0).abs() < 1e-12, "{m:?}");
        let m =
            Displacement::PEG_ARRAY.metrics(&crate::lab::displacement::FieldEdge::FULL_TIME, &rec);
        assert!(
            (m.velocity_bl_min - 1.3 / 1.024 / 2.0).abs() < 1e-12,
            "16 modules"
        );
    }

    #[test]
    fn forward_is_signed_along_the_start_heading() {
        // Head at +x: 1.2 m forward and 0.5 m sideways counts 1.2 m; sliding tail first
        // counts negative although the unsigned displacement is the same.
        let mut rec = record(vec![[0.0, 0.0], [1.2, 0.5]], 120.0);
        rec.start_links_m = (0..17).map(|k| [-0.064 * k as f64, 0.0]).collect();
        let m = displacement_metrics(&rec, 1.024);
        assert!(
            (m.forward_bl_min - 1.2 / 1.024 / 2.0).abs() < 1e-12,
            "{m:?}"
        );
        rec.centre_m = vec![[0.0, 0.0], [-1.2, 0.5]];
        let back = displacement_metrics(&rec, 1.024);
        assert!((back.forward_bl_min + 1.2 / 1.024 / 2.0).abs() < 1e-12);
        assert_eq!(back.velocity_bl_min, m.velocity_bl_min);
        // A body with no length has no heading.
        rec.start_links_m = vec![[0.0; 2]; 17];
        assert!(displacement_metrics(&rec, 1.024).forward_bl_min.is_nan());
    }

    fn result(controller: &str, start: usize, repeat: usize, v: f64) -> TrialResult<Displacement> {
        let rec = record(vec![[0.0, 0.0], [v * 1.024 * 2.0, 0.0]], 120.0);
        TrialResult {
            controller: controller.into(),
            layout: "seed101".into(),
            start,
            repeat,
            metrics: displacement_metrics(&rec, 1.024),
            strain: Default::default(),
            stuck: Default::default(),
            odometry: Default::default(),
            position: Default::default(),
            plotted: None,
        }
    }

    #[test]
    fn summaries_pool_repeats_per_pose_and_spread_across_poses() {
        let results = vec![
            result("a", 0, 0, 1.0),
            result("a", 0, 1, 3.0),
            result("a", 1, 0, 0.0),
            result("a", 1, 1, 0.0),
            result("b", 0, 0, 1.0),
            result("b", 1, 0, 1.0),
        ];
        let s = summarise(&results);
        assert_eq!(s.len(), 2);
        let a = &s[0];
        assert_eq!((a.controller.as_str(), a.trials), ("a", 4));
        assert!((a.velocity.0 - 1.0).abs() < 1e-9);
        assert_eq!(a.poses.len(), 2);
        assert!((a.poses[0].velocity.0 - 2.0).abs() < 1e-9);
        assert!((a.pose_sd - 2f64.sqrt()).abs() < 1e-9, "sd of 2 and 0");
        assert!(a.worst_pose.abs() < 1e-9);
        assert!(s[1].pose_sd.abs() < 1e-9);
        assert_eq!(a.self_contacts_mean, 7.0);
    }
}
