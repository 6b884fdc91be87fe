//! The trial plan (controllers × layouts × starts × repeats) and its execution: worker
//! threads take the next trial from an atomic index; results come back in plan order
//! (controller, layout, start, repeat) whatever the thread count, so the output is
//! identical. A shard (`lab::shard`) runs every N-th trial of the same plan.

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::LabError;
use super::compared::LabController;
use super::experiment::Experiment;
pub use super::experiment::{TrialResult, controller_names};
use super::file_stem;
use super::layout::{Layout, noise_seed};
use super::odometry_check::OdometryCheck;
use super::shard::Shard;
use super::stuck_check::StuckCheck;
use super::trial::{TrialConfig, TrialRecording, run_trial};
use crate::emu::world::WorldSpec;
use crate::gait::{BodyLayout, Plane};
use crate::module::MODULE_LENGTH_M;

/// What to run: the compared controllers on every layout, start and repeat.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The compared controllers, in report order.
    pub controllers: Vec<LabController>,
    pub layouts: Vec<Layout>,
    /// Starts (poses) per layout.
    pub starts: usize,
    /// Trials per pose, differing only in their sensor-noise seed (1: one per pose).
    pub repeats: usize,
    pub trial: TrialConfig,
    /// Record every trial to `DIR/<controller>-<layout>-s<start>.mcap` (must exist).
    pub record_dir: Option<std::path::PathBuf>,
}

/// One world of the plan: a layout with one of its starts.
#[derive(Debug, Clone)]
pub struct PlannedWorld<G> {
    pub layout: usize,
    pub start: usize,
    /// Which of the pose's repeats (0 when there is one).
    pub repeat: usize,
    pub world: Arc<WorldSpec>,
    /// What ends its trials.
    pub goal: G,
    /// Sensor-noise seed, shared by every controller on this world.
    pub noise_seed: u64,
}

/// How to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    pub threads: usize,
    /// Show a progress bar (only drawn on a terminal).
    pub progress: bool,
    /// Run only this share of the plan.
    pub shard: Option<Shard>,
    /// Keep every trial for its plots (`--plot-all`), not only each controller's first.
    pub plot_all: bool,
}

/// Checks the experiment and generates every world of it (fails before any trial runs).
pub fn plan<E: Experiment>(
    module: &E,
    exp: &Setup,
) -> Result<Vec<PlannedWorld<E::Goal>>, LabError> {
    if exp.controllers.is_empty() {
        return Err(LabError::NoControllers {
            known: crate::controller_interface::registry::known_names(
                crate::controllers::REGISTRY,
                module.gait(),
            ),
        });
    }
    let layout = BodyLayout::alternating(exp.trial.modules, Plane::Lateral, MODULE_LENGTH_M);
    let params = *exp.trial.gaits.get(module.gait());
    for (i, c) in exp.controllers.iter().enumerate() {
        if exp.controllers[..i].iter().any(|o| o.label == c.label) {
            return Err(LabError::BadValue(format!(
                "controller {:?} given twice",
                c.label
            )));
        }
        c.build(&layout, &params)?;
    }
    if exp.layouts.is_empty() {
        return Err(LabError::NoLayouts);
    }
    if exp.starts == 0 {
        return Err(LabError::NoStarts);
    }
    if exp.repeats == 0 {
        return Err(LabError::BadValue("--repeats must be at least 1".into()));
    }
    let t = &exp.trial;
    if !(t.limit_s.is_finite() && t.limit_s > 0.0) {
        return Err(LabError::BadValue(format!(
            "the time limit must be positive, not {} s",
            t.limit_s
        )));
    }
    let mut worlds = Vec::with_capacity(exp.layouts.len() * exp.starts * exp.repeats);
    for (li, l) in exp.layouts.iter().enumerate() {
        for start in 0..exp.starts {
            let (world, goal) = module.world(l, t.modules, start as u64)?;
            let world = Arc::new(world);
            let own = module.trial_config(t, &goal);
            if own.gaits != t.gaits {
                let params = own.gaits.get(module.gait());
                for c in &exp.controllers {
                    let bad = |e: String| LabError::BadValue(format!("layout {}: {e}", l.name));
                    let built = c.build(&layout, params).map_err(|e| bad(e.to_string()))?;
                    built
                        .controller
                        .accepts(params)
                        .map_err(|e| bad(format!("controller {}: {e}", c.label)))?;
                }
            }
            for repeat in 0..exp.repeats {
                worlds.push(PlannedWorld {
                    layout: li,
                    start,
                    repeat,
                    world: Arc::clone(&world),
                    goal: goal.clone(),
                    noise_seed: noise_seed(l.identity, start, repeat),
                });
            }
        }
    }
    Ok(worlds)
}

/// Runs every trial of `exp` and returns them in plan order. Stops at the first
/// failing trial and returns its error.
pub fn run<E: Experiment>(
    module: &E,
    exp: &Setup,
    opts: RunOptions,
) -> Result<Vec<TrialResult<E>>, LabError> {
    let all = RunOptions {
        shard: None,
        ..opts
    };
    Ok(run_share(module, exp, all)?
        .into_iter()
        .map(|(_, r)| r)
        .collect())
}

/// A hash of everything that decides `exp`'s trials and their figures: the
/// experiment, the controllers as built (calibrations included), the layouts' names
/// and identities, starts, repeats and the trial configuration. Shards of one run
/// share it.
pub fn plan_fingerprint<E: Experiment>(module: &E, exp: &Setup) -> u64 {
    let layouts: Vec<(&str, u64)> = exp
        .layouts
        .iter()
        .map(|l| (l.name.as_str(), l.identity))
        .collect();
    let text = format!(
        "{}|{:?}|{layouts:?}|{}|{}|{:?}",
        module.name(),
        exp.controllers,
        exp.starts,
        exp.repeats,
        exp.trial
    );
    super::layout::identity_of(text.as_bytes())
}

/// The trials of `opts.shard` (every trial without one), each with its index in the
/// whole plan, in plan order; and the plan's size.
pub fn run_share<E: Experiment>(
    module: &E,
    exp: &Setup,
    opts: RunOptions,
) -> Result<Vec<(usize, TrialResult<E>)>, LabError> {
    let worlds = plan(module, exp)?;
    let plan_total = exp.controllers.len() * worlds.len();
    let mine: Vec<usize> = (0..plan_total)
        .filter(|&i| opts.shard.is_none_or(|s| s.owns(i)))
        .collect();
    let total = mine.len();
    let who = opts
        .shard
        .map_or_else(String::new, |s| format!("shard {s}: "));
    let bar = progress_bar(total, opts.progress);
    bar.set_prefix(who.clone());
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    // Not on a terminal (a log, CI): a plain line every 5 % instead of the bar.
    let plain = opts.progress && !std::io::stderr().is_terminal();
    let every = (total / 20).max(1);
    let started = std::time::Instant::now();
    let failed = AtomicBool::new(false);
    let threads = opts.threads.clamp(1, total.max(1));
    let run_one = |i: usize| {
        let (c, w) = (i / worlds.len(), &worlds[i % worlds.len()]);
        let controller = &exp.controllers[c];
        let layout = &exp.layouts[w.layout].name;
        let recording = exp.record_dir.as_ref().map(|dir| TrialRecording {
            path: dir.join(if exp.repeats > 1 {
                format!(
                    "{}-{}-s{}-r{}.mcap",
                    file_stem(&controller.label),
                    file_stem(layout),
                    w.start,
                    w.repeat
                )
            } else {
                format!(
                    "{}-{}-s{}.mcap",
                    file_stem(&controller.label),
                    file_stem(layout),
                    w.start
                )
            }),
            world: &w.world,
            metadata: vec![
                ("experiment".into(), module.name().into()),
                ("controller".into(), controller.label.clone()),
                ("layout".into(), layout.clone()),
                ("start".into(), w.start.to_string()),
                ("repeat".into(), w.repeat.to_string()),
                ("noise_seed".into(), w.noise_seed.to_string()),
            ],
        });
        let rec = run_trial(
            controller,
            &w.world,
            &w.goal,
            w.noise_seed,
            &module.trial_config(&exp.trial, &w.goal),
            recording,
        )?;
        let metrics = module.metrics(&w.goal, &rec);
        let first = opts.plot_all || (w.layout == 0 && w.start == 0 && w.repeat == 0);
        Ok(TrialResult {
            controller: controller.label.clone(),
            layout: exp.layouts[w.layout].name.clone(),
            start: w.start,
            repeat: w.repeat,
            metrics,
            strain: rec.strain,
            stuck: StuckCheck::of(&rec),
            odometry: OdometryCheck::of(&rec),
            position: super::position_check::PositionCheck::of(&rec),
            plotted: first.then(|| (Arc::clone(&w.world), w.goal.clone(), rec)),
        })
    };
    let mut done: Vec<(usize, Result<TrialResult<E>, LabError>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut ran = Vec::new();
                    while !failed.load(Ordering::Relaxed) {
                        let j = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&i) = mine.get(j) else {
                            break;
                        };
                        let r = run_one(i);
                        failed.fetch_or(r.is_err(), Ordering::Relaxed);
                        bar.inc(1);
                        let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
                        if plain && (n.is_multiple_of(every) || n == total) {
                            eprintln!(
                                "snake-lab: {who}{n}/{total} trials, {:.0} s",
                                started.elapsed().as_secs_f64()
                            );
                        }
                        ran.push((i, r));
                    }
                    ran
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|h| h.join().expect("a trial thread panicked"))
            .collect()
    });
    bar.finish_and_clear();
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(i, r)| r.map(|r| (i, r))).collect()
}

fn progress_bar(total: usize, show: bool) -> ProgressBar {
    let target = if show && std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let style = ProgressStyle::with_template(
        "{prefix}{elapsed_precise} [{bar:30}] {pos}/{len} trials, ETA {eta_precise}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar())
    .progress_chars("=> ");
    let bar = ProgressBar::with_draw_target(Some(total as u64), target).with_style(style);
    // Trials take seconds each: tick so the clock and the ETA move between them.
    bar.enable_steady_tick(std::time::Duration::from_millis(500));
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::scenario::WorldScenario;
    use crate::gait::GaitKind;
    use crate::lab::pegboard::Pegboard;
    use crate::lab::pegboard::board::PEG_BOARD_TOML;

    fn experiment(controllers: &[&str], layouts: usize) -> Setup {
        let base = WorldScenario::parse(PEG_BOARD_TOML).unwrap();
        Setup {
            controllers: controllers
                .iter()
                .map(|s| LabController::named(GaitKind::Slithering, s).unwrap())
                .collect(),
            layouts: (0..layouts as u64)
                .map(|k| Layout::seeded(&base, 1000 + k))
                .collect(),
            starts: 2,
            repeats: 1,
            trial: TrialConfig {
                limit_s: 0.2,
                ..TrialConfig::default()
            },
            record_dir: None,
        }
    }

    #[test]
    fn plan_checks_its_input() {
        assert!(matches!(
            LabController::named(GaitKind::Slithering, "bogus"),
            Err(LabError::UnknownController { name, known }) if name == "bogus" && known.contains("open_loop")
        ));
        // A variant whose amplitude range excludes the nominal amplitude.
        let mut e = experiment(&["open_loop"], 1);
        e.controllers.push(
            LabController::variant(
                GaitKind::Slithering,
                r#"narrow={"amplitude":{"gains":{"min":0.1,"max":0.2}}}"#,
            )
            .unwrap(),
        );
        assert!(
            matches!(plan(&Pegboard::UNCONFIGURED, &e), Err(LabError::BadValue(m)) if m.contains("narrow"))
        );
        assert!(matches!(
            plan(&Pegboard::UNCONFIGURED, &experiment(&[], 1)),
            Err(LabError::NoControllers { .. })
        ));
        assert!(matches!(
            plan(&Pegboard::UNCONFIGURED, &experiment(&["open_loop"], 0)),
            Err(LabError::NoLayouts)
        ));
        assert!(matches!(
            plan(
                &Pegboard::UNCONFIGURED,
                &experiment(&["open_loop", "open_loop"], 1)
            ),
            Err(LabError::BadValue(_))
        ));
        let mut e = experiment(&["open_loop"], 1);
        e.starts = 0;
        assert!(matches!(
            plan(&Pegboard::UNCONFIGURED, &e),
            Err(LabError::NoStarts)
        ));
        let worlds = plan(&Pegboard::UNCONFIGURED, &experiment(&["open_loop"], 2)).unwrap();
        assert_eq!(worlds.len(), 4);
        assert_ne!(worlds[0].world.start, worlds[1].world.start, "two starts");
        assert_ne!(worlds[0].world.pegs, worlds[2].world.pegs, "two layouts");
    }

    #[test]
    fn results_come_in_plan_order_for_any_thread_count() {
        let e = experiment(&["open_loop"], 2);
        let one = run(
            &Pegboard::UNCONFIGURED,
            &e,
            RunOptions {
                threads: 1,
                progress: false,
                shard: None,
                plot_all: false,
            },
        )
        .unwrap();
        let two = run(
            &Pegboard::UNCONFIGURED,
            &e,
            RunOptions {
                threads: 2,
                progress: false,
                shard: None,
                plot_all: false,
            },
        )
        .unwrap();
        let keys: Vec<_> = one.iter().map(|r| (r.layout.clone(), r.start)).collect();
        assert_eq!(
            keys,
            [
                ("seed1000", 0),
                ("seed1000", 1),
                ("seed1001", 0),
                ("seed1001", 1)
            ]
            .map(|(l, s)| (l.to_string(), s))
        );
        for (a, b) in one.iter().zip(&two) {
            assert_eq!(a.metrics, b.metrics);
        }
        assert!(one[0].plotted.is_some());
        assert!(one[1..].iter().all(|r| r.plotted.is_none()));
    }
}
