//! The simulated source through a trial of the daemon's own loop: its fixes fused
//! into the pose estimate track the body's true position; a degraded one less well,
//! and it goes stale while occluded.

use super::*;
use crate::emu::world::WorldSpec;
use crate::gait::GaitKind;
use crate::lab::compared::LabController;
use crate::lab::trial::{TrialConfig, run_trial};

fn trial(source: Option<SourceConfig>, seconds: f64) -> crate::lab::trial::TrialRecord {
    let board = crate::lab::trial::tests::open_board();
    let config = TrialConfig {
        limit_s: seconds,
        pose_source: source,
        ..TrialConfig::default()
    };
    let c = LabController::named(GaitKind::Sidewinding, "open_loop").unwrap();
    run_trial(&c, &WorldSpec::default(), &board, 3, &config, None).unwrap()
}

fn tracked(errors: &[f64]) -> Vec<f64> {
    errors.iter().copied().filter(|e| e.is_finite()).collect()
}

#[test]
fn a_lab_source_is_fused_within_millimetres_of_the_truth() {
    let rec = trial(Some(SourceConfig::LAB), 6.0);
    assert_eq!(rec.position_error_m.len(), rec.centre_m.len());
    let e = tracked(&rec.position_error_m);
    assert!(
        e.len() > rec.centre_m.len() * 3 / 4,
        "tracking most of the run: {}",
        e.len()
    );
    let worst = e.iter().cloned().fold(0.0, f64::max);
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    eprintln!(
        "lab source: {} of {} samples tracked, mean {mean} m, worst {worst} m",
        e.len(),
        rec.position_error_m.len()
    );
    assert!(
        mean < 0.01 && worst < 0.03,
        "mean {mean} m, worst {worst} m"
    );
    // Without a source nothing is fused, and nothing is reported.
    assert!(trial(None, 0.5).position_error_m.is_empty());
}

#[test]
fn a_degraded_source_is_coarser_and_stale_while_occluded() {
    let degraded = SourceConfig {
        occlusions_per_s: 0.5,
        ..SourceConfig::DEGRADED
    };
    let rec = trial(Some(degraded), 10.0);
    let e = tracked(&rec.position_error_m);
    assert!(!e.is_empty());
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    let worst = e.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "degraded source: {} of {} samples tracked, mean {mean} m, worst {worst} m",
        e.len(),
        rec.position_error_m.len()
    );
    assert!(mean < 0.08, "mean {mean} m");
    let stale = rec
        .position_error_m
        .iter()
        .skip(40)
        .filter(|e| e.is_nan())
        .count();
    assert!(stale > 0, "occlusions make it stale at times");
}

#[test]
fn the_source_is_deterministic_and_checks_its_settings() {
    let a = trial(Some(SourceConfig::DEGRADED), 2.0);
    let b = trial(Some(SourceConfig::DEGRADED), 2.0);
    assert_eq!(
        format!("{:?}", a.position_error_m),
        format!("{:?}", b.position_error_m)
    );
    assert!(SourceConfig::LAB.check().is_ok() && SourceConfig::DEGRADED.check().is_ok());
    let bad = SourceConfig {
        rate_hz: 0.0,
        ..SourceConfig::LAB
    };
    assert!(bad.check().unwrap_err().contains("rate_hz"));
}
