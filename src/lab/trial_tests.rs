//! Tests of one trial through the daemon's loop.

use super::*;
use crate::emu::world::scenario::Region;
use crate::lab::pegboard::board::Board;

#[test]
fn nominal_patches_the_gait_as_the_daemon_checks_it() {
    let table = nominal_gaits(GaitKind::Slithering, Some(r#"{"amplitude_lat_rad":1.1}"#)).unwrap();
    let p = table.get(GaitKind::Slithering);
    assert_eq!(p.amplitude_lat_rad, 1.1);
    let d = GaitTable::default();
    assert_eq!(
        p.spatial_freq_rad,
        d.get(GaitKind::Slithering).spatial_freq_rad
    );
    assert_eq!(table.get(GaitKind::Rolling), d.get(GaitKind::Rolling));
    assert_eq!(nominal_gaits(GaitKind::Slithering, None).unwrap(), d);
    for bad in [
        r#"{"amplitude_lat_rad":2.0}"#,
        r#"{"amplitude":1.0}"#,
        r#"{"amplitude_dor_rad":0.3}"#,
        "not json",
    ] {
        let e = nominal_gaits(GaitKind::Slithering, Some(bad)).unwrap_err();
        assert!(e.to_string().contains("--nominal"), "{bad}: {e}");
    }
}

#[test]
fn sampling_cadence() {
    let c = TrialConfig::default();
    assert_eq!(c.steps_per_sample(), 50);
    assert!((c.sample_dt_s() - 0.05).abs() < 1e-12);
}

/// A board far wider than any short trial goes: nothing ends it early.
pub(crate) fn open_board() -> Board {
    Board::new(
        Region {
            x_m: [-5.0, 5.0],
            y_m: [-5.0, 5.0],
        },
        std::f64::consts::PI,
    )
}

#[test]
fn a_short_open_loop_trial_records_and_moves_the_joints() {
    let world = WorldSpec::default();
    let board = open_board();
    let config = TrialConfig {
        limit_s: 0.5,
        ..TrialConfig::default()
    };
    let open_loop = LabController::named(GaitKind::Slithering, "open_loop").unwrap();
    let rec = run_trial(&open_loop, &world, &board, 7, &config, None).unwrap();
    assert!(!rec.success);
    assert!((rec.seconds - 0.5).abs() < 1e-9);
    assert_eq!(rec.centre_m.len(), 11, "t = 0 and every 50 ms");
    assert_eq!(rec.start_links_m.len(), 19);
    assert_ne!(rec.start_links_m, rec.end_links_m, "the body moved");
    assert_eq!(rec.temporal_freq_rad_s, 1.0);
    assert_eq!(rec.signal_names.len(), rec.signals.len());
    let again = run_trial(&open_loop, &world, &board, 7, &config, None).unwrap();
    // Debug text: NaN (no signal before the takeover) equals itself there.
    assert_eq!(format!("{rec:?}"), format!("{again:?}"), "deterministic");
}

#[test]
fn a_trial_ends_when_the_front_half_crosses() {
    // A board whose far edge is just ahead of the straight body's front half: the
    // front half starts beyond the x_max edge (entry x_min), so the first sample ends it.
    let world = WorldSpec::default();
    let board = Board::new(
        Region {
            x_m: [-3.0, -0.5],
            y_m: [-1.0, 1.0],
        },
        std::f64::consts::PI,
    );
    let config = TrialConfig {
        limit_s: 2.0,
        ..TrialConfig::default()
    };
    let open_loop = LabController::named(GaitKind::Slithering, "open_loop").unwrap();
    let rec = run_trial(&open_loop, &world, &board, 1, &config, None).unwrap();
    assert!(rec.success);
    assert!((rec.seconds - 0.05).abs() < 1e-9, "{}", rec.seconds);
}
