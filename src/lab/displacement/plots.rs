//! The displacement experiments' figures:
//! - [`velocity_plot`]: each controller's velocity per pose (black bars) and over all
//!   trials (red bar, ± one sd), the paper's Fig. 6;
//! - [`absition_plot`]: one trial's mean amplitudes and its body sections' absitions
//!   (head, middle and tail for three) over time, per plane, with the thresholds and
//!   the moments a section switched into PDC or NDC, the paper's Fig. 2 and 5.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::Displacement;
use super::metrics::summarise;
use crate::lab::LabError;
use crate::lab::plots::{FONT, plot_err, register_fonts};
use crate::lab::runner::TrialResult;
use crate::lab::trial::TrialRecord;

/// Velocity per pose and overall, per controller.
pub fn velocity_plot(
    path: &Path,
    title: &str,
    results: &[TrialResult<Displacement>],
) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    let sums = summarise(results);
    let n = sums.len().max(1);
    let hi = sums
        .iter()
        .flat_map(|s| {
            let top = s.velocity.0 + s.velocity.1;
            s.poses
                .iter()
                .map(|p| p.velocity.0)
                .chain(std::iter::once(top))
        })
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max)
        .max(1e-3)
        * 1.15;
    let width = (260 * n as u32 + 160).max(600);
    let root = BitMapBackend::new(path, (width, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..hi)
        .map_err(&err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("velocity, body lengths per minute")
        .label_style((FONT, 14))
        .draw()
        .map_err(&err)?;
    for (i, s) in sums.iter().enumerate() {
        let x = i as f64;
        let poses = s.poses.len().max(1);
        // Pose bars in [x − 0.4, x + 0.15], the overall bar in [x + 0.2, x + 0.4].
        let w = 0.55 / poses as f64;
        chart
            .draw_series(s.poses.iter().enumerate().map(|(k, p)| {
                let x0 = x - 0.4 + k as f64 * w;
                Rectangle::new(
                    [(x0 + 0.1 * w, 0.0), (x0 + 0.9 * w, p.velocity.0.max(0.0))],
                    BLACK.filled(),
                )
            }))
            .map_err(&err)?;
        let (mean, sd, _) = s.velocity;
        let red = RGBColor(200, 30, 30);
        chart
            .draw_series([Rectangle::new(
                [(x + 0.2, 0.0), (x + 0.4, mean.max(0.0))],
                red.filled(),
            )])
            .map_err(&err)?;
        let (y0, y1) = ((mean - sd).max(0.0), (mean + sd).min(hi));
        chart
            .draw_series([
                PathElement::new([(x + 0.3, y0), (x + 0.3, y1)], BLACK.stroke_width(2)),
                PathElement::new([(x + 0.25, y0), (x + 0.35, y0)], BLACK.stroke_width(2)),
                PathElement::new([(x + 0.25, y1), (x + 0.35, y1)], BLACK.stroke_width(2)),
            ])
            .map_err(&err)?;
        let (px, py) = chart.backend_coord(&(x, 0.0));
        let label = format!("{} (sd across poses {:.3})", s.controller, s.pose_sd);
        let style = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(label, (px, py + 10), style))
            .map_err(&err)?;
    }
    root.present().map_err(&err)
}

/// A series of `rec` by name (empty if the controller does not report it).
fn series<'a>(rec: &'a TrialRecord, name: &str) -> &'a [f64] {
    rec.signal_names
        .iter()
        .position(|n| n == name)
        .map_or(&[], |k| &rec.signals[k])
}

/// Whether `rec` has any finite value of `name`.
fn reported(rec: &TrialRecord, name: &str) -> bool {
    series(rec, name).iter().any(|v| v.is_finite())
}

/// Amplitudes and absitions of one trial (see the module docs). Says so in the figure
/// when the controller reports no absitions.
pub fn absition_plot(path: &Path, title: &str, rec: &TrialRecord) -> Result<(), LabError> {
    register_fonts();
    let err = plot_err(path);
    // The sections by name, head first, as the controller reports them
    // (`absition_{plane}_{section}`).
    let sections: Vec<&str> = rec
        .signal_names
        .iter()
        .filter_map(|n| n.strip_prefix("absition_lat_"))
        .collect();
    let planes: Vec<(&str, &str)> = [("lat", "lateral"), ("dor", "dorsal")]
        .into_iter()
        .filter(|(p, _)| {
            sections
                .iter()
                .any(|s| reported(rec, &format!("absition_{p}_{s}")))
        })
        .collect();
    let panels = 1 + planes.len();
    let root = BitMapBackend::new(path, (1100, 60 + 260 * panels as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(&err)?;
    let root = root.titled(title, (FONT, 22)).map_err(&err)?;
    if planes.is_empty() {
        root.draw(&Text::new(
            "this controller reports no absitions",
            (40, 60),
            (FONT, 18).into_font(),
        ))
        .map_err(&err)?;
        return root.present().map_err(&err);
    }
    let dt = rec.sample_dt_s;
    let t_end = (rec.centre_m.len().saturating_sub(1) as f64 * dt).max(1e-3);
    let areas = root.split_evenly((panels, 1));
    let colours = [
        RGBColor(210, 30, 30),
        RGBColor(30, 60, 210),
        RGBColor(20, 150, 40),
        RGBColor(230, 140, 20),
    ];
    // Amplitudes (mean over each plane's joints).
    {
        let names: Vec<String> = planes
            .iter()
            .map(|(p, _)| format!("amplitude_{p}_mean_rad"))
            .collect();
        let lines: Vec<(&str, &[f64], RGBColor)> = names
            .iter()
            .zip([BLUE, RGBColor(120, 60, 160)])
            .map(|(n, c)| (n.as_str(), series(rec, n), c))
            .collect();
        draw_panel(
            &areas[0],
            "mean amplitude, rad",
            &lines,
            &[],
            &[],
            dt,
            t_end,
        )
        .map_err(&err)?;
    }
    for (k, (p, plane)) in planes.iter().enumerate() {
        let names: Vec<String> = sections
            .iter()
            .map(|t| format!("absition_{p}_{t}"))
            .collect();
        let lines: Vec<(&str, &[f64], RGBColor)> = names
            .iter()
            .zip(colours)
            .map(|(n, c)| (n.as_str(), series(rec, n), c))
            .collect();
        let thresholds: Vec<f64> = ["threshold_low_rad_s", "threshold_high_rad_s"]
            .iter()
            .filter_map(|n| series(rec, n).iter().copied().find(|v| v.is_finite()))
            .collect();
        // A switch into PDC (+1) or NDC (−1) of a section.
        let mut switches = Vec::new();
        for t in &sections {
            let modes = series(rec, &format!("mode_{p}_{t}"));
            for (i, w) in modes.windows(2).enumerate() {
                if w[0] == 0.0 && (w[1] == 1.0 || w[1] == -1.0) {
                    switches.push(((i + 1) as f64 * dt, w[1]));
                }
            }
        }
        let order = ["red", "blue", "green", "orange"];
        let key: Vec<String> = sections
            .iter()
            .zip(order)
            .map(|(s, c)| format!("{s} {c}"))
            .collect();
        let label = format!("{plane} absition per section, rad·s ({})", key.join(", "));
        draw_panel(
            &areas[k + 1],
            &label,
            &lines,
            &thresholds,
            &switches,
            dt,
            t_end,
        )
        .map_err(&err)?;
    }
    root.present().map_err(&err)
}

type AreaResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// One panel: `lines` over time, horizontal dash-dot `thresholds`, vertical dotted
/// `switches` (time, +1 PDC green / −1 NDC purple).
fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    label: &str,
    lines: &[(&str, &[f64], RGBColor)],
    thresholds: &[f64],
    switches: &[(f64, f64)],
    dt: f64,
    t_end: f64,
) -> AreaResult {
    let values = lines
        .iter()
        .flat_map(|(_, v, _)| v.iter().copied())
        .chain(thresholds.iter().copied())
        .filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = ((hi - lo) * 0.08).max(1e-6);
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(28)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?;
    chart
        .configure_mesh()
        .label_style((FONT, 12))
        .x_desc("t, s")
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    for &(t, mode) in switches {
        let colour = if mode > 0.0 {
            RGBColor(20, 160, 60)
        } else {
            RGBColor(140, 40, 170)
        };
        let dots = (0..40).map(|k| {
            let y0 = lo - pad + (hi - lo + 2.0 * pad) * k as f64 / 40.0;
            PathElement::new([(t, y0), (t, y0 + (hi - lo + 2.0 * pad) / 90.0)], colour)
        });
        chart.draw_series(dots)?;
    }
    for &y in thresholds {
        let dashes = (0..60).map(|k| {
            let x0 = t_end * k as f64 / 60.0;
            PathElement::new([(x0, y), (x0 + t_end / 100.0, y)], BLACK.stroke_width(2))
        });
        chart.draw_series(dashes)?;
    }
    for (_, values, colour) in lines {
        chart.draw_series(LineSeries::new(
            values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(k, &v)| (k as f64 * dt, v)),
            colour.stroke_width(2),
        ))?;
    }
    chart.draw_series(std::iter::once(
        EmptyElement::at((0.0, hi + pad))
            + Text::new(label.to_owned(), (8, 4), (FONT, 14).into_font()),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> TrialRecord {
        let n = 200;
        let mut names = vec![
            "amplitude_lat_mean_rad".to_string(),
            "threshold_low_rad_s".into(),
            "threshold_high_rad_s".into(),
        ];
        let mut signals = vec![vec![0.7; n], vec![-0.6; n], vec![0.6; n]];
        for t in ["head", "mid", "tail"] {
            names.push(format!("absition_lat_{t}"));
            signals.push((0..n).map(|k| -0.01 * k as f64).collect());
            names.push(format!("mode_lat_{t}"));
            signals.push((0..n).map(|k| if k > 60 { 1.0 } else { 0.0 }).collect());
        }
        TrialRecord {
            links_m: Vec::new(),
            sample_dt_s: 0.05,
            centre_m: vec![[0.0; 2]; n],
            start_links_m: vec![[0.0; 2]; 17],
            end_links_m: vec![[0.0; 2]; 17],
            signal_names: names,
            signals,
            seconds: 10.0,
            success: false,
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
    fn the_figures_are_written() {
        let dir = std::env::temp_dir().join(format!("snaked-dplots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("absition.png");
        absition_plot(&p, "absitions", &record()).unwrap();
        assert!(std::fs::metadata(&p).unwrap().len() > 10_000);
        let mut empty = record();
        empty.signal_names.clear();
        empty.signals.clear();
        absition_plot(&dir.join("none.png"), "none", &empty).unwrap();
        let results: Vec<TrialResult<Displacement>> = (0..4)
            .map(|k| TrialResult {
                controller: if k < 2 { "a" } else { "b" }.into(),
                layout: "seed1".into(),
                start: k % 2,
                repeat: 0,
                metrics: super::super::metrics::displacement_metrics(&record(), 1.0),
                strain: Default::default(),
                stuck: Default::default(),
                odometry: Default::default(),
                position: Default::default(),
                plotted: None,
            })
            .collect();
        let p = dir.join("velocity.png");
        velocity_plot(&p, "velocity", &results).unwrap();
        assert!(std::fs::metadata(&p).unwrap().len() > 5_000);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
