//! The pole experiment's figures:
//! - [`climb_plot`]: the body centre's height over time, one line per controller on
//!   the first pole and start, the diameter changes and the top marked;
//! - [`windows_plot`]: a windowed controller's half turns on the pole, each second: the
//!   coil's inner diameter its ρ (and its set point) stands for against the pole's
//!   diameter where the half turn lies; on the diagonal the coil fits the pole exactly.

use std::path::Path;

use plotters::prelude::*;

use super::poles::diameter_at;
use super::{PoleClimb, PoleGoal};
use crate::lab::LabError;
use crate::lab::plots::{FONT, plot_err, register_fonts};
use crate::lab::runner::{TrialResult, controller_names};
use crate::lab::trial::TrialRecord;
use crate::module::MODULE_DIAMETER_M;

/// Every controller's first trial: height over time.
pub fn climb_plot(path: &Path, results: &[TrialResult<PoleClimb>]) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let root = BitMapBackend::new(path, (1000, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let plotted: Vec<_> = results
        .iter()
        .filter_map(|r| r.plotted.as_ref().map(|p| (r, p)))
        .collect();
    let t_max = plotted
        .iter()
        .map(|(_, (_, _, rec))| rec.seconds)
        .fold(1.0, f64::max);
    let title = plotted.first().map_or_else(
        || "no trial to plot".to_string(),
        |(r, _)| format!("centre height: pole {}, start {}", r.layout, r.start),
    );
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .caption(title, (FONT, 18))
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..t_max, 0.0..1.5)
        .map_err(&err)?;
    chart
        .configure_mesh()
        .x_desc("time, s")
        .y_desc("centre height, m")
        .label_style((FONT, 13))
        .draw()
        .map_err(&err)?;
    if let Some((_, (_, goal, _))) = plotted.first() {
        for &z in &goal.changes_m {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    [(0.0, z), (t_max, z)],
                    RGBColor(150, 150, 150).stroke_width(1),
                )))
                .map_err(&err)?;
        }
        chart
            .draw_series(std::iter::once(PathElement::new(
                [(0.0, goal.top_m), (t_max, goal.top_m)],
                RGBColor(0, 150, 60).stroke_width(2),
            )))
            .map_err(&err)?;
    }
    let names = controller_names(results);
    for (r, (_, _, rec)) in &plotted {
        let i = names.iter().position(|n| *n == r.controller).unwrap_or(0);
        let colour = Palette99::pick(i).to_rgba();
        let samples = rec.heights_m.len() / rec.start_links_m.len().max(1);
        chart
            .draw_series(LineSeries::new(
                (0..samples).map(|k| (k as f64 * rec.sample_dt_s, rec.centre_height(k))),
                colour.stroke_width(2),
            ))
            .map_err(&err)?
            .label(format!("{} ({})", r.controller, r.metrics.outcome.name()))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .draw()
        .map_err(&err)?;
    root.present().map_err(&err)?;
    Ok(())
}

/// The inner diameter of a coil whose radius parameter is `scale` × the nominal
/// (`r = r_0/ρ`: the helix parameter grows as the coil tightens), m.
fn inner_diameter(nominal_radius_m: f64, scale: f64) -> f64 {
    2.0 * (nominal_radius_m / scale - 0.5 * MODULE_DIAMETER_M)
}

/// The half turns of one trial against the pole's diameter where they lie.
pub fn windows_plot(
    path: &Path,
    title: &str,
    goal: &PoleGoal,
    rec: &TrialRecord,
) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let root = BitMapBackend::new(path, (800, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let every = ((1.0 / rec.sample_dt_s).round() as usize).max(1);
    let n = rec.start_links_m.len();
    let (mut coil, mut set) = (Vec::new(), Vec::new());
    for (k, windows) in rec.windows.iter().enumerate().step_by(every) {
        let heights = rec.heights_at(k);
        if heights.len() < n {
            break;
        }
        let links = rec.links_at(k);
        for w in windows {
            let link = ((w[0] * (n - 1) as f64).round() as usize).min(n - 1);
            let d = diameter_at(&goal.sections, heights[link]);
            // Only half turns on the pole (their middle link against it; the pole
            // stands at the origin): the ends hanging off it hold nothing.
            let [x, y] = links[link];
            if x.hypot(y) > 0.5 * (d + MODULE_DIAMETER_M) + 0.015 {
                continue;
            }
            coil.push((d, inner_diameter(goal.nominal_radius_m, w[1])));
            set.push((d, inner_diameter(goal.nominal_radius_m, w[2])));
        }
    }
    let all = || coil.iter().chain(&set);
    let lo = all().map(|p| p.0.min(p.1)).fold(0.08, f64::min).max(0.0);
    let hi = all().map(|p| p.0.max(p.1)).fold(0.25, f64::max);
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .caption(title, (FONT, 17))
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(lo..hi, lo..hi)
        .map_err(&err)?;
    chart
        .configure_mesh()
        .x_desc("pole diameter where the half turn lies, m")
        .y_desc("coil's inner diameter, m")
        .label_style((FONT, 13))
        .draw()
        .map_err(&err)?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            [(lo, lo), (hi, hi)],
            BLACK.stroke_width(1),
        )))
        .map_err(&err)?
        .label("fits the pole")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    let blue = RGBColor(30, 90, 200);
    let orange = RGBColor(230, 120, 0);
    chart
        .draw_series(
            coil.iter()
                .map(|&p| Circle::new(p, 2, blue.mix(0.5).filled())),
        )
        .map_err(&err)?
        .label("R (each half turn on the pole, every 1 s)")
        .legend(move |(x, y)| Circle::new((x + 9, y), 3, blue.filled()));
    chart
        .draw_series(
            set.iter()
                .map(|&p| Circle::new(p, 2, orange.mix(0.5).filled())),
        )
        .map_err(&err)?
        .label("set point")
        .legend(move |(x, y)| Circle::new((x + 9, y), 3, orange.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .draw()
        .map_err(&err)?;
    root.present().map_err(&err)?;
    Ok(())
}
