//! One controller on one world through the daemon's loop (the lab's trial), printing what
//! it asks of the actuators (`lab::strain`: guard-limited cycles, joint speeds, time at
//! the torque limit) and the range of chosen controller signals in every 2 s: the data
//! behind docs/measurements/sidewinding.md, "Chatter among pegs" (issue 25).
//!     cargo run --release --example chatter_diag -- SCENARIO.toml START GAIT CONTROLLER [SECONDS]
//! CONTROLLER: a name (`ac_sfc`) or a variant `LABEL=JSON`. Environment: SIGNALS
//! (comma-separated signal names, default the amplitude and spatial frequency), HZ (the
//! sample rate, 200), RECORD (an MCAP file to write: every cycle, `/joints` and more).
use snaked::gait::GaitKind;
use snaked::lab::compared::LabController;
use snaked::lab::experiment::Goal;
use snaked::lab::trial::{TrialConfig, TrialRecording, run_trial};

struct Never;
impl Goal for Never {
    fn reached(&self, _: &dyn snaked::emu::Plant) -> bool {
        false
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 5 {
        eprintln!("usage: chatter_diag SCENARIO START GAIT CONTROLLER [SECONDS]");
        std::process::exit(2);
    }
    let sc = snaked::emu::world::scenario::WorldScenario::load(std::path::Path::new(&a[1]))
        .expect("scenario");
    let start: u64 = a[2].parse().expect("start");
    let gait: GaitKind =
        serde_json::from_value(serde_json::Value::String(a[3].clone())).expect("gait name");
    let ctl = if a[4].contains('=') {
        LabController::variant_on(gait, &a[4], "anti_compliant_sidewinding")
    } else {
        LabController::named(gait, &a[4])
    }
    .expect("controller");
    let secs: f64 = a.get(5).map_or(30.0, |s| s.parse().expect("seconds"));
    let hz: f64 = std::env::var("HZ")
        .ok()
        .map_or(200.0, |v| v.parse().unwrap());
    let config = TrialConfig {
        limit_s: secs,
        sample_hz: hz,
        ..TrialConfig::default()
    };
    let world = sc.generate_trial(config.modules, start).expect("world");
    let recording = std::env::var("RECORD").ok().map(|path| TrialRecording {
        path: path.into(),
        world: &world,
        metadata: Vec::new(),
    });
    let rec = run_trial(&ctl, &world, &Never, 7, &config, recording).expect("trial");
    let s = &rec.strain;
    println!(
        "{}: guard-limited {:.1} % of cycles, peak joint speed {:.1} rad/s, mean {:.2}, above 3.46 rad/s {:.2} %, at the torque limit {:.2} %",
        ctl.label,
        s.guard_limited_pct(),
        s.peak_joint_speed_rad_s,
        s.mean_joint_speed_rad_s(),
        s.fast_pct(),
        s.torque_limit_pct()
    );
    let c0 = rec.centre_m[0];
    let c1 = *rec.centre_m.last().unwrap();
    println!(
        "centre moved ({:.3}, {:.3}) m in {:.1} s",
        c1[0] - c0[0],
        c1[1] - c0[1],
        rec.seconds
    );
    let wanted =
        std::env::var("SIGNALS").unwrap_or_else(|_| "amplitude_mean_rad,spatial_freq_rad".into());
    let per = (2.0 / rec.sample_dt_s).round() as usize;
    for name in wanted.split(',') {
        let Some(k) = rec.signal_names.iter().position(|n| n == name) else {
            println!("no signal {name}; have {:?}", rec.signal_names);
            continue;
        };
        let series = &rec.signals[k];
        let ranges: Vec<String> = series
            .chunks(per)
            .map(|c| {
                let (lo, hi) = c
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                        (l.min(v), h.max(v))
                    });
                format!("{lo:.2}..{hi:.2}")
            })
            .collect();
        println!("{name} per 2 s: {}", ranges.join(" "));
    }
}
