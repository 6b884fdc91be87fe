//! Runs a validated world scenario's generators in a fixed order into a `WorldSpec`.

use super::generators::{self as g, Kind};
use super::scenario::{PegRow, ScenarioError, WorldScenario};
use super::spec::{Friction, Peg, Pole, PoleSection, StartPose, WorldSpec};
use crate::module::MODULE_RADIUS_M;

/// Tries for a random start before giving up.
const START_TRIES: usize = 1_000;

pub(crate) fn build(
    s: &WorldScenario,
    modules: usize,
    trial: u64,
) -> Result<WorldSpec, ScenarioError> {
    let mut w = WorldSpec {
        ground: s.ground.enabled,
        friction: Friction {
            mu: s.friction.mu,
            anisotropic: s.friction.anisotropic,
            peg_mu: s.friction.peg_mu,
        },
        ..WorldSpec::default()
    };
    for p in &s.pegs {
        w.pegs.push(Peg {
            x_m: p.x_m,
            y_m: p.y_m,
            diameter_m: p.diameter_m,
            height_m: p.height_m,
        });
    }
    for (i, f) in s.peg_files.iter().enumerate() {
        let path = s.base_dir().join(&f.path);
        let key = format!("peg_file[{i}].path");
        let text = std::fs::read_to_string(&path)
            .map_err(|e| s.invalid(&key, format!("{}: {e}", path.display())))?;
        let pegs = g::parse_pegs_csv(&text, f.diameter_m, f.height_m)
            .map_err(|(line, msg)| s.invalid(&key, format!("{}:{line}: {msg}", path.display())))?;
        w.pegs.extend(pegs);
    }
    for (i, r) in s.peg_rows.iter().enumerate() {
        peg_row(s, &format!("peg_row[{i}]"), r, modules, &mut w.pegs)?;
    }
    for (i, f) in s.peg_fences.iter().enumerate() {
        let mut rng = g::rng_for(s.seed, f.seed, Kind::PegFence, i as u64);
        w.pegs.extend(g::fence_pegs(&mut rng, f));
    }
    for (i, b) in s.peg_boards.iter().enumerate() {
        let mut rng = g::rng_for(s.seed, b.seed, Kind::PegBoard, i as u64);
        let centres =
            g::sample_centres(&mut rng, &b.region, b.count, b.min_spacing_m).map_err(|fit| {
                ScenarioError::PegsDontFit {
                    file: s.file_name(),
                    key: format!("peg_board[{i}].count"),
                    count: b.count,
                    spacing_m: b.min_spacing_m,
                    fit,
                    hex: g::hex_bound(&b.region, b.min_spacing_m),
                }
            })?;
        w.pegs.extend(centres.into_iter().map(|[x, y]| Peg {
            x_m: x,
            y_m: y,
            diameter_m: b.diameter_m,
            height_m: b.height_m,
        }));
    }
    for p in &s.poles {
        w.poles.push(Pole {
            x_m: p.x_m,
            y_m: p.y_m,
            sections: pole_sections(p),
            mu: p.mu.unwrap_or(s.friction.mu),
        });
    }
    for (i, r) in s.rock_piles.iter().enumerate() {
        let mut rng = g::rng_for(s.seed, r.seed, Kind::RockPile, i as u64);
        for _ in 0..r.count {
            let x = g::uniform(&mut rng, r.region.x_m);
            let y = g::uniform(&mut rng, r.region.y_m);
            let size = g::uniform(&mut rng, r.size_m);
            let pts = g::rock_points(&mut rng, size, r.points, r.flatness, r.jitter);
            w.rocks.push(g::rock_on_ground(x, y, pts));
        }
    }
    w.walls.clone_from(&s.walls);
    w.start = start(s, &w, modules, trial)?;
    Ok(w)
}

fn peg_row(
    s: &WorldScenario,
    key: &str,
    r: &PegRow,
    modules: usize,
    out: &mut Vec<Peg>,
) -> Result<(), ScenarioError> {
    // Pegs inside each bend of the wave: the body axis passes `MODULE_RADIUS_M + peg
    // radius` outside the peg's centre at the crest, so a slithering body wraps them.
    let wave = match (r.wave, r.serpenoid) {
        (Some(w), _) => Some((w.wavelength_m, w.amplitude_m)),
        (_, Some(sp)) => Some(g::serpenoid_geometry(
            modules,
            sp.waves_per_body,
            sp.joint_amplitude_rad,
        )),
        _ => None,
    };
    let (spacing, offset) = match wave {
        Some((lambda, amp)) => {
            let inside = amp - MODULE_RADIUS_M - r.diameter_m / 2.0;
            let offset = r.lateral_offset_m.unwrap_or(inside);
            if offset < 0.0 {
                return Err(s.invalid(
                    key,
                    format!(
                        "wave amplitude {amp:.4} m is smaller than module radius + peg radius \
                         ({:.4} m): no peg fits inside the bends; give lateral_offset_m",
                        MODULE_RADIUS_M + r.diameter_m / 2.0
                    ),
                ));
            }
            (lambda / 2.0, offset)
        }
        None => (
            r.spacing_m.expect("validated: one spacing form"),
            r.lateral_offset_m.unwrap_or(0.0),
        ),
    };
    let (sin, cos) = r.direction_rad.sin_cos();
    for i in 0..r.count {
        let along = i as f64 * spacing;
        let side = if i % 2 == 0 { offset } else { -offset };
        out.push(Peg {
            x_m: r.start_m[0] + along * cos - side * sin,
            y_m: r.start_m[1] + along * sin + side * cos,
            diameter_m: r.diameter_m,
            height_m: r.height_m,
        });
    }
    Ok(())
}

fn pole_sections(p: &super::scenario::PoleGen) -> Vec<PoleSection> {
    if let Some(t) = p.taper {
        let dz = t.height_m / t.steps as f64;
        return (0..t.steps)
            .map(|k| {
                // Each step takes the diameter at its middle.
                let f = (k as f64 + 0.5) / t.steps as f64;
                PoleSection {
                    z0_m: k as f64 * dz,
                    z1_m: (k + 1) as f64 * dz,
                    diameter_m: t.bottom_diameter_m + f * (t.top_diameter_m - t.bottom_diameter_m),
                }
            })
            .collect();
    }
    let mut z0 = 0.0;
    p.sections
        .iter()
        .flatten()
        .map(|sec| {
            let out = PoleSection {
                z0_m: z0,
                z1_m: sec.top_m,
                diameter_m: sec.diameter_m,
            };
            z0 = sec.top_m;
            out
        })
        .collect()
}

fn start(
    s: &WorldScenario,
    w: &WorldSpec,
    modules: usize,
    trial: u64,
) -> Result<StartPose, ScenarioError> {
    let st = &s.start;
    let blocked = |msg: String| ScenarioError::StartBlocked {
        file: s.file_name(),
        msg,
    };
    if st.joint_angles_rad.len() > modules {
        return Err(s.invalid(
            "start.joint_angles_rad",
            format!("{} angles for {modules} joints", st.joint_angles_rad.len()),
        ));
    }
    if let Some(r) = &st.random {
        let mut rng = g::rng_for(s.seed, r.seed, Kind::Start, trial);
        for _ in 0..START_TRIES {
            let head = [
                g::uniform(&mut rng, r.region.x_m),
                g::uniform(&mut rng, r.region.y_m),
            ];
            let yaw = g::uniform(&mut rng, r.yaw_range_rad);
            if st.allow_contact || g::body_hits(w, head, yaw, modules).is_none() {
                return Ok(StartPose {
                    head_m: [head[0], head[1], 0.0],
                    yaw_rad: yaw,
                    roll_rad: 0.0,
                    joint_angles_rad: st.joint_angles_rad.clone(),
                });
            }
        }
        return Err(blocked(format!(
            "no random start in {START_TRIES} tries clears the obstacles for {modules} modules"
        )));
    }
    let h = st.head_m.clone().unwrap_or_default();
    let head = [
        h.first().copied().unwrap_or(0.0),
        h.get(1).copied().unwrap_or(0.0),
        h.get(2).copied().unwrap_or(0.0),
    ];
    let yaw = st.yaw_rad.unwrap_or(std::f64::consts::PI);
    if !st.allow_contact
        && let Some(hit) = g::body_hits(w, [head[0], head[1]], yaw, modules)
    {
        return Err(blocked(format!(
            "the straight body ({modules} modules from head ({:.3}, {:.3}), yaw {yaw:.3} rad) \
             intersects {hit}",
            head[0], head[1]
        )));
    }
    Ok(StartPose {
        head_m: head,
        yaw_rad: yaw,
        roll_rad: 0.0,
        joint_angles_rad: st.joint_angles_rad.clone(),
    })
}
