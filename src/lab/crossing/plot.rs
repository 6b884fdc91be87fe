//! The navigator's trial over the board: its centre path coloured by what it ran
//! (sidewinding towards the far side, backing off, slithering), as the loop reported it
//! each sample (`navigator_choice`, the trial's only signal for the navigator).

use std::path::Path;

use plotters::prelude::*;

use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::Region;
use crate::lab::LabError;
use crate::lab::plots::{draw_legend, draw_path, path_height, plot_err, register_fonts};
use crate::lab::trial::TrialRecord;
use crate::navigation::navigator::Choice;

pub use crate::lab::trial_navigator::CHOICE_SIGNAL;

fn colour(c: Choice) -> RGBColor {
    match c {
        Choice::Sidewind => RGBColor(230, 120, 0),
        Choice::BackOff => RGBColor(150, 40, 170),
        Choice::Slither => RGBColor(0, 150, 130),
        Choice::Turn => RGBColor(200, 30, 90),
    }
}

/// The path figure ([`draw_path`]) with the centre coloured by the navigator's choice.
pub fn choice_path_plot(
    path: &Path,
    title: &str,
    world: &WorldSpec,
    region: Option<&Region>,
    rec: &TrialRecord,
) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let width = 1100u32;
    let height = path_height(width, world, region, rec);
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    let mut chart = draw_path(&root, path, title, world, region, rec)?;
    let choices = rec
        .signal_names
        .iter()
        .position(|n| n == CHOICE_SIGNAL)
        .map(|k| &rec.signals[k][..])
        .unwrap_or(&[]);
    let mut labelled = [false; 4];
    for (k, c) in [
        Choice::Sidewind,
        Choice::BackOff,
        Choice::Slither,
        Choice::Turn,
    ]
    .into_iter()
    .enumerate()
    {
        for run in runs(choices, c.code()) {
            // One sample further, so consecutive runs join.
            let end = (run.end + 1).min(rec.centre_m.len());
            let points: Vec<(f64, f64)> = rec.centre_m[run.start..end]
                .iter()
                .map(|p| (p[0], p[1]))
                .collect();
            let style = colour(c).stroke_width(3);
            let s = chart
                .draw_series(LineSeries::new(points, style))
                .map_err(&err)?;
            if !labelled[k] {
                labelled[k] = true;
                s.label(format!("navigator: {}", c.name()))
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
            }
        }
    }
    draw_legend(&mut chart, path)?;
    root.present().map_err(&err)
}

/// The index ranges where `series` equals `code`.
fn runs(series: &[f64], code: f64) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &v) in series.iter().enumerate() {
        match (v == code, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push(s..i);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push(s..series.len());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_are_the_stretches_of_one_choice() {
        let s = [0.0, 1.0, 1.0, 2.0, 1.0, 3.0, 3.0];
        assert_eq!(runs(&s, 1.0), vec![1..3, 4..5]);
        assert_eq!(runs(&s, 3.0), vec![5..7]);
        assert!(runs(&s, 2.5).is_empty());
    }
}
