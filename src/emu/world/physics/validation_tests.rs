//! The physics against the literature, driven by the real gaits (SPEC §2, §5-6).
//! Figures are printed (`cargo test -- --nocapture`) for the report.

use std::f64::consts::PI;

use super::tests::{hold, quiet};
use super::*;
use crate::emu::Plant;
use crate::gait::{BodyLayout, GaitKind, GaitParams, Serpenoid};
use crate::module::MODULE_LENGTH_M;

pub(super) const N: usize = 18;

pub(super) fn layout() -> BodyLayout {
    BodyLayout::alternating(N, Plane::Lateral, MODULE_LENGTH_M)
}

/// Joint angles of `kind` at phase `psi_rad`.
fn gait_pose(kind: GaitKind, params: &GaitParams, psi_rad: f64) -> Vec<f64> {
    let l = layout();
    let mut out = vec![0.0; N];
    Serpenoid::for_layout(kind, params, &l).evaluate(&l, psi_rad, &mut out);
    out
}

/// Runs `kind` open loop for `duration_s` from its own start pose (no blend), calling
/// `each(t_s, plant)` after every step; returns the plant.
pub(super) fn run_gait(
    spec: &WorldSpec,
    kind: GaitKind,
    params: GaitParams,
    duration_s: f64,
    each: impl FnMut(f64, &PhysicsPlant),
) -> PhysicsPlant {
    run_gait_from(spec, quiet(N), kind, params, 0.0, duration_s, each)
}

/// [`run_gait`] with the gait's clock starting at `t0_s` (its pose at that phase).
pub(super) fn run_gait_from(
    spec: &WorldSpec,
    config: PhysicsConfig,
    kind: GaitKind,
    params: GaitParams,
    t0_s: f64,
    duration_s: f64,
    mut each: impl FnMut(f64, &PhysicsPlant),
) -> PhysicsPlant {
    let psi0 = params.temporal_freq_rad_s * t0_s;
    let spec = WorldSpec {
        start: crate::emu::world::StartPose {
            joint_angles_rad: gait_pose(kind, &params, psi0),
            ..spec.start.clone()
        },
        ..spec.clone()
    };
    let mut plant = PhysicsPlant::new(&spec, config).unwrap();
    let (l, mut pos) = (layout(), vec![0.0; N]);
    let gait = Serpenoid::for_layout(kind, &params, &l);
    let steps = (duration_s * 1e3).round() as usize;
    for k in 0..steps {
        gait.evaluate(
            &l,
            psi0 + params.temporal_freq_rad_s * k as f64 * 1e-3,
            &mut pos,
        );
        plant.step(1e-3, &hold(&pos));
        each((k + 1) as f64 * 1e-3, &plant);
    }
    plant
}

/// Second moments (xx, xy, yy) of the links' ground-plane positions about their centre.
fn second_moments(plant: &PhysicsPlant) -> [f64; 3] {
    let c = plant.centre_of_mass_m();
    let mut m = [0.0; 3];
    for k in 0..plant.link_count() {
        let p = plant.link_pose(k).position_m;
        let (x, y) = (p[0] - c[0], p[1] - c[1]);
        m[0] += x * x;
        m[1] += x * y;
        m[2] += y * y;
    }
    m
}

/// Principal axis (unit, sign arbitrary) of second moments `m`.
fn principal_axis(m: [f64; 3]) -> [f64; 2] {
    let theta = 0.5 * (2.0 * m[1]).atan2(m[0] - m[2]);
    [theta.cos(), theta.sin()]
}

/// Principal axis of the links' ground-plane positions (unit, sign arbitrary).
fn body_axis(plant: &PhysicsPlant) -> [f64; 2] {
    principal_axis(second_moments(plant))
}

/// Angle between a displacement and an axis, degrees in [0, 90].
fn angle_to_axis_deg(d: [f64; 2], axis: [f64; 2]) -> f64 {
    let cos = ((d[0] * axis[0] + d[1] * axis[1]) / d[0].hypot(d[1])).abs();
    cos.min(1.0).acos().to_degrees()
}

fn body_length_m() -> f64 {
    (N + 1) as f64 * MODULE_LENGTH_M
}

#[test]
fn sidewinding_travels_sideways() {
    let params = GaitParams::default_for(GaitKind::Sidewinding);
    let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
    let cycles = 3;
    // Centre at each cycle boundary after one settling cycle, and the body axis
    // averaged over each cycle (the principal axis of the summed second moments), so
    // the wave's own swing of the axis within a cycle does not count.
    let mut marks: Vec<[f64; 3]> = Vec::new();
    let mut moments: Vec<[f64; 3]> = Vec::new();
    let mut next = cycle_s;
    run_gait(
        &WorldSpec::default(),
        GaitKind::Sidewinding,
        params,
        cycle_s * (1 + cycles) as f64 + 1e-3,
        |t, p| {
            if t >= next - 1e-9 {
                marks.push(p.centre_of_mass_m());
                moments.push([0.0; 3]);
                next += cycle_s;
            }
            if let Some(m) = moments.last_mut() {
                let now = second_moments(p);
                (0..3).for_each(|i| m[i] += now[i]);
            }
        },
    );
    let mut total = 0.0;
    let mut angles = Vec::new();
    for (w, m) in marks.windows(2).zip(&moments) {
        let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
        total += d[0].hypot(d[1]);
        angles.push(angle_to_axis_deg(d, principal_axis(*m)));
    }
    let per_cycle_bl = total / cycles as f64 / body_length_m();
    let angle_deg = angles.iter().sum::<f64>() / angles.len() as f64;
    println!(
        "sidewinding: {per_cycle_bl:.3} body lengths per cycle ({total:.3} m in {cycles} cycles), \
         {angle_deg:.1} deg from the body axis (per cycle: {angles:.1?})"
    );
    assert!(per_cycle_bl > 0.1 && per_cycle_bl < 1.0, "{per_cycle_bl}");
    assert!(angle_deg > 75.0, "{angle_deg}");
}

/// Centre displacement per cycle, m, the mean angle of each cycle's displacement to
/// the body axis at its start, degrees, and the total displacement, over `cycles`
/// cycles after `settle_s`.
fn travel_per_cycle(
    spec: &WorldSpec,
    kind: GaitKind,
    params: GaitParams,
    settle_s: f64,
    cycles: usize,
) -> (f64, f64, [f64; 2], [f64; 2]) {
    travel_per_cycle_with(spec, quiet(N), kind, params, settle_s, cycles)
}

/// [`travel_per_cycle`] with the plant's `config`.
fn travel_per_cycle_with(
    spec: &WorldSpec,
    config: PhysicsConfig,
    kind: GaitKind,
    params: GaitParams,
    settle_s: f64,
    cycles: usize,
) -> (f64, f64, [f64; 2], [f64; 2]) {
    let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
    let mut marks: Vec<([f64; 3], [f64; 2])> = Vec::new();
    let mut next = settle_s;
    run_gait_from(
        spec,
        config,
        kind,
        params,
        0.0,
        settle_s + cycle_s * cycles as f64 + 1e-3,
        |t, p| {
            if t >= next - 1e-9 {
                marks.push((p.centre_of_mass_m(), body_axis(p)));
                next += cycle_s;
            }
        },
    );
    let mut path = 0.0;
    let mut angle = 0.0;
    for w in marks.windows(2) {
        let d = [w[1].0[0] - w[0].0[0], w[1].0[1] - w[0].0[1]];
        path += d[0].hypot(d[1]);
        angle += angle_to_axis_deg(d, w[0].1);
        println!(
            "  {kind:?} cycle: displacement {d:.3?} m, body axis {:.3?}, angle {:.1} deg",
            w[0].1,
            angle_to_axis_deg(d, w[0].1)
        );
    }
    let first = marks[0].0;
    let last = marks[marks.len() - 1].0;
    let d = [last[0] - first[0], last[1] - first[1]];
    (path / cycles as f64, angle / cycles as f64, d, marks[0].1)
}

/// The default rolling gait on flat ground for `duration_s`, started a quarter cycle in,
/// where the C lies flat on the ground (at ψ = 0 it stands on its ends); `each` as in
/// [`run_gait`].
pub(super) fn roll_from_flat(
    duration_s: f64,
    each: impl FnMut(f64, &PhysicsPlant),
) -> PhysicsPlant {
    let params = GaitParams::default_for(GaitKind::Rolling);
    let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
    let spec = WorldSpec::default();
    run_gait_from(
        &spec,
        quiet(N),
        GaitKind::Rolling,
        params,
        0.25 * cycle_s,
        duration_s,
        each,
    )
}

#[test]
fn rolling_rolls_sideways() {
    // The arc's middle module, followed step by step: a rolling body turns about its
    // own axis and moves across it.
    let params = GaitParams::default_for(GaitKind::Rolling);
    let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
    let (settle_s, cycles) = (1.0, 3.0);
    let mid = N / 2 + 1;
    let (mut across, mut along, mut roll) = (0.0, 0.0, 0.0);
    let mut last: Option<[f64; 3]> = None;
    roll_from_flat(settle_s + cycles * cycle_s, |t, p| {
        let pose = p.link_pose(mid);
        let pos = pose.position_m;
        let [w, x, y, z] = pose.quat_wxyz;
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
        let axis = q * nalgebra::Vector3::x();
        let flat = nalgebra::Vector3::new(axis.x, axis.y, 0.0).normalize();
        let side = nalgebra::Vector3::z().cross(&flat);
        if let (Some(l), true) = (last, t > settle_s) {
            let d = nalgebra::Vector3::new(pos[0] - l[0], pos[1] - l[1], 0.0);
            across += d.dot(&side);
            along += d.dot(&flat);
        }
        last = Some(pos);
        if t > settle_s {
            roll += p.link_angvel_rad_s(mid).dot(&axis) * 1e-3;
        }
    });
    let ideal = PI * crate::module::MODULE_DIAMETER_M;
    let (across, along, roll) = (across / cycles, along / cycles, roll / cycles);
    println!(
        "rolling: the middle module turns {:.2} rev about its axis and moves {across:.3} m \
         across it ({:.2} of rolling without slip, π·d = {ideal:.3} m) and {along:.3} m (net) \
         along it per cycle",
        roll / (2.0 * PI),
        across.abs() / ideal
    );
    assert!((roll.abs() / (2.0 * PI) - 1.0).abs() < 0.3, "{roll}");
    assert!(across.abs() > 0.4 * ideal, "{across}");
    // Rolling, not skidding: a cylinder turning by ω about its axis a moves by
    // ω·r·(a × z), i.e. against `side` = z × a.
    assert!(across * roll < 0.0, "{across} {roll}");
    // The alternating joints make the arc slightly helical: it also screws along its
    // axis, about as far as it rolls across (printed above); bounded here.
    assert!(along.abs() < 2.0 * across.abs(), "{along} vs {across}");
}

/// Pegs matching the slithering wave: one just outside each lateral extremum of the
/// start shape (relative to the line from tail to head), repeated every wavelength
/// ahead of the head. Returns the pegs and the forward (tail-to-head) direction.
fn matched_pegs(params: &GaitParams) -> (Vec<crate::emu::world::Peg>, [f64; 2]) {
    let spec = WorldSpec::default();
    let angles = gait_pose(GaitKind::Slithering, params, 0.0);
    let poses = build::start_poses(
        &WorldSpec {
            start: crate::emu::world::StartPose {
                joint_angles_rad: angles,
                ..spec.start.clone()
            },
            ..spec
        },
        &quiet(N),
        None,
    );
    let pts: Vec<[f64; 2]> = poses
        .iter()
        .map(|p| [p.translation.x, p.translation.y])
        .collect();
    let (head, tail) = (pts[0], pts[pts.len() - 1]);
    let len = (head[0] - tail[0]).hypot(head[1] - tail[1]);
    let fwd = [(head[0] - tail[0]) / len, (head[1] - tail[1]) / len];
    let side = [-fwd[1], fwd[0]];
    // Coordinates along (u) and across (w) the line.
    let uw: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| {
            let (x, y) = (p[0] - tail[0], p[1] - tail[1]);
            [x * fwd[0] + y * fwd[1], x * side[0] + y * side[1]]
        })
        .collect();
    let mean_w = uw.iter().map(|p| p[1]).sum::<f64>() / uw.len() as f64;
    let mut crests = Vec::new();
    for k in 1..uw.len() - 1 {
        let (a, b, c) = (uw[k - 1][1], uw[k][1], uw[k + 1][1]);
        if (b > a && b >= c) || (b < a && b <= c) {
            crests.push(uw[k]);
        }
    }
    assert!(crests.len() >= 3, "{crests:?}");
    // Wavelength along the line: between crests on the same side.
    let lambda = (crests[0][0] - crests[2][0]).abs();
    let peg_d = 0.05;
    let gap = 0.5 * crate::module::MODULE_DIAMETER_M + 0.5 * peg_d + 0.003;
    // Measured: 3/8 of a wavelength behind each apex (near the inflection, where the
    // tailward flank faces backwards) pushes best; at 1/8 or on the apex it barely helps.
    let shift = 0.375;
    let mut pegs = Vec::new();
    for c in &crests {
        // Outside the bend's tailward flank, where the travelling wave presses it.
        let u0 = c[0] - shift * lambda;
        let w0 = interpolate_w(&uw, u0);
        for rep in 0..6 {
            let u = u0 + rep as f64 * lambda;
            let w = w0 + (c[1] - mean_w).signum() * gap;
            pegs.push(crate::emu::world::Peg {
                x_m: tail[0] + u * fwd[0] + w * side[0],
                y_m: tail[1] + u * fwd[1] + w * side[1],
                diameter_m: peg_d,
                height_m: 0.1,
            });
        }
    }
    (pegs, fwd)
}

/// `w` of the polyline `uw` at `u` (linear between the nearest points).
fn interpolate_w(uw: &[[f64; 2]], u: f64) -> f64 {
    for p in uw.windows(2) {
        let (a, b) = (p[0], p[1]);
        if (a[0] - u) * (b[0] - u) <= 0.0 && a[0] != b[0] {
            return a[1] + (b[1] - a[1]) * (u - a[0]) / (b[0] - a[0]);
        }
    }
    uw[0][1]
}

/// Slithering on isotropic skin needs pegs: on open ground the body drifts slightly
/// back (as the quasi-static Coulomb model predicts); along matched pegs the pegs'
/// reaction carries it head first, as rough as the ground (µ 0.5) or smooth (µ 0.2, as
/// the thesis's robot in its low-friction sleeve) alike: 0.635 and 0.638 m per cycle.
/// (With rapier's cone alone, whose sliding friction is off the slip's opposite, rough
/// pegs held the body: 0.03 m per cycle; `skin_friction`.)
#[test]
fn slithering_needs_pegs() {
    let params = GaitParams::default_for(GaitKind::Slithering);
    let cycles = 4;
    let (pegs, fwd) = matched_pegs(&params);
    let along = |d: [f64; 2]| (d[0] * fwd[0] + d[1] * fwd[1]) / cycles as f64;
    let (free, _, free_d, _) = travel_per_cycle(
        &WorldSpec::default(),
        GaitKind::Slithering,
        params,
        0.5,
        cycles,
    );
    let pegged = |peg_mu: Option<f64>| {
        let world = WorldSpec {
            pegs: pegs.clone(),
            friction: crate::emu::world::Friction {
                peg_mu,
                ..Default::default()
            },
            ..WorldSpec::default()
        };
        along(travel_per_cycle(&world, GaitKind::Slithering, params, 0.5, cycles).2)
    };
    let (rough, smooth) = (pegged(None), pegged(Some(0.2)));
    println!(
        "slithering: {free:.3} m per cycle on isotropic friction without pegs \
         ({:.3} m forward); along {} matched pegs {rough:.3} m forward per cycle at the \
         ground's µ 0.5, {smooth:.3} at peg µ 0.2",
        along(free_d),
        pegs.len(),
    );
    // Isotropic friction: no progress, a slight backward drift that the independent
    // quasi-static Coulomb model of the same gait also predicts.
    let l = layout();
    let gait = Serpenoid::for_layout(GaitKind::Slithering, &params, &l);
    let model = super::coulomb_model::displacement_per_cycle(
        &gait,
        &l,
        0.5 * crate::module::MODULE_DIAMETER_M,
        1000,
    );
    println!(
        "quasi-static Coulomb model of the same gait: {:.3} m forward, {:.3} m across per cycle",
        model[0], model[1]
    );
    assert!(free < 0.08, "{free}");
    assert!(
        model[0] < 0.0 && along(free_d) < 0.0,
        "{model:?} {free_d:?}"
    );
    let ratio = along(free_d) / model[0];
    assert!(
        (0.5..2.0).contains(&ratio),
        "physics/model drift ratio {ratio}"
    );
    // Pegs: head first, by a clear margin over open ground.
    for (pegs, v) in [("rough", rough), ("smooth", smooth)] {
        assert!(v > along(free_d) + 0.15, "{pegs} pegs: {v} vs {free_d:?}");
    }
}

/// Snake-like anisotropic skin (sliding along the body easier than across it) lets
/// slithering progress without pegs (Hu et al. 2009), through the friction hook.
#[test]
fn slithering_on_anisotropic_skin_moves_forward() {
    let params = GaitParams::default_for(GaitKind::Slithering);
    let (_, fwd) = matched_pegs(&params);
    let spec = WorldSpec {
        friction: crate::emu::world::Friction {
            mu: 0.5,
            anisotropic: Some(crate::emu::world::Anisotropic {
                mu_axial: 0.2,
                mu_lateral: 0.8,
            }),
            peg_mu: None,
        },
        ..WorldSpec::default()
    };
    let (_, _, d, _) = travel_per_cycle(&spec, GaitKind::Slithering, params, 0.5, 1);
    let forward = d[0] * fwd[0] + d[1] * fwd[1];
    println!(
        "slithering, anisotropic skin (axial 0.2, lateral 0.8): {forward:.3} m forward per cycle"
    );
    assert!(forward > 0.1, "{d:?}");
}

/// The physics with the servo's old speed-clamped position loop
/// (`PositionLoop::SpeedClamped`, the earlier default), for comparison.
fn speed_clamped(modules: usize) -> PhysicsConfig {
    let mut c = quiet(modules);
    c.servo.position_loop = crate::emu::servo::PositionLoop::SpeedClamped;
    c
}

/// Sidewinding and rolling travel no further per cycle than the body could without its
/// skin slipping (`no_slip_bound`), and a held 3-D pose comes to rest: with the
/// (default) profiled servo loop. With the old speed-clamped loop a held sidewinding
/// pose thrashes (links at 5 rad/s, flung 0.3 m up) and sidewinding covers 0.74 m per
/// cycle, past the bound (printed here).
#[test]
fn three_d_gaits_stay_within_the_no_slip_bound() {
    let radius = 0.5 * crate::module::MODULE_DIAMETER_M;
    for kind in [GaitKind::Sidewinding, GaitKind::Rolling] {
        let params = GaitParams::default_for(kind);
        let cycle_s = 2.0 * PI / params.temporal_freq_rad_s;
        let bound = super::no_slip_bound::no_slip(kind, &params, &layout(), radius);
        let travel = |config: PhysicsConfig| {
            travel_per_cycle_with(&WorldSpec::default(), config, kind, params, cycle_s, 3).0
        };
        let (per_cycle, clamped) = (travel(quiet(N)), travel(speed_clamped(N)));
        println!(
            "{kind:?}: {per_cycle:.3} m per cycle ({clamped:.3} with the speed-clamped \
             servo loop); no-slip bound {:.3} m, the cross-section loop {:.3} m",
            bound.bound_m, bound.loop_m
        );
        assert!(
            per_cycle < bound.bound_m,
            "{kind:?}: {per_cycle} vs {bound:?}"
        );
        assert!(
            per_cycle > 0.2 * bound.bound_m,
            "{kind:?} hardly moves: {per_cycle}"
        );
    }
    // A held sidewinding pose comes to rest. Released onto flat ground it may first
    // topple onto the side it rests on (δ = π/2's pose at phase 0 does, in about 3 s),
    // so the last 2 of 8 s are judged: thrashing (the speed-clamped loop's) goes on.
    let params = GaitParams::default_for(GaitKind::Sidewinding);
    let pose = gait_pose(GaitKind::Sidewinding, &params, 0.0);
    let spec = WorldSpec {
        start: crate::emu::world::StartPose {
            joint_angles_rad: pose.clone(),
            ..WorldSpec::default().start
        },
        ..WorldSpec::default()
    };
    let fastest = |config: PhysicsConfig| {
        let mut plant = PhysicsPlant::new(&spec, config).unwrap();
        let mut fastest = 0.0f64;
        for k in 0..8000 {
            plant.step(1e-3, &hold(&pose));
            if k >= 6000 {
                for l in 0..plant.link_count() {
                    fastest = fastest.max(plant.link_angvel_rad_s(l).norm());
                }
            }
        }
        fastest
    };
    let (profiled_w, clamped_w) = (fastest(quiet(N)), fastest(speed_clamped(N)));
    println!(
        "held sidewinding pose, 6-8 s: links up to {profiled_w:.3} rad/s ({clamped_w:.1} \
         with the speed-clamped loop)"
    );
    assert!(
        profiled_w < 0.2,
        "a held sidewinding pose still moves at {profiled_w} rad/s"
    );
}
