//! Why does the emulator report joints faster than the motor (3.46 rad/s) under an
//! open-loop gait? Runs the gait straight through the physics plant (on flat ground, or
//! `rolling_helix` coiled round a pole) and prints, per run:
//! - the reported joint speed (the module's velocity field: the links' relative angular
//!   velocity about the joint axis): its peak, the share above the motor's, the
//!   commanded set-points' peak speed;
//! - its fast part (what is left after a 20 ms moving average): RMS, sign changes per
//!   joint-second (|x| > 0.3 rad/s), the lag-1 autocorrelation (−1: it alternates every
//!   1 ms step) and the spectrum's share above 20 Hz in bands (the spring's own mode
//!   `sqrt(k/J)/2π` ≈ 95 Hz for one link; 450-500 Hz = an odd-even alternation);
//! - the same for the speed a real module would compute from its encoder, `Δθ / 1 ms`
//!   of the exact joint angle (the twist of the two links' relative rotation);
//! - the joint constraints' violation (the anchors' gap, mm; the swing off the joint
//!   axis, mrad) and the fast part of the twist angle itself (mrad), RMS;
//! - every episode above the motor's speed: how many steps it lasts, whether one of
//!   the joint's two links touched down, lifted off or was hit (the world's normal
//!   force on it jumping by more than 2 N) from 3 ms before to 2 ms after;
//! - the plant's step time (µs per 1 ms step; the machine may be shared).
//!
//!     cargo run --release --example joint_speed_diag -- GAIT [SECONDS]
//!
//! Environment overrides: SPRING_K, SPRING_DAMP (N·m·s/rad), KV (velocity gain),
//! SUBSTEPS, ITER (solver iterations), PGS (sweeps per iteration), STAB (unbiased
//! sweeps), WARM=1 (warm-started joints), CONTACT_HZ, CONTACT_ZETA, NOISE=0 (no sensor
//! noise), SCENARIO (a world; default flat ground), SKIP (s left out at the start,
//! default 2), VERBOSE=1 (per joint), DUMP=1 (the worst episode's samples), EVENTS=1
//! (every episode).
use std::time::Instant;

use snaked::emu::Plant;
use snaked::emu::plant::plane_of;
use snaked::emu::world::physics::kinematics::{axis_of, twist_angle, upright_helix};
use snaked::emu::world::physics::{PhysicsConfig, PhysicsPlant};
use snaked::emu::world::scenario::WorldScenario;
use snaked::emu::world::{Pole, PoleSection, StartPose, WorldSpec};
use snaked::gait::{BodyLayout, GaitKind, GaitParams, GaitSelector, GaitTable, Plane, Serpenoid};
use snaked::module::MODULE_DIAMETER_M;
use snaked::module::MODULE_LENGTH_M;
use snaked::protocol::Command;

const MOTOR_RAD_S: f64 = 3.46;
const N: usize = 18;

/// `n` empty series with room for `steps` samples each.
fn series<T>(n: usize, steps: usize) -> Vec<Vec<T>> {
    (0..n).map(|_| Vec::with_capacity(steps)).collect()
}

fn env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

fn config() -> PhysicsConfig {
    let mut c = PhysicsConfig {
        modules: N,
        seed: 7,
        ..PhysicsConfig::default()
    };
    if let Some(v) = env("SPRING_K") {
        c.servo.spring_stiffness_nm_per_rad = v;
    }
    if let Some(v) = env("SPRING_DAMP") {
        c.servo.spring_damping_nm_s_per_rad = v;
    }
    if let Some(v) = env("KV") {
        c.servo.velocity_gain_nm_s_per_rad = v;
    }
    if let Some(v) = env("SUBSTEPS") {
        c.substeps = v;
    }
    if let Some(v) = env("ITER") {
        c.solver_iterations = v;
    }
    if let Some(v) = env("PGS") {
        c.pgs_iterations = v;
    }
    if let Some(v) = env("STAB") {
        c.stabilization_iterations = v;
    }
    if let Some(v) = env::<u32>("WARM") {
        c.warmstart_joints = v == 1;
    }
    if let Some(v) = env("CONTACT_HZ") {
        c.contact_natural_frequency_hz = v;
    }
    if let Some(v) = env("CONTACT_ZETA") {
        c.contact_damping_ratio = v;
    }
    if env::<u32>("NOISE") == Some(0) {
        c.noise = snaked::emu::plant::NoiseConfig::NONE;
    }
    c
}

/// The set-points of one step.
enum Driver {
    Selector(Box<GaitSelector>),
    /// The rolling helix rolled at `rate` rad/s of phase (as the pole tests do).
    Helix(Serpenoid, BodyLayout, f64),
}

impl Driver {
    fn update(&mut self, t_s: f64, pos: &mut [f64], vel: &mut [f64]) {
        match self {
            Driver::Selector(s) => s.update(t_s, pos, vel),
            Driver::Helix(g, l, rate) => {
                g.evaluate(l, *rate * t_s, pos);
                vel.iter_mut().for_each(|v| *v = f64::NAN);
            }
        }
    }
}

/// The helix gait of `radius_m` (the default pitch angle).
fn helix(radius_m: f64, layout: &BodyLayout) -> Serpenoid {
    let d = GaitParams::default_for(GaitKind::RollingHelix);
    let p = GaitParams {
        helix_radius_m: radius_m,
        helix_pitch_m: d.helix_pitch_m * radius_m / d.helix_radius_m,
        ..d
    };
    Serpenoid::for_layout(GaitKind::RollingHelix, &p, layout)
}

/// The pole tests' set-up: coiled at a 0.10 m helix round a pole 2 mm inside it, the
/// 0.075 m helix commanded (it squeezes) and rolled up at 1 rad/s.
fn on_the_pole(config: PhysicsConfig, layout: &BodyLayout) -> (PhysicsPlant, Driver) {
    let mut angles = vec![0.0; N];
    helix(0.10, layout).evaluate(layout, 0.0, &mut angles);
    let (place, r) = upright_helix(Plane::Lateral, &angles, MODULE_LENGTH_M, 0.6);
    let pole_r = r - 0.5 * MODULE_DIAMETER_M - 0.002;
    let spec = WorldSpec {
        poles: vec![Pole {
            x_m: 0.0,
            y_m: 0.0,
            sections: vec![PoleSection {
                z0_m: 0.0,
                z1_m: 2.0,
                diameter_m: 2.0 * pole_r,
            }],
            mu: 0.5,
        }],
        start: StartPose {
            joint_angles_rad: angles,
            ..StartPose::default()
        },
        ..WorldSpec::default()
    };
    let plant = PhysicsPlant::with_head_pose(&spec, config, Some(place)).unwrap();
    (
        plant,
        Driver::Helix(helix(0.075, layout), layout.clone(), 1.0),
    )
}

/// Statistics of one speed signal per joint (`s[i][k]`, rad/s, 1 ms apart).
#[derive(Default)]
struct Stats {
    peak: f64,
    peak_at: (usize, usize),
    above: usize,
    count: usize,
    fast_sq: f64,
    fast_n: usize,
    changes: Vec<usize>,
    lag1: (f64, f64),
    /// Spectral power in 0-20, 20-150, 150-450, 450-500 Hz.
    bands: [f64; 4],
}

/// `x` minus its centred moving average over 21 samples (20 ms; zero at the ends).
fn fast_part(x: &[f64]) -> Vec<f64> {
    let w = 10;
    let mut out = vec![0.0; x.len()];
    if x.len() <= 2 * w + 1 {
        return out;
    }
    let mut sum: f64 = x[..=2 * w].iter().sum();
    for k in w..x.len() - w {
        out[k] = x[k] - sum / (2 * w + 1) as f64;
        if k + w + 1 < x.len() {
            sum += x[k + w + 1] - x[k - w];
        }
    }
    out
}

fn stats(s: &[Vec<f64>]) -> Stats {
    let mut st = Stats {
        changes: vec![0; s.len()],
        ..Stats::default()
    };
    for (i, x) in s.iter().enumerate() {
        for (k, &v) in x.iter().enumerate() {
            if v.abs() > st.peak {
                st.peak = v.abs();
                st.peak_at = (i, k);
            }
            st.above += usize::from(v.abs() > MOTOR_RAD_S);
            st.count += 1;
        }
        let f = fast_part(x);
        let mut last_sign = 0.0;
        for k in 1..f.len() {
            st.fast_sq += f[k] * f[k];
            st.fast_n += 1;
            st.lag1.0 += f[k] * f[k - 1];
            st.lag1.1 += f[k] * f[k];
            let sign = if f[k].abs() > 0.3 { f[k].signum() } else { 0.0 };
            if sign != 0.0 {
                if last_sign != 0.0 && sign != last_sign {
                    st.changes[i] += 1;
                }
                last_sign = sign;
            }
        }
        // Hann-windowed periodogram over 500-sample blocks (2 Hz bins).
        let b = 500;
        let hann: Vec<f64> = (0..b)
            .map(|k| 0.5 - 0.5 * (std::f64::consts::TAU * k as f64 / b as f64).cos())
            .collect();
        for block in x.chunks_exact(b) {
            let mean = block.iter().sum::<f64>() / b as f64;
            let w: Vec<f64> = block
                .iter()
                .zip(&hann)
                .map(|(v, h)| (v - mean) * h)
                .collect();
            for bin in 1..=b / 2 {
                let (mut re, mut im) = (0.0, 0.0);
                let step = std::f64::consts::TAU * bin as f64 / b as f64;
                for (k, v) in w.iter().enumerate() {
                    let (sn, cs) = (step * k as f64).sin_cos();
                    re += v * cs;
                    im += v * sn;
                }
                let hz = bin as f64 * 1000.0 / b as f64;
                let band = match hz {
                    h if h < 20.0 => 0,
                    h if h < 150.0 => 1,
                    h if h < 450.0 => 2,
                    _ => 3,
                };
                st.bands[band] += re * re + im * im;
            }
        }
    }
    st
}

fn line(name: &str, st: &Stats, seconds: f64, skip: usize) -> String {
    let total: f64 = st.bands.iter().sum();
    let share = |b: usize| 100.0 * st.bands[b] / total.max(1e-30);
    let changes: usize = st.changes.iter().sum();
    format!(
        "  {name}: peak {:.2} rad/s (joint {} at {:.3} s), above 3.46 {:.3} % | fast part RMS {:.3} rad/s, \
         sign changes {:.1} /s per joint, lag-1 autocorrelation {:+.2} | spectrum 20-150 / 150-450 / 450-500 Hz: {:.1} / {:.1} / {:.1} % of the power",
        st.peak,
        st.peak_at.0,
        (st.peak_at.1 + skip) as f64 * 1e-3,
        100.0 * st.above as f64 / st.count.max(1) as f64,
        (st.fast_sq / st.fast_n.max(1) as f64).sqrt(),
        changes as f64 / seconds,
        st.lag1.0 / st.lag1.1.max(1e-30),
        share(1),
        share(2),
        share(3),
    )
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let gait: GaitKind = serde_json::from_value(serde_json::Value::String(
        a.get(1).cloned().unwrap_or("rolling".into()),
    ))
    .expect("gait name");
    let secs: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(20.0);
    let config = config();
    let layout = BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M);
    let (mut plant, mut driver) = if gait == GaitKind::RollingHelix {
        on_the_pole(config.clone(), &layout)
    } else {
        let f = std::env::var("SCENARIO").unwrap_or("scenarios/flat.toml".into());
        let spec = WorldScenario::load(std::path::Path::new(&f))
            .unwrap()
            .generate_trial(N, 0)
            .unwrap();
        let sel = GaitSelector::new(layout.clone(), GaitTable::default(), gait, 0.5, 3.46);
        (
            PhysicsPlant::new(&spec, config.clone()).unwrap(),
            Driver::Selector(Box::new(sel)),
        )
    };
    // The links' bodies and the joints' axes and anchors (as build.rs makes them).
    let links: Vec<_> = {
        let w = plant.world();
        let mut v: Vec<(u128, _)> = w
            .colliders
            .iter()
            .filter(|(_, c)| c.user_data >= 1000)
            .map(|(_, c)| (c.user_data - 1000, c.parent().unwrap()))
            .collect();
        v.sort_by_key(|x| x.0);
        v.into_iter().map(|x| x.1).collect()
    };
    let axes: Vec<_> = (0..N)
        .map(|i| {
            let a = axis_of(plane_of(config.first_plane, i));
            rapier3d::math::Vector::new(a.x as f32, a.y as f32, a.z as f32)
        })
        .collect();
    let half = (0.5 * MODULE_LENGTH_M) as f32;
    let (mut pos, mut vel) = (vec![0.0; N], vec![0.0; N]);
    let mut cmds = vec![Command::LIMP; N];
    let steps = (secs * 1e3) as usize;
    let mut v: Vec<Vec<f64>> = series(N, steps);
    let mut angle: Vec<Vec<f64>> = series(N, steps);
    let mut gap_mm: Vec<Vec<f64>> = series(N, steps);
    let mut swing_mrad: Vec<Vec<f64>> = series(N, steps);
    // Per link: the world's normal force on it, N.
    let mut touching: Vec<Vec<f32>> = series(N + 1, steps);
    let mut last_pos = [f64::NAN; N];
    let mut cmd_peak: f64 = 0.0;
    let mut busy = std::time::Duration::ZERO;
    for _ in 0..steps {
        driver.update(plant.time_s(), &mut pos, &mut vel);
        for i in 0..N {
            cmds[i] = Command {
                position_rad: pos[i] as f32,
                velocity_rad_s: vel[i] as f32,
                torque_nm: f32::NAN,
            };
            if last_pos[i].is_finite() {
                cmd_peak = cmd_peak.max(((pos[i] - last_pos[i]) / 1e-3).abs());
            }
            last_pos[i] = pos[i];
        }
        let t0 = Instant::now();
        plant.step(1e-3, &cmds);
        busy += t0.elapsed();
        let w = plant.world();
        for i in 0..N {
            v[i].push(f64::from(plant.feedback(i).velocity_rad_s));
            let (p, c) = (&w.bodies[links[i]], &w.bodies[links[i + 1]]);
            angle[i].push(twist_angle(p.rotation(), c.rotation(), axes[i]));
            let a1 = p.position() * rapier3d::math::Vector::new(-half, 0.0, 0.0);
            let a2 = c.position() * rapier3d::math::Vector::new(half, 0.0, 0.0);
            gap_mm[i].push(f64::from((a1 - a2).length()) * 1e3);
            let (ap, ac) = (*p.rotation() * axes[i], *c.rotation() * axes[i]);
            swing_mrad[i].push(f64::from(ap.cross(ac).length()).atan2(f64::from(ap.dot(ac))) * 1e3);
        }
        // Per link: the world's normal force on it over the last substep, N.
        let mut t = vec![0.0f32; N + 1];
        let dt = w.integration_parameters.dt;
        for pair in w.narrow_phase.contact_pairs() {
            let tag = |h| w.colliders.get(h).map_or(0, |c| c.user_data);
            let (t1, t2) = (tag(pair.collider1), tag(pair.collider2));
            if (t1 >= 1000) != (t2 >= 1000) {
                let k = (t1.max(t2) - 1000) as usize;
                t[k] += pair.total_impulse_magnitude() / dt;
            }
        }
        for (k, x) in t.into_iter().enumerate() {
            touching[k].push(x);
        }
    }
    let skip = ((env::<f64>("SKIP").unwrap_or(2.0) * 1e3) as usize).min(steps);
    let seconds = (steps - skip) as f64 * 1e-3 * N as f64;
    let cut = |x: &[Vec<f64>]| -> Vec<Vec<f64>> { x.iter().map(|s| s[skip..].to_vec()).collect() };
    let reported = stats(&cut(&v));
    let encoder: Vec<Vec<f64>> = angle
        .iter()
        .map(|s| {
            s.windows(2)
                .map(|w| (w[1] - w[0]) / 1e-3)
                .skip(skip.saturating_sub(1))
                .collect()
        })
        .collect();
    let enc = stats(&encoder);
    println!(
        "{gait:?} ({:.0} s after {:.1} s; substeps {} × iterations {} × PGS {} × stabilisation {}): \
         commanded peak {cmd_peak:.2} rad/s; plant step {:.1} µs",
        seconds / N as f64,
        skip as f64 * 1e-3,
        config.substeps,
        config.solver_iterations,
        config.pgs_iterations,
        config.stabilization_iterations,
        busy.as_secs_f64() / steps as f64 * 1e6,
    );
    println!("{}", line("reported", &reported, seconds, skip));
    println!("{}", line("encoder Δθ/1 ms", &enc, seconds, skip));
    // The constraint's violation against the twist angle's own fast part.
    let rms = |x: &[Vec<f64>]| {
        let (s, n) = x
            .iter()
            .flatten()
            .fold((0.0, 0usize), |a, v| (a.0 + v * v, a.1 + 1));
        (s / n.max(1) as f64).sqrt()
    };
    let max = |x: &[Vec<f64>]| x.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let fast = |x: &[Vec<f64>]| -> Vec<Vec<f64>> { x.iter().map(|s| fast_part(s)).collect() };
    let (gap, swing, twist) = (cut(&gap_mm), cut(&swing_mrad), cut(&angle));
    let twist_mrad: Vec<Vec<f64>> = fast(&twist)
        .iter()
        .map(|s| s.iter().map(|x| x * 1e3).collect())
        .collect();
    println!(
        "  constraint: anchor gap RMS {:.3} mm (max {:.2}), fast part {:.4} mm; swing RMS {:.2} mrad \
         (max {:.1}), fast part {:.3} mrad | twist angle's fast part {:.3} mrad RMS",
        rms(&gap),
        max(&gap),
        rms(&fast(&gap)),
        rms(&swing),
        max(&swing),
        rms(&fast(&swing)),
        rms(&twist_mrad),
    );
    if std::env::var("VERBOSE").is_ok() {
        let per_s = |c: &[usize]| -> Vec<String> {
            c.iter()
                .map(|x| format!("{:.0}", *x as f64 * N as f64 / seconds))
                .collect()
        };
        println!(
            "  sign changes /s, reported, per joint: {}",
            per_s(&reported.changes).join(" ")
        );
        println!(
            "  sign changes /s, encoder, per joint:  {}",
            per_s(&enc.changes).join(" ")
        );
        let per_joint_rms = |x: &[Vec<f64>]| -> Vec<String> {
            x.iter()
                .map(|s| {
                    format!(
                        "{:.2}",
                        (s.iter().map(|v| v * v).sum::<f64>() / s.len() as f64).sqrt()
                    )
                })
                .collect()
        };
        println!(
            "  fast part RMS, reported, per joint: {}",
            per_joint_rms(&fast(&cut(&v))).join(" ")
        );
        let touch: Vec<String> = touching
            .iter()
            .map(|t| {
                let t = &t[skip..];
                format!(
                    "{:.0}",
                    100.0 * t.iter().filter(|&&x| x > 0.0).count() as f64 / t.len() as f64
                )
            })
            .collect();
        println!(
            "  % of time touching the world, per link: {}",
            touch.join(" ")
        );
        let force: Vec<String> = touching
            .iter()
            .map(|t| {
                let t: Vec<f64> = t[skip..].iter().map(|&x| f64::from(x)).collect();
                let f = fast_part(&t);
                let mean = t.iter().sum::<f64>() / t.len() as f64;
                let rms = (f.iter().map(|x| x * x).sum::<f64>() / f.len() as f64).sqrt();
                format!("{mean:.1}±{rms:.1}")
            })
            .collect();
        println!(
            "  the world's normal force per link, N: mean ± RMS of its fast part: {}",
            force.join(" ")
        );
    }
    // Episodes above the motor's speed (reported).
    let (mut episodes, mut single, mut touched, mut lengths) = (0, 0, 0, Vec::new());
    let print_events = std::env::var("EVENTS").is_ok();
    for i in 0..N {
        let mut k = skip;
        while k < steps {
            if v[i][k].abs() <= MOTOR_RAD_S {
                k += 1;
                continue;
            }
            let start = k;
            while k < steps && v[i][k].abs() > MOTOR_RAD_S {
                k += 1;
            }
            let len = k - start;
            episodes += 1;
            single += usize::from(len <= 2);
            lengths.push(len);
            let lo = start.saturating_sub(3);
            let hi = (k + 2).min(steps);
            // A link of the joint touching down (its normal force rising from under
            // 0.05 N) or lifting off, or the force on it jumping by more than 2 N
            // (its weight), within 3 ms before to 2 ms after.
            let onset = [i, i + 1].iter().any(|&l| {
                (lo.max(1)..hi).any(|j| {
                    let (a, b) = (touching[l][j - 1], touching[l][j]);
                    (a < 0.05) != (b < 0.05) || (b - a).abs() > 2.0
                })
            });
            touched += usize::from(onset);
            if print_events {
                let peak = v[i][start..k].iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let d_mrad = (angle[i][k - 1] - angle[i][start.saturating_sub(1)]) * 1e3;
                println!(
                    "  episode: joint {i} at {:.3} s, {len} step(s), peak {peak:.2} rad/s, angle moved {d_mrad:+.2} mrad, contact event on link {i}/{}: {onset} (normal force {:.1?} / {:.1?} N); reported {:?}, encoder {:?}",
                    start as f64 * 1e-3,
                    i + 1,
                    &touching[i][lo..hi],
                    &touching[i + 1][lo..hi],
                    v[i][lo..hi]
                        .iter()
                        .map(|x| (x * 100.0).round() / 100.0)
                        .collect::<Vec<_>>(),
                    (lo.max(1)..hi)
                        .map(|j| ((angle[i][j] - angle[i][j - 1]) * 1e5).round() / 100.0)
                        .collect::<Vec<_>>(),
                );
            }
        }
    }
    lengths.sort_unstable();
    println!(
        "  episodes above 3.46 rad/s (reported): {episodes}, {single} of them 1-2 steps long (longest {}), \
         {touched} with a link of the joint touching down, lifting off or hit (a normal force jump over 2 N) within 3 ms",
        lengths.last().copied().unwrap_or(0),
    );
    if std::env::var("DUMP").is_ok() {
        let (i, k0) = (reported.peak_at.0, reported.peak_at.1 + skip);
        for k in k0.saturating_sub(30)..(k0 + 30).min(steps) {
            println!(
                "{:.3} v {:+.3} enc {:+.3} angle {:+.5} gap {:.3} mm swing {:.2} mrad normal force on the links {:.2}/{:.2} N",
                k as f64 * 1e-3,
                v[i][k],
                if k > 0 {
                    (angle[i][k] - angle[i][k - 1]) / 1e-3
                } else {
                    0.0
                },
                angle[i][k],
                gap_mm[i][k],
                swing_mrad[i][k],
                touching[i][k],
                touching[i + 1][k],
            );
        }
    }
}
