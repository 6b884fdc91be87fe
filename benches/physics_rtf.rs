//! Real-time factor (simulated s per wall s) of the physics plant: 18 modules
//! slithering among 40 pegs, and sidewinding over a pile of convex rocks, each with
//! self-collision off and on (the variants alternate, so a busy machine slows both).
//! Criterion times one 1 ms plant step (RTF = 1 ms / step time); the explicit
//! figures over 5 simulated seconds (median of 3 alternating rounds) are printed first.
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use snaked::emu::Plant;
use snaked::emu::plant::NoiseConfig;
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::{Peg, Rock, StartPose, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, Plane};
use snaked::module::MODULE_LENGTH_M;
use snaked::protocol::Command;

const N: usize = 18;

fn pegs_world() -> WorldSpec {
    // 40 pegs on a jittered 8 x 5 grid around and ahead of the body.
    let mut rng = Pcg64::seed_from_u64(1);
    let mut pegs = Vec::new();
    for i in 0..8 {
        for j in 0..5 {
            pegs.push(Peg {
                x_m: -1.2 + 0.3 * i as f64 + rng.random_range(-0.05..0.05),
                y_m: -0.6 + 0.3 * j as f64 + 0.15 + rng.random_range(-0.05..0.05),
                diameter_m: 0.05,
                height_m: 0.15,
            });
        }
    }
    WorldSpec {
        pegs,
        start: StartPose {
            head_m: [0.0, 0.0, 0.0],
            ..StartPose::default()
        },
        ..WorldSpec::default()
    }
}

fn rocks_world() -> WorldSpec {
    // A dozen convex rocks (random hulls of 12 points, 5-12 cm) under the body.
    let mut rng = Pcg64::seed_from_u64(2);
    let rocks = (0..12)
        .map(|k| {
            let size = rng.random_range(0.05..0.12);
            Rock {
                center_m: [-0.1 * k as f64, rng.random_range(-0.2..0.2), 0.3 * size],
                points_m: (0..12)
                    .map(|_| [0; 3].map(|_| rng.random_range(-0.5..0.5) * size))
                    .collect(),
            }
        })
        .collect();
    WorldSpec {
        rocks,
        start: StartPose {
            head_m: [0.0, 0.0, 0.12],
            ..StartPose::default()
        },
        ..WorldSpec::default()
    }
}

struct Run {
    plant: PhysicsPlant,
    sel: GaitSelector,
    pos: Vec<f64>,
    vel: Vec<f64>,
    cmds: Vec<Command>,
}

impl Run {
    fn new(spec: &WorldSpec, gait: GaitKind, self_collision: bool) -> Self {
        let config = PhysicsConfig {
            modules: N,
            noise: NoiseConfig::default(),
            self_collision,
            ..PhysicsConfig::default()
        };
        let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
        Run {
            plant: PhysicsPlant::new(spec, config).expect("valid world"),
            sel: GaitSelector::new(layout, GaitTable::default(), gait, 0.5, 3.46),
            pos: vec![0.0; N],
            vel: vec![0.0; N],
            cmds: vec![Command::LIMP; N],
        }
    }

    fn step(&mut self) {
        let t = self.plant.time_s();
        self.sel.update(t, &mut self.pos, &mut self.vel);
        for (c, &p) in self.cmds.iter_mut().zip(&self.pos) {
            *c = Command::position(p);
        }
        self.plant.step(1e-3, &self.cmds);
    }
}

const VARIANTS: [(&str, bool); 2] = [("self_collision_off", false), ("self_collision_on", true)];
const ROUNDS: usize = 3;

/// Wall seconds for 5 simulated seconds from the start pose.
fn time_5s(spec: &WorldSpec, gait: GaitKind, self_collision: bool) -> (f64, Run) {
    let mut run = Run::new(spec, gait, self_collision);
    let start = Instant::now();
    for _ in 0..5000 {
        run.step();
    }
    (start.elapsed().as_secs_f64(), run)
}

fn print_rtf(name: &str, spec: &WorldSpec, gait: GaitKind) {
    let mut walls = [Vec::new(), Vec::new()];
    for round in 0..ROUNDS {
        for (v, &(variant, on)) in VARIANTS.iter().enumerate() {
            let (wall, run) = time_5s(spec, gait, on);
            walls[v].push(wall);
            println!(
                "physics_rtf {name} {variant} round {round}: 5.0 simulated s in {wall:.3} wall s, \
                 RTF {:.1}x, contacts at the end {:?}, self-contact onsets {}",
                5.0 / wall,
                run.plant.contacts(),
                run.plant.self_contacts()
            );
        }
    }
    for (v, (variant, _)) in VARIANTS.iter().enumerate() {
        walls[v].sort_by(f64::total_cmp);
        let median = walls[v][ROUNDS / 2];
        println!(
            "physics_rtf {name} {variant}: median {:.1} µs per 1 ms step, RTF {:.1}x",
            median / 5.0 * 1e3,
            5.0 / median
        );
    }
}

fn physics_rtf(c: &mut Criterion) {
    let worlds = [
        (
            "18_modules_40_pegs_slithering",
            pegs_world(),
            GaitKind::Slithering,
        ),
        (
            "18_modules_rock_pile_sidewinding",
            rocks_world(),
            GaitKind::Sidewinding,
        ),
    ];
    for (name, spec, gait) in &worlds {
        print_rtf(name, spec, *gait);
    }
    let mut group = c.benchmark_group("physics_step_1ms");
    group.sample_size(20);
    for (name, spec, gait) in &worlds {
        for (variant, on) in VARIANTS {
            let mut run = Run::new(spec, *gait, on);
            for _ in 0..1000 {
                run.step();
            }
            group.bench_function(format!("{name}/{variant}"), |b| b.iter(|| run.step()));
        }
    }
    group.finish();
}

// No plots: criterion's plotters backend finds no font once plotters' `ab_glyph`
// feature (the lab's PNGs) is on; the figures are the printed estimates.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = physics_rtf
}
criterion_main!(benches);
