//! Seeded geometry generators behind the world scenario: peg layouts, serpenoid peg
//! spacing, rocks, the body-clearance check and the peg CSV reader. Pure functions.

use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::scenario::{PegFence, Region};
use super::spec::{Peg, Rock, WorldSpec};
use crate::module::{MODULE_LENGTH_M, MODULE_RADIUS_M};

/// Generator kinds, mixed into the derived seeds so kinds never share a stream.
#[derive(Debug, Clone, Copy)]
#[repr(u64)]
pub enum Kind {
    PegBoard = 1,
    RockPile = 2,
    Start = 3,
    PegFence = 4,
}

/// An RNG for generator `index` of `kind` from the master `seed` (or `over`ride):
/// adding a generator never reshuffles another.
pub fn rng_for(seed: u64, over: Option<u64>, kind: Kind, index: u64) -> Pcg64 {
    let base = over.unwrap_or(seed);
    let s = splitmix(splitmix(base ^ splitmix(kind as u64)) ^ index);
    Pcg64::seed_from_u64(s)
}

fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in `[a, b)`.
pub fn uniform<R: Rng + ?Sized>(rng: &mut R, [a, b]: [f64; 2]) -> f64 {
    a + (b - a) * rng.random::<f64>()
}

/// The pegs of a fence: the first at `start_m`, each next one a free gap drawn from
/// `gap_m` further along, while within `length_m`; each pushed off the line by up to
/// `±jitter_m`.
pub fn fence_pegs<R: Rng + ?Sized>(rng: &mut R, f: &PegFence) -> Vec<Peg> {
    let (sin, cos) = f.direction_rad.sin_cos();
    let mut pegs = Vec::new();
    let mut along = 0.0;
    while along <= f.length_m {
        let off = uniform(rng, [-f.jitter_m, f.jitter_m]);
        pegs.push(Peg {
            x_m: f.start_m[0] + along * cos - off * sin,
            y_m: f.start_m[1] + along * sin + off * cos,
            diameter_m: f.diameter_m,
            height_m: f.height_m,
        });
        along += f.diameter_m + uniform(rng, f.gap_m);
    }
    pegs
}

/// Consecutive rejected darts after which a layout counts as saturated.
const SATURATION_FAILS: usize = 5_000;

/// Dart throwing: up to `count` centres uniform in `region`, none closer than
/// `spacing_m` to another or to `existing`. `Err(placed)` when the region saturated
/// first (the number a random layout fits).
pub fn sample_centres<R: Rng + ?Sized>(
    rng: &mut R,
    region: &Region,
    count: usize,
    spacing_m: f64,
) -> Result<Vec<[f64; 2]>, usize> {
    let mut placed: Vec<[f64; 2]> = Vec::with_capacity(count);
    let mut fails = 0;
    let s2 = spacing_m * spacing_m;
    while placed.len() < count {
        let c = [uniform(rng, region.x_m), uniform(rng, region.y_m)];
        let free = placed
            .iter()
            .all(|p| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) >= s2);
        if free {
            placed.push(c);
            fails = 0;
        } else {
            fails += 1;
            if fails >= SATURATION_FAILS {
                return Err(placed.len());
            }
        }
    }
    Ok(placed)
}

/// Upper bound on centres `spacing_m` apart in `region`: hexagonal packing of disks of
/// radius `spacing_m / 2` in the region grown by that radius.
pub fn hex_bound(region: &Region, spacing_m: f64) -> usize {
    let area = (region.width_m() + spacing_m) * (region.depth_m() + spacing_m);
    (area * 2.0 / (3f64.sqrt() * spacing_m * spacing_m)).floor() as usize
}

/// Wavelength (along the direction of travel) and amplitude (across) of the body axis
/// of a lateral serpenoid on a snake of `modules` modules whose lateral joints are every
/// other module: curvature amplitude `A / (2·L_module)`, tangent angle
/// `ψ(s) = α·cos(2π s / λ_s)`, integrated numerically.
pub fn serpenoid_geometry(modules: usize, waves_per_body: f64, joint_amp_rad: f64) -> (f64, f64) {
    let body_m = modules as f64 * MODULE_LENGTH_M;
    let lambda_s = body_m / waves_per_body;
    let kappa = joint_amp_rad / (2.0 * MODULE_LENGTH_M);
    let alpha = kappa * lambda_s / std::f64::consts::TAU;
    const STEPS: usize = 4000;
    let ds = lambda_s / STEPS as f64;
    let (mut x, mut y) = (0.0_f64, 0.0_f64);
    let (mut y_min, mut y_max) = (0.0_f64, 0.0_f64);
    for i in 0..STEPS {
        let s = (i as f64 + 0.5) * ds;
        let psi = alpha * (std::f64::consts::TAU * s / lambda_s).cos();
        x += psi.cos() * ds;
        y += psi.sin() * ds;
        y_min = y_min.min(y);
        y_max = y_max.max(y);
    }
    (x, (y_max - y_min) / 2.0)
}

/// Points of a rock of size (≈ horizontal diameter) `size_m`: random directions on an
/// ellipsoid (semi-axes `size/2`, `size/2·u`, `size/2·flatness`), each pushed out or in
/// by up to `jitter`, turned by a random yaw. Centred on the origin.
pub fn rock_points<R: Rng + ?Sized>(
    rng: &mut R,
    size_m: f64,
    points: usize,
    flatness: [f64; 2],
    jitter: f64,
) -> Vec<[f64; 3]> {
    let a = size_m / 2.0;
    let b = a * uniform(rng, [0.7, 1.0]);
    let c = a * uniform(rng, flatness);
    let yaw = uniform(rng, [0.0, std::f64::consts::TAU]);
    let (sy, cy) = yaw.sin_cos();
    (0..points)
        .map(|_| {
            // Uniform direction on the sphere.
            let z = uniform(rng, [-1.0, 1.0]);
            let phi = uniform(rng, [0.0, std::f64::consts::TAU]);
            let r = (1.0 - z * z).sqrt();
            let k = 1.0 + jitter * uniform(rng, [-1.0, 1.0]);
            let (px, py, pz) = (a * k * r * phi.cos(), b * k * r * phi.sin(), c * k * z);
            [cy * px - sy * py, sy * px + cy * py, pz]
        })
        .collect()
}

/// A rock at `(x, y)` resting on the ground: its lowest point at z = 0.
pub fn rock_on_ground(x: f64, y: f64, points: Vec<[f64; 3]>) -> Rock {
    let low = points.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    Rock {
        center_m: [x, y, -low],
        points_m: points,
    }
}

/// Distance from point `p` to segment `a`–`b` in the plane.
pub fn point_segment_m(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((a[0] + t * dx - p[0]).powi(2) + (a[1] + t * dy - p[1]).powi(2)).sqrt()
}

/// Distance between segments `a`–`b` and `c`–`d` in the plane.
pub fn segment_segment_m(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    point_segment_m(a, c, d)
        .min(point_segment_m(b, c, d))
        .min(point_segment_m(c, a, b))
        .min(point_segment_m(d, a, b))
}

/// The straight body's axis in the plane: head and tail end.
pub fn body_segment(head: [f64; 2], yaw_rad: f64, modules: usize) -> ([f64; 2], [f64; 2]) {
    let len = modules as f64 * MODULE_LENGTH_M;
    let tail = [head[0] + len * yaw_rad.cos(), head[1] + len * yaw_rad.sin()];
    (head, tail)
}

/// The first obstacle the straight body (radius `MODULE_RADIUS_M`) would intersect, as
/// a description, or `None` when it is clear of every peg, pole, rock and wall.
pub fn body_hits(
    world: &WorldSpec,
    head: [f64; 2],
    yaw_rad: f64,
    modules: usize,
) -> Option<String> {
    let (a, b) = body_segment(head, yaw_rad, modules);
    let r = MODULE_RADIUS_M;
    for (i, p) in world.pegs.iter().enumerate() {
        if point_segment_m([p.x_m, p.y_m], a, b) < r + p.diameter_m / 2.0 {
            return Some(format!("peg {i} at ({:.3}, {:.3})", p.x_m, p.y_m));
        }
    }
    for (i, p) in world.poles.iter().enumerate() {
        let d = p.sections.iter().map(|s| s.diameter_m).fold(0.0, f64::max);
        if point_segment_m([p.x_m, p.y_m], a, b) < r + d / 2.0 {
            return Some(format!("pole {i} at ({:.3}, {:.3})", p.x_m, p.y_m));
        }
    }
    for (i, k) in world.rocks.iter().enumerate() {
        let reach = k
            .points_m
            .iter()
            .map(|q| q[0].hypot(q[1]))
            .fold(0.0, f64::max);
        if point_segment_m([k.center_m[0], k.center_m[1]], a, b) < r + reach {
            return Some(format!(
                "rock {i} at ({:.3}, {:.3})",
                k.center_m[0], k.center_m[1]
            ));
        }
    }
    for (i, w) in world.walls.iter().enumerate() {
        if segment_segment_m(a, b, w.from_m, w.to_m) < r + w.thickness_m / 2.0 {
            return Some(format!("wall {i}"));
        }
    }
    None
}

/// Parse a pegs CSV: `x,y[,diameter]` per line, `#` comments, blank lines and one
/// non-numeric header line allowed. `Err((line, message))`, 1-based line.
pub fn parse_pegs_csv(
    text: &str,
    default_diameter_m: Option<f64>,
    height_m: f64,
) -> Result<Vec<Peg>, (usize, String)> {
    let mut pegs = Vec::new();
    let mut seen_data = false;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let nums: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
        let nums = match nums {
            Ok(v) => v,
            Err(_) if !seen_data && pegs.is_empty() => {
                seen_data = true; // the header
                continue;
            }
            Err(e) => return Err((n + 1, format!("{line:?}: {e}"))),
        };
        seen_data = true;
        let diameter_m = match (nums.len(), default_diameter_m) {
            (3, _) => nums[2],
            (2, Some(d)) => d,
            (2, None) => return Err((n + 1, "no diameter and no diameter_m default".into())),
            (k, _) => return Err((n + 1, format!("{k} fields, expected x,y[,diameter]"))),
        };
        if !(nums.iter().all(|v| v.is_finite()) && diameter_m > 0.0) {
            return Err((n + 1, "values must be finite, diameter positive".into()));
        }
        pegs.push(Peg {
            x_m: nums[0],
            y_m: nums[1],
            diameter_m,
            height_m,
        });
    }
    Ok(pegs)
}
