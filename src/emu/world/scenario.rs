//! World scenario files (TOML): a world described by seeded generators (peg boards, peg
//! rows, explicit pegs, pegs from CSV, poles, rock piles, walls, a start pose), turned into
//! an explicit [`WorldSpec`] by [`WorldScenario::generate`]. `docs/scenarios.md` documents
//! every key and its default; `scenarios/` holds examples.
//!
//! A separate file type from the emulator's model file (`emu::model_file`): that one describes
//! the robot model (servo, noise), this one the world; the lab varies them independently.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::spec::{Anisotropic, Wall, WorldSpec};

/// Default height of generated pegs, m (well above the body's 5.1 cm).
pub const DEFAULT_PEG_HEIGHT_M: f64 = 0.15;

/// A world scenario file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldScenario {
    /// Master seed; each generator derives its own RNG from it, its kind and its index.
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub ground: Ground,
    #[serde(default)]
    pub friction: FrictionSpec,
    /// `[[peg_board]]`: seeded random peg layouts.
    #[serde(default, rename = "peg_board")]
    pub peg_boards: Vec<PegBoard>,
    /// `[[peg_row]]`: straight rows of pegs, optionally alternating sides.
    #[serde(default, rename = "peg_row")]
    pub peg_rows: Vec<PegRow>,
    /// `[[peg_fence]]`: seeded irregular rows of pegs with openings between them.
    #[serde(default, rename = "peg_fence")]
    pub peg_fences: Vec<PegFence>,
    /// `[[peg]]`: explicit pegs.
    #[serde(default, rename = "peg")]
    pub pegs: Vec<ExplicitPeg>,
    /// `[[peg_file]]`: pegs from CSV files (paths relative to the scenario file).
    #[serde(default, rename = "peg_file")]
    pub peg_files: Vec<PegFile>,
    /// `[[pole]]`: vertical poles.
    #[serde(default, rename = "pole")]
    pub poles: Vec<PoleGen>,
    /// `[[rock_pile]]`: seeded random convex rocks resting on the ground.
    #[serde(default, rename = "rock_pile")]
    pub rock_piles: Vec<RockPile>,
    /// `[[wall]]`: straight walls (the `WorldSpec` type, all keys required).
    #[serde(default, rename = "wall")]
    pub walls: Vec<Wall>,
    #[serde(default)]
    pub start: StartGen,
    /// The file this was loaded from (for error messages and relative paths).
    #[serde(skip)]
    pub source: Option<PathBuf>,
}

/// `[ground]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Ground {
    pub enabled: bool,
}

impl Default for Ground {
    fn default() -> Self {
        Self { enabled: true }
    }
}

/// `[friction]` (and `[friction.anisotropic]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionSpec {
    pub mu: f64,
    pub anisotropic: Option<Anisotropic>,
    /// Skin–peg friction; default `mu` (docs/scenarios.md).
    pub peg_mu: Option<f64>,
}

impl Default for FrictionSpec {
    fn default() -> Self {
        Self {
            mu: 0.5,
            anisotropic: None,
            peg_mu: None,
        }
    }
}

/// A rectangle in the ground plane: `{ x_m = [a, b], y_m = [c, d] }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    pub x_m: [f64; 2],
    pub y_m: [f64; 2],
}

impl Region {
    pub fn contains(&self, x: f64, y: f64) -> bool {
        (self.x_m[0]..=self.x_m[1]).contains(&x) && (self.y_m[0]..=self.y_m[1]).contains(&y)
    }
    pub fn width_m(&self) -> f64 {
        self.x_m[1] - self.x_m[0]
    }
    pub fn depth_m(&self) -> f64 {
        self.y_m[1] - self.y_m[0]
    }
}

/// `[[peg_board]]`: `count` pegs whose centres lie in `region`, no two centres closer
/// than `min_spacing_m` (centre to centre; the free gap is `min_spacing_m − diameter_m`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PegBoard {
    pub count: usize,
    pub diameter_m: f64,
    #[serde(default = "default_peg_height")]
    pub height_m: f64,
    pub min_spacing_m: f64,
    pub region: Region,
    /// Overrides the derived seed of this board.
    #[serde(default)]
    pub seed: Option<u64>,
}

/// `[[peg_row]]`: pegs at `start_m + i·spacing·(cos d, sin d)`, alternating sides by
/// `lateral_offset_m` (peg 0 to the left). The spacing comes from exactly one of
/// `spacing_m`, `wave` or `serpenoid`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PegRow {
    pub start_m: [f64; 2],
    #[serde(default)]
    pub direction_rad: f64,
    pub count: usize,
    pub diameter_m: f64,
    #[serde(default = "default_peg_height")]
    pub height_m: f64,
    #[serde(default)]
    pub spacing_m: Option<f64>,
    #[serde(default)]
    pub lateral_offset_m: Option<f64>,
    /// Pegs inside the bends of a planar wave of this geometry.
    #[serde(default)]
    pub wave: Option<Wave>,
    /// Pegs inside the bends of the serpenoid this robot makes.
    #[serde(default)]
    pub serpenoid: Option<SerpenoidWave>,
}

/// `[[peg_fence]]`: pegs along a line from `start_m` in `direction_rad`, `length_m`
/// long, the free gap between neighbours uniform in `gap_m` and each peg pushed off the
/// line by up to `jitter_m` either way: an irregular array with openings of random
/// width (thesis §4.3.7, the sidewinding experiment).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PegFence {
    pub start_m: [f64; 2],
    #[serde(default)]
    pub direction_rad: f64,
    pub length_m: f64,
    pub diameter_m: f64,
    #[serde(default = "default_peg_height")]
    pub height_m: f64,
    /// `[min, max]` free gap between neighbouring pegs (surface to surface), m.
    pub gap_m: [f64; 2],
    #[serde(default)]
    pub jitter_m: f64,
    #[serde(default)]
    pub seed: Option<u64>,
}

/// A planar wave of the body axis: wavelength along the row, amplitude across it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wave {
    pub wavelength_m: f64,
    pub amplitude_m: f64,
}

/// A lateral serpenoid: `waves_per_body` waves, joint amplitude `joint_amplitude_rad` on
/// the lateral joints (every other module).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerpenoidWave {
    pub waves_per_body: f64,
    pub joint_amplitude_rad: f64,
}

/// `[[peg]]`: one explicit peg.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExplicitPeg {
    pub x_m: f64,
    pub y_m: f64,
    pub diameter_m: f64,
    #[serde(default = "default_peg_height")]
    pub height_m: f64,
}

/// `[[peg_file]]`: a CSV of `x,y[,diameter]` per line (m; `#` comments and a header
/// line allowed); `diameter_m` is used where a line has no diameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PegFile {
    pub path: PathBuf,
    #[serde(default)]
    pub diameter_m: Option<f64>,
    #[serde(default = "default_peg_height")]
    pub height_m: f64,
}

/// `[[pole]]`: `sections` (bottom to top) or `taper`, exactly one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoleGen {
    pub x_m: f64,
    pub y_m: f64,
    /// Skin–pole friction; default `[friction] mu`.
    #[serde(default)]
    pub mu: Option<f64>,
    #[serde(default)]
    pub sections: Option<Vec<SectionGen>>,
    #[serde(default)]
    pub taper: Option<Taper>,
}

/// One pole section from the previous section's top (or the ground) up to `top_m`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionGen {
    pub top_m: f64,
    pub diameter_m: f64,
}

/// A pole whose diameter changes linearly from bottom to top, in `steps` equal sections.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Taper {
    pub height_m: f64,
    pub bottom_diameter_m: f64,
    pub top_diameter_m: f64,
    #[serde(default = "default_taper_steps")]
    pub steps: usize,
}

/// `[[rock_pile]]`: `count` rocks, centres in `region`, sizes (≈ diameter) uniform in
/// `size_m`, each the convex hull of `points` points on a jittered ellipsoid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RockPile {
    pub count: usize,
    pub size_m: [f64; 2],
    pub region: Region,
    #[serde(default)]
    pub seed: Option<u64>,
    #[serde(default = "default_rock_points")]
    pub points: usize,
    /// Height ÷ width range of the ellipsoids (flat rocks < 1).
    #[serde(default = "default_rock_flatness")]
    pub flatness: [f64; 2],
    /// Relative radial jitter of the hull points.
    #[serde(default = "default_rock_jitter")]
    pub jitter: f64,
}

/// `[start]`: explicit (`head_m`, `yaw_rad`, `joint_angles_rad`) or `random`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StartGen {
    /// `[x, y]` or `[x, y, z]`; default `[0, 0, 0]`.
    pub head_m: Option<Vec<f64>>,
    /// Direction head → tail, rad from +x; default π (the snake faces +x).
    pub yaw_rad: Option<f64>,
    pub joint_angles_rad: Vec<f64>,
    pub random: Option<RandomStart>,
    /// Skip the check that the straight body clears every obstacle.
    pub allow_contact: bool,
}

/// `[start.random]`: head uniform in `region`, yaw uniform in `yaw_range_rad`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomStart {
    pub region: Region,
    #[serde(default = "default_yaw_range")]
    pub yaw_range_rad: [f64; 2],
    #[serde(default)]
    pub seed: Option<u64>,
}

fn default_peg_height() -> f64 {
    DEFAULT_PEG_HEIGHT_M
}
fn default_taper_steps() -> usize {
    8
}
fn default_rock_points() -> usize {
    16
}
fn default_rock_flatness() -> [f64; 2] {
    [0.5, 0.9]
}
fn default_rock_jitter() -> f64 {
    0.15
}
fn default_yaw_range() -> [f64; 2] {
    [std::f64::consts::PI, std::f64::consts::PI]
}

/// Everything that can go wrong loading or generating a world scenario. Messages name
/// the file and the key (`peg_board[1].min_spacing_m`).
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("world scenario {}: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("world scenario {}: {source}", path.display())]
    Parse {
        path: PathBuf,
        #[source]
        source: toml::de::Error,
    },
    #[error("world scenario {file}: {key}: {msg}")]
    Invalid {
        file: String,
        key: String,
        msg: String,
    },
    #[error(
        "world scenario {file}: {key}: {count} pegs do not fit at min_spacing_m = {spacing_m} \
         in the region: a random layout fits about {fit} (a hexagonal packing at most {hex})"
    )]
    PegsDontFit {
        file: String,
        key: String,
        count: usize,
        spacing_m: f64,
        /// How many the seeded random layout placed before it saturated.
        fit: usize,
        /// Upper bound from a hexagonal packing of the region.
        hex: usize,
    },
    #[error("world scenario {file}: start: {msg}")]
    StartBlocked { file: String, msg: String },
}

impl WorldScenario {
    /// Read, parse and validate `path` (unknown keys are errors). Peg files are read by
    /// [`generate`](Self::generate), relative to `path`'s directory.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
            path: path.to_owned(),
            source,
        })?;
        let mut s: Self = toml::from_str(&text).map_err(|source| ScenarioError::Parse {
            path: path.to_owned(),
            source,
        })?;
        s.source = Some(path.to_owned());
        s.validate()?;
        Ok(s)
    }

    /// Parse and validate TOML text (peg files relative to the current directory).
    pub fn parse(text: &str) -> Result<Self, ScenarioError> {
        let s: Self = toml::from_str(text).map_err(|source| ScenarioError::Parse {
            path: PathBuf::from("<text>"),
            source,
        })?;
        s.validate()?;
        Ok(s)
    }

    /// The name used in error messages.
    pub fn file_name(&self) -> String {
        self.source
            .as_ref()
            .map_or_else(|| "<text>".to_owned(), |p| p.display().to_string())
    }

    /// The directory relative paths are resolved against.
    pub fn base_dir(&self) -> PathBuf {
        self.source
            .as_ref()
            .and_then(|p| p.parent())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
    }

    /// The world for a snake of `modules` modules: deterministic given the seeds.
    /// Same as `generate_trial(modules, 0)`.
    pub fn generate(&self, modules: usize) -> Result<WorldSpec, ScenarioError> {
        self.generate_trial(modules, 0)
    }

    /// The world with the random start of trial `trial`: obstacles are the same for every
    /// trial; only a `[start.random]` start changes (explicit starts ignore `trial`).
    pub fn generate_trial(&self, modules: usize, trial: u64) -> Result<WorldSpec, ScenarioError> {
        self.validate()?;
        super::build::build(self, modules, trial)
    }

    pub(crate) fn invalid(&self, key: impl Into<String>, msg: impl Into<String>) -> ScenarioError {
        ScenarioError::Invalid {
            file: self.file_name(),
            key: key.into(),
            msg: msg.into(),
        }
    }
}

#[cfg(test)]
#[path = "scenario_tests.rs"]
mod tests;
