use super::*;
use crate::emu::world::scenario::WorldScenario;

const FENCE: &str = "seed = 5\n[[peg_fence]]\nstart_m = [-2.0, -0.5]\nlength_m = 4.0\n\
    diameter_m = 0.05\ngap_m = [0.1, 0.3]\njitter_m = 0.0\n\
    [start]\nhead_m = [0.5, 0.0]\nyaw_rad = 3.14159\n";

/// A straight body along x (head at +x) sliding from y = 0 down through x ≈ `at` to
/// y = −1, with β reversing at `rev_s`.
fn record(at: f64, through: bool, rev_s: Option<f64>) -> (Fence, TrialRecord) {
    let s = WorldScenario::parse(FENCE).unwrap();
    let w = s.generate(18).unwrap();
    let fence = Fence::new(&s.peg_fences[0], &w, 18);
    let n = 5;
    let samples = 100;
    let mut links = Vec::new();
    let mut centre = Vec::new();
    let end_y = if through { -1.0 } else { -0.3 };
    for k in 0..samples {
        let y = end_y * k as f64 / (samples - 1) as f64;
        for l in 0..n {
            links.push([at + 0.02 * (2.0 - l as f64), y]);
        }
        centre.push([at, y]);
    }
    let names = [
        "beta_rad",
        "heading_rad",
        "heading_nominal_rad",
        "reversals",
    ];
    let dt = 0.1;
    let signals = vec![
        (0..samples)
            .map(|k| match rev_s {
                Some(t) if k as f64 * dt >= t => PI,
                _ => 0.0,
            })
            .collect(),
        vec![0.3; samples],
        vec![0.3; samples],
        (0..samples)
            .map(|k| match rev_s {
                Some(t) if k as f64 * dt >= t => 1.0,
                _ => 0.0,
            })
            .collect(),
    ];
    let rec = TrialRecord {
        sample_dt_s: dt,
        centre_m: centre,
        start_links_m: links[..n].to_vec(),
        end_links_m: links[links.len() - n..].to_vec(),
        links_m: links,
        signal_names: names.iter().map(|s| s.to_string()).collect(),
        signals,
        seconds: samples as f64 * dt,
        success: through,
        temporal_freq_rad_s: 1.0,
        cycles_not_running: 0,
        self_contacts: 0,
        heights_m: Vec::new(),
        windows: Vec::new(),
        strain: Default::default(),
        stuck_reported: Vec::new(),
        estimate: Vec::new(),
        position_error_m: Vec::new(),
        gait_switches: 0,
    };
    (fence, rec)
}

#[test]
fn a_body_through_an_opening_counts_it_and_the_reversal() {
    let (fence, _) = record(0.0, true, None);
    let o = 4;
    let mid = (fence.openings[o].from_m + fence.openings[o].to_m) / 2.0;
    let (x, _) = (mid - 2.0, 0.0); // the fence starts at x = −2
    let (fence, rec) = record(x, true, Some(3.0));
    let m = sidewinding_metrics(&fence, &rec, 1.0);
    assert_eq!(m.outcome, Outcome::Through);
    assert_eq!(m.opening, Some(o));
    assert_eq!(m.first_opening, Some(o));
    assert_eq!(m.openings_passed, Some(0));
    assert_eq!(m.reversals, 1);
    assert!((m.first_reversal_s - 3.0).abs() < 1e-9);
    assert_eq!(m.reverse_beyond_s, rec.seconds);
    // Heading 0 all along, nominal 0.3 in the estimate = 0 in truth: in the π well the
    // body should point at π, so the error is π.
    assert!((m.heading_error_end_rad.abs() - PI).abs() < 1e-6, "{m:?}");
    assert!(m.estimate_error_max_rad < 1e-9);
    assert!((m.progress_m - 1.0).abs() < 1e-9);
    assert!(!m.failed());
}

#[test]
fn the_target_is_the_controllers_well_not_the_one_beta_is_nearest() {
    // β past the hill (2.0 rad) but never within 0.2 rad of π: the controller still
    // steers to its 0 well, and so does the target.
    let (fence, mut rec) = record(0.0, false, None);
    rec.signals[0] = vec![2.0; rec.signals[0].len()];
    let h = HeadingTraces::of(&rec, 1.0);
    assert!(h.target.iter().all(|t| t.abs() < 1e-9));
    let m = sidewinding_metrics(&fence, &rec, 1.0);
    assert!(m.heading_error_end_rad.abs() < 1e-6, "{m:?}");
    // A recording without the count falls back to the nearer well.
    rec.signal_names[3] = "other".into();
    let h = HeadingTraces::of(&rec, 1.0);
    assert!(h.target.iter().all(|t| (t.abs() - PI).abs() < 1e-9));
}

#[test]
fn a_body_that_never_gets_through_is_a_failed_attempt() {
    let (fence, rec) = record(0.0, false, None);
    let m = sidewinding_metrics(&fence, &rec, 1.0);
    assert_eq!(m.outcome, Outcome::Timeout);
    assert!(m.failed() && m.opening.is_none() && m.openings_passed.is_none());
    assert!(m.reverse_beyond_s.is_nan() && m.first_reversal_s.is_nan());
    assert!(m.heading_error_end_rad.abs() < 1e-6);
}
