//! Scratch: run one sidewinding trial (layout seed, start, repeat) and plot it.
use snaked::emu::world::scenario::WorldScenario;
use snaked::gait::GaitKind;
use snaked::lab::board::Layout;
use snaked::lab::controllers::LabController;
use snaked::lab::experiment::ExperimentModule;
use snaked::lab::runner::noise_seed;
use snaked::lab::sidewinding::{SIDEWINDING_PEGS_TOML, SidewindingPegs, metrics, plots};
use snaked::lab::trial::{TrialConfig, run_trial};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    // swdiag SCENARIO|- SEED START REPEAT CONTROLLER|LABEL=JSON OUTPREFIX [SECONDS]
    let base = if a[1] == "-" {
        WorldScenario::parse(SIDEWINDING_PEGS_TOML).unwrap()
    } else {
        WorldScenario::load(std::path::Path::new(&a[1])).unwrap()
    };
    let seed: u64 = a[2].parse().unwrap();
    let start: usize = a[3].parse().unwrap();
    let repeat: usize = a[4].parse().unwrap();
    let c = if a[5].contains('=') {
        LabController::variant_on(GaitKind::Sidewinding, &a[5], "ac_sfc").unwrap()
    } else {
        LabController::named(GaitKind::Sidewinding, &a[5]).unwrap()
    };
    let out = &a[6];
    let secs: f64 = a.get(7).map(|s| s.parse().unwrap()).unwrap_or(90.0);
    let layout = Layout::seeded(&base, seed);
    let m = SidewindingPegs;
    let (world, fence) = m.world(&layout, TrialConfig::default().modules, start as u64).unwrap();
    let trial = TrialConfig { limit_s: secs, ..TrialConfig::default() };
    let ns = noise_seed(layout.seed(), start, repeat);
    let rec = run_trial(&c, &world, &fence, ns, &trial, None).unwrap();
    let met = metrics::sidewinding_metrics(&fence, &rec, 1.0);
    println!("{met:?}");
    let title = format!("{} seed{seed} start {start} rep {repeat}", c.label);
    plots::trial_plot(std::path::Path::new(&format!("{out}-trial.png")), &title, &world, &rec, 1.0).unwrap();
    snaked::lab::plots::signals_plot(std::path::Path::new(&format!("{out}-signals.png")), &title, &rec).unwrap();
}
