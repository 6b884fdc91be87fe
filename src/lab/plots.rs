//! The plot primitives every experiment may use (plotters, bitmap backend; text in
//! DejaVu Sans from the `dejavu` crate, so no system font is needed):
//! - [`path_plot`]: a trial's centre path over its obstacles, start and end poses;
//! - [`signals_plot`]: the controller's signals over time, one panel each.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::LabError;
use super::metrics::{MetricsConfig, moving_average};
use super::trial::TrialRecord;
use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::Region;

/// Panels drawn at most by [`signals_plot`]; further signals are left out (and said so).
pub const MAX_SIGNAL_PANELS: usize = 12;

pub(crate) const FONT: &str = "sans-serif";

pub(crate) fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font shipped in the crate; a failure would
        // surface as a plot error at the first text drawn.
        let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

pub(crate) fn plot_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> LabError + '_ {
    move |e| LabError::Plot {
        path: path.to_owned(),
        msg: e.to_string(),
    }
}

/// Bounds `[x0, x1, y0, y1]` of `points`, grown by `margin_m`.
fn bounds(points: impl Iterator<Item = [f64; 2]>, margin_m: f64) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for [x, y] in points {
        b = [b[0].min(x), b[1].max(x), b[2].min(y), b[3].max(y)];
    }
    if !b.iter().all(|v| v.is_finite()) {
        b = [-1.0, 1.0, -1.0, 1.0];
    }
    [
        b[0] - margin_m,
        b[1] + margin_m,
        b[2] - margin_m,
        b[3] + margin_m,
    ]
}

/// A trial's body-centre path (raw and smoothed as the metrics smooth it) over the
/// obstacles: pegs and rocks to scale (rocks by their footprint's reach), the board's
/// region when there is one, the body at the start and at the end.
pub fn path_plot(
    path: &Path,
    title: &str,
    world: &WorldSpec,
    region: Option<&Region>,
    rec: &TrialRecord,
) -> Result<(), LabError> {
    register_fonts();
    let width = 1100u32;
    let height = path_height(width, world, region, rec);
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    draw_path(&root, path, title, world, region, rec)?;
    root.present().map_err(plot_err(path))
}

/// A controller's plotted trial as most experiments show it: `path-<label>.png` (the
/// path over the obstacles and `region`) and `signals-<label>.png`, titled `title`.
pub fn path_and_signals(
    dir: &Path,
    label: &str,
    title: &str,
    world: &WorldSpec,
    region: Option<&Region>,
    rec: &TrialRecord,
) -> Result<Vec<std::path::PathBuf>, LabError> {
    let stem = crate::lab::file_stem(label);
    let path = dir.join(format!("path-{stem}.png"));
    path_plot(&path, title, world, region, rec)?;
    let signals = dir.join(format!("signals-{stem}.png"));
    signals_plot(&signals, title, rec)?;
    Ok(vec![path, signals])
}

/// The chart [`draw_path`] draws on: metres on both axes.
pub(crate) type PathChart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

const PATH_MARGINS: (u32, u32, u32) = (70, 50, 50);

fn path_bounds(world: &WorldSpec, region: Option<&Region>, rec: &TrialRecord) -> [f64; 4] {
    let corners: Vec<[f64; 2]> = region
        .map(|r| vec![[r.x_m[0], r.y_m[0]], [r.x_m[1], r.y_m[1]]])
        .unwrap_or_default();
    bounds(
        corners
            .into_iter()
            .chain(world.pegs.iter().map(|p| [p.x_m, p.y_m]))
            .chain(rec.centre_m.iter().copied())
            .chain(rec.start_links_m.iter().copied())
            .chain(rec.end_links_m.iter().copied()),
        0.1,
    )
}

/// The height in pixels a path figure `width` wide needs for equal scales on both axes.
pub(crate) fn path_height(
    width: u32,
    world: &WorldSpec,
    region: Option<&Region>,
    rec: &TrialRecord,
) -> u32 {
    let b = path_bounds(world, region, rec);
    let (left, bottom, top) = PATH_MARGINS;
    let area_w = f64::from(width - left - 20);
    let area_h = (area_w * (b[3] - b[2]) / (b[1] - b[0])).clamp(200.0, 1400.0);
    area_h as u32 + bottom + top
}

/// [`path_plot`]'s drawing on `root` (sized by [`path_height`]); returns the chart so a
/// caller can draw more on it. `path` names the file in errors.
pub(crate) fn draw_path<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    path: &Path,
    title: &str,
    world: &WorldSpec,
    region: Option<&Region>,
    rec: &TrialRecord,
) -> Result<PathChart<'a, 'b>, LabError> {
    let reach = |k: &crate::emu::world::Rock| {
        k.points_m
            .iter()
            .map(|q| q[0].hypot(q[1]))
            .fold(0.0, f64::max)
    };
    // Equal scales on both axes: the plot area's aspect follows the data's.
    let b = path_bounds(world, region, rec);
    let (left, bottom, _) = PATH_MARGINS;
    let err = plot_err(path);
    root.fill(&WHITE).map_err(&err)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 22))
        .margin_right(20)
        .x_label_area_size(bottom)
        .y_label_area_size(left)
        .build_cartesian_2d(b[0]..b[1], b[2]..b[3])
        .map_err(&err)?;
    chart
        .configure_mesh()
        .x_desc("x, m")
        .y_desc("y, m")
        .light_line_style(WHITE.mix(0.0))
        .label_style((FONT, 14))
        .draw()
        .map_err(&err)?;
    if let Some(r) = region {
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(r.x_m[0], r.y_m[0]), (r.x_m[1], r.y_m[1])],
                BLACK.mix(0.4).stroke_width(1),
            )))
            .map_err(&err)?;
    }
    let px_per_m = {
        let (a, c) = (
            chart.backend_coord(&(0.0, 0.0)),
            chart.backend_coord(&(1.0, 0.0)),
        );
        f64::from(c.0 - a.0)
    };
    chart
        .draw_series(world.pegs.iter().map(|p| {
            let radius = (p.diameter_m / 2.0 * px_per_m).round().max(2.0) as i32;
            Circle::new((p.x_m, p.y_m), radius, BLACK.mix(0.6).filled())
        }))
        .map_err(&err)?;
    chart
        .draw_series(world.rocks.iter().map(|k| {
            let radius = (reach(k) * px_per_m).round().max(2.0) as i32;
            Circle::new(
                (k.center_m[0], k.center_m[1]),
                radius,
                BLACK.mix(0.25).filled(),
            )
        }))
        .map_err(&err)?;
    let xy = |v: &[[f64; 2]]| v.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>();
    let half = (MetricsConfig::for_wave(rec.temporal_freq_rad_s).smooth_s / rec.sample_dt_s / 2.0)
        .round() as usize;
    let smooth = moving_average(&rec.centre_m, half);
    let series = [
        (
            xy(&rec.start_links_m),
            GREEN.stroke_width(5),
            "body at start",
        ),
        (xy(&rec.end_links_m), RED.stroke_width(5), "body at end"),
        (xy(&rec.centre_m), BLUE.mix(0.35).stroke_width(1), "centre"),
        (xy(&smooth), BLUE.stroke_width(2), "centre, smoothed"),
    ];
    for (points, style, label) in series {
        let legend = style;
        chart
            .draw_series(LineSeries::new(points, style))
            .map_err(&err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], legend));
    }
    // The heads: a dot on the first link of each pose.
    for (links, colour) in [(&rec.start_links_m, GREEN), (&rec.end_links_m, RED)] {
        if let Some(h) = links.first() {
            chart
                .draw_series(std::iter::once(Circle::new(
                    (h[0], h[1]),
                    6,
                    colour.filled(),
                )))
                .map_err(&err)?;
        }
    }
    draw_legend(&mut chart, path)?;
    Ok(chart)
}

/// The path figure's legend (lower left), over whatever the chart holds so far: a
/// caller that adds labelled series draws it again.
pub(crate) fn draw_legend<'a, 'b>(
    chart: &mut PathChart<'a, 'b>,
    path: &Path,
) -> Result<(), LabError>
where
    'b: 'a,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT, 14))
        .draw()
        .map_err(plot_err(path))
}

/// The controller's signals over the trial, one panel per signal (at most
/// [`MAX_SIGNAL_PANELS`]).
pub fn signals_plot(path: &Path, title: &str, rec: &TrialRecord) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let shown = rec.signals.len().min(MAX_SIGNAL_PANELS);
    let (width, panel_h, head_h) = (1000u32, 170u32, 50u32);
    let height = head_h + panel_h * shown.max(1) as u32;
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let caption = if rec.signals.len() > shown {
        format!(
            "{title}: signals over t, s (first {shown} of {})",
            rec.signals.len()
        )
    } else {
        format!("{title}: signals over t, s")
    };
    let root = root.titled(&caption, (FONT, 22)).map_err(&err)?;
    if shown == 0 {
        root.draw(&Text::new(
            "this controller reports no shape signals",
            (40, 60),
            (FONT, 18).into_font(),
        ))
        .map_err(&err)?;
        return root.present().map_err(&err);
    }
    let t_end = (rec.centre_m.len().saturating_sub(1) as f64 * rec.sample_dt_s).max(1e-3);
    for (i, panel) in root.split_evenly((shown, 1)).into_iter().enumerate() {
        signal_panel(
            &panel,
            &rec.signal_names[i],
            &rec.signals[i],
            rec.sample_dt_s,
            t_end,
        )
        .map_err(&err)?;
    }
    root.present().map_err(&err)
}

type AreaResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

fn signal_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    name: &str,
    values: &[f64],
    dt_s: f64,
    t_end_s: f64,
) -> AreaResult {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = ((hi - lo) * 0.08).max(1e-6 * (1.0 + lo.abs()));
    let mut chart = ChartBuilder::on(area)
        .margin(6)
        .x_label_area_size(26)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end_s, (lo - pad)..(hi + pad))?;
    chart
        .configure_mesh()
        .label_style((FONT, 12))
        .y_labels(5)
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    chart.draw_series(LineSeries::new(
        values
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(k, &v)| (k as f64 * dt_s, v)),
        BLUE.stroke_width(2),
    ))?;
    // The name inside the panel, top left.
    chart.draw_series(std::iter::once(
        EmptyElement::at((0.0, hi + pad))
            + Text::new(name.to_owned(), (8, 4), (FONT, 14).into_font()),
    ))?;
    Ok(())
}

#[cfg(test)]
#[path = "plots_tests.rs"]
pub(crate) mod tests;
