//! One pole-experiment trial through the daemon's loop (`snake-lab pole`'s), printed
//! every second: the middle link's distance from the pole's axis, the head, the
//! getting-on stage, ρ, the grip, the centre's height, the links touching the pole
//! (within 1 cm of its skin) and the highest link.
//!     cargo run --release --example pole_trial -- [POLE] [CONTROLLER] [START] [SECONDS] [JSON]
//! POLE a named pole or `seedN`; JSON a configuration over CONTROLLER. Environment:
//! WT (ωT), ROLL (the start's roll, rad), LEAD (the lead-in, s), DETAIL (every 0.25 s
//! to 8 s), LINKS (every third link's position).
use snaked::gait::GaitKind;
use snaked::lab::compared::LabController;
use snaked::lab::experiment::Experiment;
use snaked::lab::layout::Layout;
use snaked::lab::layout::noise_seed;
use snaked::lab::pole::{PoleClimb, poles};
use snaked::lab::trial::{TrialConfig, run_trial};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let pole = a.get(1).map_or("step-up", |s| s.as_str());
    let name = a.get(2).map_or("windowed_adaptive", |s| s.as_str());
    let start: u64 = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    let secs: f64 = a.get(4).and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let mut designs = poles::named_set();
    if let Some(seed) = pole.strip_prefix("seed") {
        designs.push(poles::seeded(seed.parse().unwrap()));
    }
    let module = PoleClimb {
        designs,
        lead_in_s: std::env::var("LEAD")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1.0),
        ..PoleClimb::default()
    };
    let layouts = module.layouts().unwrap();
    let layout: &Layout = layouts.iter().find(|l| l.name == pole).unwrap();
    let (mut world, goal) = module.world(layout, 18, start).unwrap();
    if let Some(r) = std::env::var("ROLL").ok().and_then(|v| v.parse().ok()) {
        world.start.roll_rad = r;
    }
    let c = match a.get(5) {
        Some(json) => {
            LabController::variant_on(GaitKind::RollingHelix, &format!("v={json}"), name).unwrap()
        }
        None => LabController::named(GaitKind::RollingHelix, name).unwrap(),
    };
    let base = TrialConfig {
        limit_s: secs,
        ..TrialConfig::default()
    };
    let mut config = module.trial_config(&base, &goal);
    if let Some(wt) = std::env::var("WT").ok().and_then(|v| v.parse().ok()) {
        config
            .gaits
            .get_mut(GaitKind::RollingHelix)
            .temporal_freq_rad_s = wt;
    }
    let rec = run_trial(
        &c,
        &world,
        &goal,
        noise_seed(layout.identity, start as usize, 0),
        &config,
        None,
    )
    .unwrap();
    let sig = |n: &str| {
        rec.signal_names
            .iter()
            .position(|s| s == n)
            .map(|i| &rec.signals[i])
    };
    let (stage, rho, grip) = (sig("getting_on"), sig("radius_scale"), sig("grip_nm"));
    println!(
        "start {:?} roll {:.2} yaw {:.2}; nominal r {:.3}",
        world.start.head_m, world.start.roll_rad, world.start.yaw_rad, goal.nominal_radius_m
    );
    let every = (1.0 / rec.sample_dt_s).round() as usize;
    let samples = rec.heights_m.len() / rec.start_links_m.len();
    let detail = std::env::var("DETAIL").is_ok();
    let every = if detail { every / 4 } else { every };
    for k in (0..samples).step_by(every) {
        if detail && k as f64 * rec.sample_dt_s > 8.0 {
            break;
        }
        let links = rec.links_at(k);
        let h = rec.heights_at(k);
        let touching = links
            .iter()
            .zip(h)
            .filter(|(p, z)| {
                let r = 0.5 * poles::diameter_at(&goal.sections, **z) + 0.025 + 0.01;
                p[0].hypot(p[1]) < r
            })
            .count();
        let top = h.iter().copied().fold(0.0, f64::max);
        let at = |s: Option<&Vec<f64>>| s.map_or(f64::NAN, |v| v[k]);
        if std::env::var("LINKS").is_ok() {
            let pts: Vec<String> = links
                .iter()
                .step_by(3)
                .zip(h.iter().step_by(3))
                .map(|(p, z)| format!("({:.2},{:.2},{:.2})", p[0], p[1], z))
                .collect();
            println!("   links {}", pts.join(" "));
        }
        let m = links[links.len() / 2];
        let head = links[0];
        print!(
            "mid r {:.3} head ({:.2},{:.2}) ",
            m[0].hypot(m[1]),
            head[0],
            head[1]
        );
        println!(
            "{:5.1}s stage {:3.0} rho {:5.3} grip {:5.2} z {:5.3} touch {:2} top {:5.3}",
            k as f64 * rec.sample_dt_s,
            at(stage),
            at(rho),
            at(grip),
            rec.centre_height(k),
            touching,
            top
        );
    }
}
