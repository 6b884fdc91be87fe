//! Where a crossing trial starts: at the board's entry edge (the whole body before it)
//! or inside (the body's middle about 0.7-1.0 m in), lying along the direction of travel
//! (+x, facing it) or across it (facing +y: the way the sidewinding gait travels +x).
//! Position and yaw (±0.3 rad) are drawn per start from the layout's seed; a start
//! that touches an obstacle is drawn again (`emu::world::build`).

use std::f64::consts::FRAC_PI_2;

use crate::emu::world::scenario::{RandomStart, Region, StartGen};
use crate::module::MODULE_LENGTH_M;

/// Half the spread of the start's yaw, rad.
pub const YAW_SPREAD_RAD: f64 = 0.3;

/// One of the four starts; start `k` of a layout is `ALL[k % 4]`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
pub enum StartKind {
    AlongEdge,
    AlongInside,
    AcrossEdge,
    AcrossInside,
}

impl StartKind {
    pub const ALL: [StartKind; 4] = [
        StartKind::AlongEdge,
        StartKind::AlongInside,
        StartKind::AcrossEdge,
        StartKind::AcrossInside,
    ];

    pub fn of(start: u64) -> StartKind {
        Self::ALL[(start % 4) as usize]
    }

    pub fn name(self) -> &'static str {
        match self {
            StartKind::AlongEdge => "along-edge",
            StartKind::AlongInside => "along-inside",
            StartKind::AcrossEdge => "across-edge",
            StartKind::AcrossInside => "across-inside",
        }
    }

    pub fn inside(self) -> bool {
        matches!(self, StartKind::AlongInside | StartKind::AcrossInside)
    }

    fn across(self) -> bool {
        matches!(self, StartKind::AcrossEdge | StartKind::AcrossInside)
    }

    /// The random start of this kind on `board` for a body of `modules`.
    pub fn start_gen(self, board: &Region, modules: usize) -> StartGen {
        let half = modules as f64 * MODULE_LENGTH_M / 2.0;
        let x0 = board.x_m[0];
        let y_mid = 0.5 * (board.y_m[0] + board.y_m[1]);
        // Where the body's middle goes.
        let mid_x = match (self.inside(), self.across()) {
            (true, _) => [x0 + 0.7, x0 + 1.0],
            // Along: the head 6-12 cm before the edge.
            (false, false) => [x0 - 0.12 - half, x0 - 0.06 - half],
            // Across: the head 0.40-0.50 m before the edge, so the body, turned up to
            // 0.3 rad about it, stays 5 cm or more clear.
            (false, true) => [x0 - 0.50, x0 - 0.40],
        };
        let mid_y = [y_mid - 0.4, y_mid + 0.4];
        // The head is half a body ahead of the middle; yaw is head -> tail.
        let (head, yaw) = if self.across() {
            let y = [mid_y[0] + half, mid_y[1] + half];
            ((mid_x, y), -FRAC_PI_2)
        } else {
            (
                ([mid_x[0] + half, mid_x[1] + half], mid_y),
                std::f64::consts::PI,
            )
        };
        StartGen {
            random: Some(RandomStart {
                region: Region {
                    x_m: head.0,
                    y_m: head.1,
                },
                yaw_range_rad: [yaw - YAW_SPREAD_RAD, yaw + YAW_SPREAD_RAD],
                seed: None,
            }),
            ..StartGen::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::scenario::WorldScenario;

    #[test]
    fn starts_lie_where_their_kind_says() {
        let board = Region {
            x_m: [0.0, 2.0],
            y_m: [-1.5, 1.5],
        };
        let mut s = WorldScenario::parse("").unwrap();
        for (k, kind) in StartKind::ALL.into_iter().enumerate() {
            assert_eq!(StartKind::of(k as u64 + 4), kind);
            s.start = kind.start_gen(&board, 18);
            for trial in 0..20 {
                let w = s.generate_trial(18, trial).unwrap();
                let (sin, cos) = w.start.yaw_rad.sin_cos();
                let len = 18.0 * MODULE_LENGTH_M;
                let tail = [w.start.head_m[0] + cos * len, w.start.head_m[1] + sin * len];
                let mid_x = 0.5 * (w.start.head_m[0] + tail[0]);
                let max_x = w.start.head_m[0].max(tail[0]);
                if kind.inside() {
                    // 0.7-1.0 m for the nominal yaw; the yaw's spread moves it ±0.17 m.
                    assert!((0.52..=1.18).contains(&mid_x), "{kind:?} {mid_x}");
                } else {
                    assert!(
                        max_x < -0.05,
                        "{kind:?}: the body before the board, {max_x}"
                    );
                }
                // Facing: +x along, +y across (head -> tail is the opposite).
                let facing = if kind.across() {
                    [0.0, 1.0]
                } else {
                    [1.0, 0.0]
                };
                assert!(
                    -(cos * facing[0] + sin * facing[1]) > 0.95,
                    "{kind:?} yaw {}",
                    w.start.yaw_rad
                );
            }
        }
    }
}
