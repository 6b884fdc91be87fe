//! The peg board's own figure: every trial's cycles per metre per controller.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::Pegboard;
use super::report::summarise;
use crate::lab::LabError;
use crate::lab::plots::{FONT, plot_err, register_fonts};
use crate::lab::runner::TrialResult;

/// Cycles per metre of every trial, per controller: each trial a dot (filled: success,
/// hollow: not), the mean as a bar and ± one sd as a whisker; log scale.
pub fn results_plot(path: &Path, results: &[TrialResult<Pegboard>]) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let sums = summarise(results);
    let n = sums.len().max(1);
    let values = results.iter().map(|r| r.metrics.cycles_per_m);
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (lo, hi) = if lo.is_finite() {
        (lo / 1.5, hi * 1.5)
    } else {
        (0.1, 10.0)
    };
    let width = (220 * n as u32 + 160).max(500);
    let root = BitMapBackend::new(path, (width, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Time to traverse per controller", (FONT, 22))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), (lo..hi).log_scale())
        .map_err(&err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("body-wave cycles per metre (lower is better)")
        .label_style((FONT, 14))
        .draw()
        .map_err(&err)?;
    for (i, s) in sums.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let x = i as f64;
        let mine: Vec<_> = results
            .iter()
            .filter(|r| r.controller == s.controller)
            .collect();
        let m = mine.len().max(2) as f64 - 1.0;
        chart
            .draw_series(mine.iter().enumerate().map(|(k, r)| {
                let jitter = -0.25 + 0.5 * k as f64 / m;
                let style = if r.metrics.success {
                    colour.filled()
                } else {
                    colour.stroke_width(2)
                };
                Circle::new((x + jitter, r.metrics.cycles_per_m.clamp(lo, hi)), 5, style)
            }))
            .map_err(&err)?;
        let (mean, sd, _) = s.cycles_per_m;
        let (y0, y1) = ((mean - sd).clamp(lo, hi), (mean + sd).clamp(lo, hi));
        let ym = mean.clamp(lo, hi);
        let black = BLACK.stroke_width(3);
        chart
            .draw_series([
                PathElement::new([(x - 0.35, ym), (x + 0.35, ym)], black),
                PathElement::new([(x, y0), (x, y1)], BLACK.stroke_width(2)),
                PathElement::new([(x - 0.1, y0), (x + 0.1, y0)], BLACK.stroke_width(2)),
                PathElement::new([(x - 0.1, y1), (x + 0.1, y1)], BLACK.stroke_width(2)),
            ])
            .map_err(&err)?;
        let (px, py) = chart.backend_coord(&(x, lo));
        let label = format!("{} ({}/{})", s.controller, s.successes, s.trials);
        let style = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(label, (px, py + 10), style))
            .map_err(&err)?;
    }
    root.present().map_err(&err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::pegboard::metrics::TrialMetrics;
    use crate::lab::plots::tests::is_png;

    #[test]
    fn the_results_figure_is_a_png() {
        let dir = tempfile::tempdir().unwrap();
        let results: Vec<TrialResult<Pegboard>> = (0..5)
            .map(|k| TrialResult {
                controller: if k < 3 { "a" } else { "b" }.into(),
                layout: "seed1".into(),
                start: k,
                repeat: 0,
                metrics: TrialMetrics {
                    success: k % 2 == 0,
                    seconds: 50.0,
                    cycles: 8.0,
                    path_m: 1.0,
                    distance_m: 1.0,
                    cycles_per_m: 5.0 + k as f64,
                    stuck_s: 0.0,
                    self_contacts: 0,
                    side_exit: false,
                    progress_m: 1.0,
                },
                strain: Default::default(),
                stuck: Default::default(),
                odometry: Default::default(),
                position: Default::default(),
                plotted: None,
            })
            .collect();
        let p = dir.path().join("results.png");
        results_plot(&p, &results).unwrap();
        assert!(is_png(&p));
        let bad = dir.path().join("no/such/dir/x.png");
        assert!(matches!(
            results_plot(&bad, &results),
            Err(LabError::Plot { .. })
        ));
    }
}
