//! What a world contains after its generators ran: every obstacle explicit.
use serde::{Deserialize, Serialize};

/// Contact friction between the snake's skin and the world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    /// Coulomb coefficient (isotropic cone). SEA Snake's polyester sleeve: about 0.4–0.6.
    pub mu: f64,
    /// Optional anisotropy: coefficients for sliding along the module's axis and across
    /// it (the cone becomes an ellipse); `None` = isotropic.
    pub anisotropic: Option<Anisotropic>,
    /// Skin–peg friction (isotropic), when the pegs are smoother than the ground;
    /// `None` = `mu` (and the anisotropy, as on the ground).
    #[serde(default)]
    pub peg_mu: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Anisotropic {
    pub mu_axial: f64,
    pub mu_lateral: f64,
}

impl Default for Friction {
    fn default() -> Self {
        Self {
            mu: 0.5,
            anisotropic: None,
            peg_mu: None,
        }
    }
}

/// A vertical cylinder standing on the ground (a peg).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Peg {
    pub x_m: f64,
    pub y_m: f64,
    pub diameter_m: f64,
    pub height_m: f64,
}

/// One section of a vertical pole, from `z0_m` to `z1_m`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoleSection {
    pub z0_m: f64,
    pub z1_m: f64,
    pub diameter_m: f64,
}

/// A vertical pole whose diameter changes along its height.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pole {
    pub x_m: f64,
    pub y_m: f64,
    /// Bottom to top, contiguous.
    pub sections: Vec<PoleSection>,
    /// Friction between the skin and the pole (the pole's surface).
    pub mu: f64,
}

/// A rock: a convex hull of points, placed at `center_m` (points are relative to it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rock {
    pub center_m: [f64; 3],
    pub points_m: Vec<[f64; 3]>,
}

/// A straight wall standing on the ground from `from_m` to `to_m` (x, y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wall {
    pub from_m: [f64; 2],
    pub to_m: [f64; 2],
    pub height_m: f64,
    pub thickness_m: f64,
}

/// Where the snake starts: the head module's position and the body's heading in the
/// ground plane, plus optional initial joint angles (head first; missing = straight).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPose {
    /// Position of the head end of the body, m (z is the body axis' height; 0 = resting
    /// on the ground at the module radius).
    pub head_m: [f64; 3],
    /// Direction from head to tail in the ground plane, rad from +x. (For a pole climb the
    /// generator places the body around the pole instead; see `scenario`.)
    pub yaw_rad: f64,
    /// The body rolled about its own axis (the head link's x, towards the head), rad;
    /// 0: the lateral joints' plane is horizontal.
    #[serde(default)]
    pub roll_rad: f64,
    pub joint_angles_rad: Vec<f64>,
}

impl Default for StartPose {
    fn default() -> Self {
        Self {
            head_m: [0.0, 0.0, 0.0],
            yaw_rad: std::f64::consts::PI,
            roll_rad: 0.0,
            joint_angles_rad: Vec::new(),
        }
    }
}

/// Everything in the world, explicit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// Flat ground at z = 0 (absent: the snake falls forever, useful only for tests).
    pub ground: bool,
    /// Skin friction against the ground, pegs, rocks and walls.
    pub friction: Friction,
    pub pegs: Vec<Peg>,
    pub poles: Vec<Pole>,
    pub rocks: Vec<Rock>,
    pub walls: Vec<Wall>,
    pub start: StartPose,
}

impl Default for WorldSpec {
    fn default() -> Self {
        Self {
            ground: true,
            friction: Friction::default(),
            pegs: Vec::new(),
            poles: Vec::new(),
            rocks: Vec::new(),
            walls: Vec::new(),
            start: StartPose::default(),
        }
    }
}
