//! What a body section's mean amplitude does among obstacles while the body progresses
//! and while it is held (issue 26, point 2): runs a directional-compliance controller
//! (default `dc_nc`, calibrated on open ground as the lab does) on seeded layouts of a
//! displacement scenario and, per nominal gait cycle and body section, prints the
//! absition's rate (`Ā − A₀ − c`, rad) beside the ground truth: how far that section's
//! links moved over the cycle (body lengths per cycle, unsigned and along the body's
//! heading at the cycle's start). One line per class of cycle (held / slow / progressing)
//! with the rate's quartiles; with `CSV=path`, every (trial, cycle, section) row.
//!     cargo run --release --example dc_baseline_diag -- SCENARIO.toml SEED_BASE LAYOUTS STARTS
//! Environment: CONTROLLER (dc_nc), NOMINAL (the gait's JSON, default
//! `{"amplitude_lat_rad":1.2,"spatial_freq_rad":6.283185307179586}`), SECS (120),
//! THREADS (2), PLANE (`lat` or `dor`), ROCKS (any value: the 3-D rock pile's
//! `dc3d_nc` by default and 16 modules' odd/even layout as the lab's), FULL_TIME (any
//! value: run every trial its full time; by default a trial ends, as the lab's do, when
//! the body's centre leaves the obstacles' bounding box).
use std::io::Write;

use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::GaitKind;
use snaked::lab::calibration::calibrate;
use snaked::lab::compared::LabController;
use snaked::lab::displacement::FieldEdge;
use snaked::lab::layout::Layout;
use snaked::lab::layout::noise_seed;
use snaked::lab::trial::{TrialConfig, TrialRecord, nominal_gaits, run_trial};
use snaked::module::MODULE_LENGTH_M;

const SECTIONS: [&str; 3] = ["head", "mid", "tail"];

/// One (trial, cycle, section) row.
struct Row {
    trial: String,
    cycle: usize,
    section: usize,
    rate: f64,
    moved_bl: f64,
    forward_bl: f64,
    body_bl: f64,
}

fn rows(trial: &str, rec: &TrialRecord, body_m: f64) -> Vec<Row> {
    let n_links = rec.start_links_m.len();
    let samples = rec.centre_m.len();
    let period = std::f64::consts::TAU / rec.temporal_freq_rad_s.abs();
    let per = (period / rec.sample_dt_s).round() as usize;
    let series: Vec<Option<&Vec<f64>>> = SECTIONS
        .iter()
        .map(|s| {
            let plane = std::env::var("PLANE").unwrap_or("lat".into());
            let name = format!("absition_{plane}_{s}");
            let k = rec.signal_names.iter().position(|n| *n == name)?;
            Some(&rec.signals[k])
        })
        .collect();
    let mut out = Vec::new();
    let centroid = |k: usize, sec: usize| {
        let links = rec.links_at(k);
        let (a, b) = (sec * n_links / 3, (sec + 1) * n_links / 3);
        let m = (b - a) as f64;
        let s = links[a..b]
            .iter()
            .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        [s[0] / m, s[1] / m]
    };
    let mut cycle = 0;
    let mut k0 = 0;
    while k0 + per < samples {
        let k1 = k0 + per;
        let links = rec.links_at(k0);
        let (h, t) = (links[0], links[n_links - 1]);
        let d = [h[0] - t[0], h[1] - t[1]];
        let l = d[0].hypot(d[1]).max(1e-9);
        let heading = [d[0] / l, d[1] / l];
        let (c0, c1) = (rec.centre_m[k0], rec.centre_m[k1]);
        let body_bl = (c1[0] - c0[0]).hypot(c1[1] - c0[1]) / body_m;
        for (sec, s) in series.iter().enumerate() {
            let Some(s) = s else { continue };
            let (s0, s1) = (s[k0], s[k1]);
            if !(s0.is_finite() && s1.is_finite()) {
                continue;
            }
            let (p0, p1) = (centroid(k0, sec), centroid(k1, sec));
            let dd = [p1[0] - p0[0], p1[1] - p0[1]];
            out.push(Row {
                trial: trial.to_owned(),
                cycle,
                section: sec,
                rate: (s1 - s0) / ((k1 - k0) as f64 * rec.sample_dt_s),
                moved_bl: dd[0].hypot(dd[1]) / body_m,
                forward_bl: (dd[0] * heading[0] + dd[1] * heading[1]) / body_m,
                body_bl,
            });
        }
        cycle += 1;
        k0 = k1;
    }
    out
}

fn quartiles(mut v: Vec<f64>) -> String {
    if v.is_empty() {
        return "-".into();
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    format!(
        "n {:4}  mean {:+.3}  q25 {:+.3}  median {:+.3}  q75 {:+.3}",
        v.len(),
        mean,
        q(0.25),
        q(0.5),
        q(0.75)
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let file = args
        .get(1)
        .cloned()
        .unwrap_or("docs/lab-results/peg-array-sleeve/peg-array-sleeve.toml".into());
    let arg = |i: usize, d: u64| args.get(i).and_then(|v| v.parse().ok()).unwrap_or(d);
    let (seed_base, layouts, starts) = (arg(2, 500), arg(3, 10), arg(4, 2));
    let rocks = std::env::var("ROCKS").is_ok();
    let full_time = std::env::var("FULL_TIME").is_ok();
    let name =
        std::env::var("CONTROLLER").unwrap_or(if rocks { "dc3d_nc" } else { "dc_nc" }.into());
    let nominal = std::env::var("NOMINAL")
        .unwrap_or(r#"{"amplitude_lat_rad":1.2,"spatial_freq_rad":6.283185307179586}"#.into());
    let secs: f64 = std::env::var("SECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(120.0);
    let threads: usize = std::env::var("THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let base = WorldScenario::load(std::path::Path::new(&file)).expect("scenario");
    let config = TrialConfig {
        modules: 16,
        limit_s: secs,
        gaits: nominal_gaits(GaitKind::Slithering, Some(&nominal)).expect("nominal"),
        ..TrialConfig::default()
    };
    let layouts: Vec<Layout> = (0..layouts)
        .map(|k| Layout::seeded(&base, seed_base + k))
        .collect();
    let plain = if name.contains('=') {
        LabController::variant_on(
            GaitKind::Slithering,
            &name,
            if rocks { "dc3d_nc" } else { "dc_nc" },
        )
        .expect("variant")
    } else {
        LabController::named(GaitKind::Slithering, &name).expect("controller")
    };
    let ground = layouts[0].scenario.generate_trial(16, 0).expect("world");
    let controller = calibrate(&plain, &ground, &config)
        .expect("calibration")
        .map_or(plain, |c| {
            eprintln!("offsets {}", c.offsets);
            c.controller
        });
    let body_m = 16.0 * MODULE_LENGTH_M;
    let jobs: Vec<(usize, u64)> = (0..layouts.len())
        .flat_map(|l| (0..starts).map(move |s| (l, s)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let all: Vec<Row> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&(l, start)) = jobs.get(i) else {
                            break;
                        };
                        let layout = &layouts[l];
                        let world = layout.scenario.generate_trial(16, start).expect("world");
                        let seed = noise_seed(layout.identity, start as usize, 0);
                        // As the lab: a trial ends when the body's centre leaves the
                        // obstacles (open ground after them would count as progressing).
                        let edge = if full_time {
                            FieldEdge::FULL_TIME
                        } else {
                            FieldEdge::of(&world)
                        };
                        let rec = run_trial(&controller, &world, &edge, seed, &config, None)
                            .expect("trial");
                        let label = format!("{}-s{start}", layout.name);
                        eprintln!("{label} done");
                        mine.extend(rows(&label, &rec, body_m));
                    }
                    mine
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("worker"))
            .collect()
    });
    if let Ok(path) = std::env::var("CSV") {
        let mut f = std::fs::File::create(path).expect("csv");
        writeln!(
            f,
            "trial,cycle,section,rate_rad,moved_bl,forward_bl,body_bl"
        )
        .unwrap();
        for r in &all {
            writeln!(
                f,
                "{},{},{},{:.5},{:.5},{:.5},{:.5}",
                r.trial, r.cycle, SECTIONS[r.section], r.rate, r.moved_bl, r.forward_bl, r.body_bl
            )
            .unwrap();
        }
    }
    println!(
        "per trial (slowest first) and section: mean Ā − A₀ − c, rad / mean |change of it from one cycle to the next|, rad / BL per cycle moved"
    );
    let mut trials: Vec<&str> = all.iter().map(|r| r.trial.as_str()).collect();
    trials.dedup();
    let moved = |t: &str| {
        let v: Vec<f64> = all
            .iter()
            .filter(|r| r.trial == t)
            .map(|r| r.moved_bl)
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    trials.sort_by(|a, b| moved(a).total_cmp(&moved(b)));
    for t in trials {
        let mut line = format!("{t:14}");
        for (sec, s) in SECTIONS.iter().enumerate() {
            let v: Vec<&Row> = all
                .iter()
                .filter(|r| r.trial == t && r.section == sec && r.cycle > 0)
                .collect();
            let n = v.len().max(1) as f64;
            let rate = v.iter().map(|r| r.rate).sum::<f64>() / n;
            let change = v
                .windows(2)
                .map(|w| (w[1].rate - w[0].rate).abs())
                .sum::<f64>()
                / (n - 1.0).max(1.0);
            let mv = v.iter().map(|r| r.moved_bl).sum::<f64>() / n;
            line += &format!("  {s} {rate:+.2} / {change:.3} / {mv:.3}");
        }
        println!("{line}");
    }
    println!("absition rate Ā − A₀ − c per cycle, rad, by what the section did over the cycle:");
    type Class = (&'static str, fn(&Row) -> bool);
    let classes: [Class; 3] = [
        ("held (< 0.01 BL/cycle)", |r| r.moved_bl < 0.01),
        ("slow (0.01-0.03)", |r| (0.01..0.03).contains(&r.moved_bl)),
        ("progressing (>= 0.03)", |r| r.moved_bl >= 0.03),
    ];
    for (sec, s) in SECTIONS.iter().enumerate() {
        for (label, f) in classes {
            let v: Vec<f64> = all
                .iter()
                .filter(|r| r.section == sec && r.cycle > 0 && f(r))
                .map(|r| r.rate)
                .collect();
            println!("{s:4} {label:24} {}", quartiles(v));
        }
    }
}
