//! The sidewinding experiment's figures (thesis Fig. 4.14–4.16):
//! - [`trial_plot`]: a trial's path over the array with the true and the estimated
//!   heading drawn along it, the headings over time against the one steered to, and β;
//! - [`metrics_plot`]: per controller the failed attempts, the openings passed before
//!   entering one and the time to reverse beyond the array, every trial a dot, the mean
//!   a bar with ± one sd.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::SidewindingPegs;
use super::metrics::{HeadingTraces, summarise};
use crate::emu::world::WorldSpec;
use crate::lab::LabError;
use crate::lab::metrics::mean_sd_median;
use crate::lab::plots::{FONT, draw_path, path_height, plot_err, register_fonts};
use crate::lab::runner::TrialResult;
use crate::lab::trial::TrialRecord;

/// Heading arrows along the path, one every this long, s.
const ARROW_EVERY_S: f64 = 5.0;
/// Their length, m.
const ARROW_M: f64 = 0.15;
const TRUE_COLOUR: RGBColor = RGBColor(0, 0, 0);
const ESTIMATE_COLOUR: RGBColor = RGBColor(230, 120, 0);
const TARGET_COLOUR: RGBColor = RGBColor(0, 150, 60);

/// A trial: its path with heading arrows (true black, estimated orange) over the array,
/// then its headings over time (true, estimated, and the nominal for the controller's
/// well, all in the true world frame) and β over time with its wells.
pub fn trial_plot(
    path: &Path,
    title: &str,
    world: &WorldSpec,
    rec: &TrialRecord,
    heading_filter_s: f64,
) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let width = 1100u32;
    let top_h = path_height(width, world, None, rec);
    let panel_h = 230u32;
    let root = BitMapBackend::new(path, (width, top_h + 2 * panel_h)).into_drawing_area();
    let (top, bottom) = root.split_vertically(top_h);
    let h = HeadingTraces::of(rec, heading_filter_s);
    {
        let mut chart = draw_path(&top, path, title, world, None, rec)?;
        let every = ((ARROW_EVERY_S / rec.sample_dt_s).round() as usize).max(1);
        for (k, c) in rec.centre_m.iter().enumerate().step_by(every) {
            for (heading, colour) in [(h.truth[k], TRUE_COLOUR), (h.estimate[k], ESTIMATE_COLOUR)] {
                if !heading.is_finite() {
                    continue;
                }
                let tip = (
                    c[0] + ARROW_M * heading.cos(),
                    c[1] + ARROW_M * heading.sin(),
                );
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        [(c[0], c[1]), tip],
                        colour.stroke_width(2),
                    )))
                    .map_err(&err)?;
                chart
                    .draw_series(std::iter::once(Circle::new(tip, 3, colour.filled())))
                    .map_err(&err)?;
            }
        }
        let note = "arrows every 5 s: true heading (black), estimated (orange)";
        top.draw(&Text::new(
            note,
            (80, top_h as i32 - 22),
            (FONT, 14).into_font(),
        ))
        .map_err(&err)?;
    }
    bottom.fill(&WHITE).map_err(&err)?;
    let panels = bottom.split_evenly((2, 1));
    let t_end = (rec.centre_m.len().saturating_sub(1) as f64 * rec.sample_dt_s).max(1e-3);
    let dt = rec.sample_dt_s;
    time_panel(
        &panels[0],
        "heading, rad",
        t_end,
        -PI..PI,
        &[
            (&h.truth, TRUE_COLOUR, "true"),
            (&h.estimate, ESTIMATE_COLOUR, "estimated"),
            (
                &h.target,
                TARGET_COLOUR,
                "nominal for the controller's well",
            ),
        ],
        dt,
        &[],
    )
    .map_err(&err)?;
    // β in [−π/2, 3π/2): both wells in view, a wobble about 0 not wrapped to 2π.
    let beta: Vec<f64> = h
        .beta
        .iter()
        .map(|b| (b + FRAC_PI_2).rem_euclid(2.0 * PI) - FRAC_PI_2)
        .collect();
    time_panel(
        &panels[1],
        "β, rad",
        t_end,
        -FRAC_PI_2..(1.5 * PI),
        &[(&beta, BLUE, "β")],
        dt,
        &[0.0, PI],
    )
    .map_err(&err)?;
    root.present().map_err(&err)
}

type AreaResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// One panel over t: each series (NaN breaks it; angles wrap, so a jump of more than π
/// breaks it too) and dashed horizontal `marks`.
fn time_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    name: &str,
    t_end_s: f64,
    y: std::ops::Range<f64>,
    series: &[(&Vec<f64>, RGBColor, &str)],
    dt_s: f64,
    marks: &[f64],
) -> AreaResult {
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_end_s, y.clone())?;
    chart
        .configure_mesh()
        .x_desc("t, s")
        .y_desc(name)
        .label_style((FONT, 12))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    for &m in marks {
        chart.draw_series(DashedLineSeries::new(
            [(0.0, m), (t_end_s, m)],
            6,
            4,
            BLACK.mix(0.4).stroke_width(1),
        ))?;
    }
    for &(values, colour, label) in series {
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        let mut last = f64::NAN;
        for (k, &v) in values.iter().enumerate() {
            let fresh = !v.is_finite() || (last.is_finite() && (v - last).abs() > PI);
            if fresh && !runs.last().is_some_and(Vec::is_empty) {
                runs.push(Vec::new());
            }
            if v.is_finite() {
                runs.last_mut()
                    .expect("one run at least")
                    .push((k as f64 * dt_s, v));
            }
            last = v;
        }
        let style = colour.stroke_width(2);
        let mut first = true;
        for run in runs.into_iter().filter(|r| !r.is_empty()) {
            let drawn = chart.draw_series(LineSeries::new(run, style))?;
            if std::mem::take(&mut first) {
                drawn
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT, 12))
        .draw()?;
    Ok(())
}

/// One metric per panel, per controller (the thesis's Fig. 4.15 and 4.16): every
/// trial's value as a dot (NaN trials left out), the mean as a bar, ± one sd.
pub fn metrics_plot(path: &Path, results: &[TrialResult<SidewindingPegs>]) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let sums = summarise(results);
    let names: Vec<&str> = sums.iter().map(|s| s.controller.as_str()).collect();
    let n = names.len().max(1);
    let width = (3 * (120 * n as u32 + 120)).max(900);
    let root = BitMapBackend::new(path, (width, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let root = root
        .titled(
            "Sidewinding through the peg array, per controller",
            (FONT, 22),
        )
        .map_err(&err)?;
    type Metric = fn(&super::metrics::SidewindingMetrics) -> f64;
    let panels: [(&str, Metric); 3] = [
        ("failed attempt (1) or through (0)", |m| {
            if m.failed() { 1.0 } else { 0.0 }
        }),
        ("openings passed before entering", |m| {
            m.openings_passed.map_or(f64::NAN, |o| o as f64)
        }),
        ("time to reverse beyond the array, s", |m| {
            m.reverse_beyond_s
        }),
    ];
    for (area, (label, f)) in root.split_evenly((1, 3)).iter().zip(panels) {
        let per: Vec<Vec<f64>> = names
            .iter()
            .map(|c| {
                results
                    .iter()
                    .filter(|r| r.controller == *c)
                    .map(|r| f(&r.metrics))
                    .filter(|v| v.is_finite())
                    .collect()
            })
            .collect();
        dots_panel(area, label, &names, &per).map_err(&err)?;
    }
    root.present().map_err(&err)
}

fn dots_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    label: &str,
    names: &[&str],
    per: &[Vec<f64>],
) -> AreaResult {
    let n = names.len().max(1);
    let hi = per.iter().flatten().copied().fold(1.0_f64, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(50)
        .caption(label, (FONT, 15))
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..hi)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .label_style((FONT, 12))
        .draw()?;
    for (i, (name, v)) in names.iter().zip(per).enumerate() {
        let x = i as f64;
        let colour = Palette99::pick(i).to_rgba();
        if let Some((m, sd, _)) = mean_sd_median(v) {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x - 0.3, 0.0), (x + 0.3, m)],
                colour.mix(0.35).filled(),
            )))?;
            let (y0, y1) = ((m - sd).max(0.0), (m + sd).min(hi));
            chart.draw_series([
                PathElement::new([(x, y0), (x, y1)], BLACK.stroke_width(2)),
                PathElement::new([(x - 0.1, y0), (x + 0.1, y0)], BLACK.stroke_width(2)),
                PathElement::new([(x - 0.1, y1), (x + 0.1, y1)], BLACK.stroke_width(2)),
            ])?;
        }
        let spread = (v.len().max(2) - 1) as f64;
        chart.draw_series(v.iter().enumerate().map(|(k, &y)| {
            let jitter = -0.22 + 0.44 * k as f64 / spread;
            Circle::new((x + jitter, y), 3, colour.filled())
        }))?;
        // The label in the area's own pixels.
        let (px, py) = chart.backend_coord(&(x, 0.0));
        let (bx, by) = area.get_base_pixel();
        let (px, py) = (px - bx, py - by);
        let style = TextStyle::from((FONT, 13).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        area.draw(&Text::new(
            format!("{name} (n {})", v.len()),
            (px, py + 8),
            style,
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::Peg;

    fn record() -> TrialRecord {
        let n = 300;
        let body = |k: usize| -> Vec<[f64; 2]> {
            (0..10)
                .map(|j| [0.01 * k as f64 - 0.06 * j as f64, -0.002 * k as f64])
                .collect()
        };
        let links_m: Vec<[f64; 2]> = (0..n).flat_map(body).collect();
        let centre_m = (0..n).map(|k| body(k)[5]).collect();
        let sig = |f: &dyn Fn(usize) -> f64| (0..n).map(f).collect::<Vec<_>>();
        TrialRecord {
            links_m,
            sample_dt_s: 0.1,
            start_links_m: body(0),
            end_links_m: body(n - 1),
            signal_names: ["beta_rad", "heading_rad", "heading_nominal_rad"]
                .map(String::from)
                .to_vec(),
            signals: vec![
                sig(&|k| {
                    if k < 100 {
                        0.0
                    } else {
                        PI.min(0.03 * (k - 100) as f64)
                    }
                }),
                sig(&|k| if k < 10 { f64::NAN } else { 0.002 * k as f64 }),
                sig(&|_| 0.0),
            ],
            centre_m,
            seconds: 30.0,
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
    fn the_figures_are_pngs() {
        let dir = tempfile::tempdir().unwrap();
        let world = WorldSpec {
            pegs: vec![Peg {
                x_m: 1.0,
                y_m: -0.4,
                diameter_m: 0.05,
                height_m: 0.15,
            }],
            ..WorldSpec::default()
        };
        let p = dir.path().join("trial.png");
        trial_plot(&p, "a trial", &world, &record(), 1.0).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert!(bytes.len() > 10_000 && bytes.starts_with(b"\x89PNG"));
        // No trials at all still draws the axes.
        let p = dir.path().join("metrics.png");
        metrics_plot(&p, &[]).unwrap();
        assert!(std::fs::read(&p).unwrap().starts_with(b"\x89PNG"));
    }
}
