//! Tests of the PNG figures on synthetic records.

use super::*;
use crate::emu::world::Peg;
use crate::emu::world::scenario::Region;
use crate::lab::pegboard::board::Board;

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

pub(crate) fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.len() > 1000 && b.starts_with(&PNG_SIGNATURE))
}

pub(crate) fn record(signals: usize) -> TrialRecord {
    let centre_m: Vec<[f64; 2]> = (0..200)
        .map(|k| [0.01 * k as f64, 0.05 * (0.05 * k as f64).sin()])
        .collect();
    let body = |x0: f64| (0..19).map(|k| [x0 - 0.064 * k as f64, 0.0]).collect();
    TrialRecord {
        links_m: Vec::new(),
        sample_dt_s: 0.05,
        start_links_m: body(0.3),
        end_links_m: body(2.3),
        signal_names: (0..signals)
            .map(|i| format!("amplitude[{i}]_rad"))
            .collect(),
        signals: (0..signals)
            .map(|i| {
                (0..200)
                    .map(|k| (i as f64 + 0.01 * k as f64).sin())
                    .collect()
            })
            .collect(),
        centre_m,
        seconds: 10.0,
        success: true,
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
    }
}

#[test]
fn every_figure_is_a_png() {
    let dir = tempfile::tempdir().unwrap();
    let world = WorldSpec {
        pegs: vec![Peg {
            x_m: 1.0,
            y_m: 0.2,
            diameter_m: 0.04,
            height_m: 0.15,
        }],
        ..WorldSpec::default()
    };
    let region = Region {
        x_m: [0.0, 2.0],
        y_m: [-0.6, 0.6],
    };
    let board = Board::new(region, std::f64::consts::PI);
    let p = dir.path().join("path.png");
    path_plot(&p, "path", &world, Some(&board.region), &record(0)).unwrap();
    assert!(is_png(&p));
    for n in [0, 3, MAX_SIGNAL_PANELS + 2] {
        let p = dir.path().join(format!("signals{n}.png"));
        signals_plot(&p, "signals", &record(n)).unwrap();
        assert!(is_png(&p), "{n} signals");
    }
}

#[test]
fn bounds_grow_by_the_margin_and_survive_no_points() {
    let b = bounds([[0.0, 1.0], [2.0, -1.0]].into_iter(), 0.5);
    assert_eq!(b, [-0.5, 2.5, -1.5, 1.5]);
    assert_eq!(bounds(std::iter::empty(), 0.0), [-1.0, 1.0, -1.0, 1.0]);
}
