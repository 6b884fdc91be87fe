//! Where the body is according to an outside position source, as the body estimate
//! carries it (`BodyEstimate::fix`, `BodyEstimate::world`): the types only; the
//! estimators that fill them are `estimation::external_pose` and
//! `estimation::world_position`.

/// What the body estimate says of the external fixes.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FixState {
    /// Fixes the loop has taken (0: none yet).
    pub number: u64,
    /// The newest one's position in the source's world, m.
    pub position_m: [f64; 3],
    /// Its orientation (w, x, y, z), if the source gives one.
    pub orientation_wxyz: Option<[f64; 4]>,
    /// How old it is this cycle, s (loop time since it was measured; infinite: none).
    pub age_s: f64,
}

impl FixState {
    pub const NONE: FixState = FixState {
        number: 0,
        position_m: [0.0; 3],
        orientation_wxyz: None,
        age_s: f64::INFINITY,
    };
}

/// What the position is worth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionState {
    /// No fix yet (or no source).
    #[default]
    None,
    /// Fixes come, the worlds are not aligned yet.
    Aligning,
    /// Valid.
    Tracking,
    /// No fix accepted for `max_age_s`: not valid.
    Stale,
}

/// The chassis in the source's world.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct WorldPosition {
    pub state: PositionState,
    /// The chassis origin, m (meaningful while `Tracking`; the last one while `Stale`).
    pub position_m: [f64; 2],
    pub velocity_m_s: [f64; 2],
    /// The chassis' forward axis, rad.
    pub heading_rad: f64,
    /// The position's standard deviation now, m.
    pub sd_m: f64,
    /// Since the last accepted fix's measurement, s (infinite: none).
    pub age_s: f64,
    pub accepted: u64,
    pub rejected: u64,
    /// Fixes measured before the history began.
    pub late: u64,
    pub alignments: u64,
    /// ψ: the source's world is the estimate's turned by this, rad.
    pub yaw_offset_rad: f64,
}

impl WorldPosition {
    pub const NONE: WorldPosition = WorldPosition {
        state: PositionState::None,
        position_m: [0.0; 2],
        velocity_m_s: [0.0; 2],
        heading_rad: 0.0,
        sd_m: f64::INFINITY,
        age_s: f64::INFINITY,
        accepted: 0,
        rejected: 0,
        late: 0,
        alignments: 0,
        yaw_offset_rad: 0.0,
    };

    /// Whether the position may be steered by.
    pub fn valid(&self) -> bool {
        self.state == PositionState::Tracking
    }
}
