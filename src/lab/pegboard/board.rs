//! The board a peg-board trial has to cross.
//!
//! A layout (`lab::layout`) is the experiment's board with its master seed set to
//! `seed_base + k` (a new random peg layout and new random starts for each `k`), or a
//! scenario file given as is. The board's region is the bounding box of the scenario's
//! `[[peg_board]]` regions and of every peg centre (for explicit layouts: the pegs'
//! bounding box).

use crate::emu::world::WorldSpec;
use crate::emu::world::scenario::{Region, WorldScenario};
use crate::lab::LabError;
use crate::lab::layout::Layout;

/// The experiment's default board (`scenarios/peg-board-40-inside.toml`: the thesis's
/// protocol, starts among the pegs), built in so the binary runs from any directory.
pub const PEG_BOARD_TOML: &str = include_str!("../../../scenarios/peg-board-40-inside.toml");

/// The same board with starts at its edge, the body behind it off the board
/// (`scenarios/peg-board-40.toml`).
pub const PEG_BOARD_EDGE_TOML: &str = include_str!("../../../scenarios/peg-board-40.toml");

/// The world of start `start` for `modules` modules and the board to cross in it.
pub fn board_world(
    layout: &Layout,
    modules: usize,
    start: u64,
) -> Result<(WorldSpec, Board), LabError> {
    let world = layout.scenario.generate_trial(modules, start)?;
    let region = board_region(&layout.scenario, &world).ok_or_else(|| LabError::NoBoard {
        layout: layout.name.clone(),
    })?;
    let board = Board::new(region, world.start.yaw_rad);
    Ok((world, board))
}

/// Bounding box of the scenario's peg-board regions and of the world's peg centres
/// (`None` when there is neither).
pub fn board_region(scenario: &WorldScenario, world: &WorldSpec) -> Option<Region> {
    let corners = scenario
        .peg_boards
        .iter()
        .flat_map(|b| {
            let r = b.region;
            [[r.x_m[0], r.y_m[0]], [r.x_m[1], r.y_m[1]]]
        })
        .chain(world.pegs.iter().map(|p| [p.x_m, p.y_m]));
    let mut bounds: Option<Region> = None;
    for [x, y] in corners {
        let r = bounds.get_or_insert(Region {
            x_m: [x, x],
            y_m: [y, y],
        });
        r.x_m = [r.x_m[0].min(x), r.x_m[1].max(x)];
        r.y_m = [r.y_m[0].min(y), r.y_m[1].max(y)];
    }
    bounds
}

/// An edge of the board's rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Edge {
    XMin,
    XMax,
    YMin,
    YMax,
}

impl Edge {
    const ALL: [Edge; 4] = [Edge::XMin, Edge::XMax, Edge::YMin, Edge::YMax];

    fn opposite(self) -> Edge {
        match self {
            Edge::XMin => Edge::XMax,
            Edge::XMax => Edge::XMin,
            Edge::YMin => Edge::YMax,
            Edge::YMax => Edge::YMin,
        }
    }

    fn outward_normal(self) -> [f64; 2] {
        match self {
            Edge::XMin => [-1.0, 0.0],
            Edge::XMax => [1.0, 0.0],
            Edge::YMin => [0.0, -1.0],
            Edge::YMax => [0.0, 1.0],
        }
    }
}

/// The board a trial crosses: its region and the edge the snake enters by.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Board {
    pub region: Region,
    /// The edge behind the start (the one whose outward normal is nearest the start's
    /// head-to-tail direction). Leaving by it is backing out, not crossing.
    pub entry: Edge,
}

impl Board {
    /// The board of `region` for a start whose head-to-tail direction is `tail_yaw_rad`.
    pub fn new(region: Region, tail_yaw_rad: f64) -> Self {
        let tail = [tail_yaw_rad.cos(), tail_yaw_rad.sin()];
        let score = |e: Edge| {
            let n = e.outward_normal();
            n[0] * tail[0] + n[1] * tail[1]
        };
        let entry =
            Edge::ALL.into_iter().fold(
                Edge::XMin,
                |best, e| if score(e) > score(best) { e } else { best },
            );
        Self { region, entry }
    }

    /// True when `p` lies beyond an edge other than the entry edge (the thesis ends a
    /// trial there: "the front half of the robot left the outer boundary of the pegs").
    pub fn crossed(&self, p: [f64; 2]) -> bool {
        self.exit(p).is_some()
    }

    /// Which way `p` has left the board: by the far edge (opposite the entry: across
    /// it), by a side, or not at all (inside, or back out by the entry edge).
    pub fn exit(&self, p: [f64; 2]) -> Option<Exit> {
        let r = &self.region;
        let beyond = |e: Edge| match e {
            Edge::XMin => p[0] < r.x_m[0],
            Edge::XMax => p[0] > r.x_m[1],
            Edge::YMin => p[1] < r.y_m[0],
            Edge::YMax => p[1] > r.y_m[1],
        };
        let far = self.entry.opposite();
        if beyond(far) {
            Some(Exit::Far)
        } else if Edge::ALL
            .into_iter()
            .any(|e| e != self.entry && e != far && beyond(e))
        {
            Some(Exit::Side)
        } else {
            None
        }
    }

    /// The board's forward direction, across it from the entry edge to the far one.
    pub fn forward(&self) -> [f64; 2] {
        let n = self.entry.outward_normal();
        [-n[0], -n[1]]
    }
}

/// How a trial left the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Across: by the edge opposite the entry (the experiment's success).
    Far,
    /// By one of the two side edges: the trial ends (as the thesis's did), not a crossing.
    Side,
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn board(yaw: f64) -> Board {
        Board::new(
            Region {
                x_m: [0.0, 2.0],
                y_m: [-0.6, 0.6],
            },
            yaw,
        )
    }

    #[test]
    fn entry_edge_is_behind_the_start() {
        // yaw = π: the tail points to −x, the snake faces +x and enters by x_min.
        assert_eq!(board(PI).entry, Edge::XMin);
        assert_eq!(board(PI + 0.3).entry, Edge::XMin);
        assert_eq!(board(0.0).entry, Edge::XMax);
        assert_eq!(board(PI / 2.0).entry, Edge::YMax);
        assert_eq!(board(-PI / 2.0).entry, Edge::YMin);
    }

    #[test]
    fn crossing_needs_an_edge_other_than_the_entry() {
        let b = board(PI);
        assert!(!b.crossed([1.0, 0.0]), "inside");
        assert!(
            !b.crossed([-0.3, 0.0]),
            "behind the entry edge: not crossed"
        );
        assert!(b.crossed([2.01, 0.0]), "beyond the far edge");
        assert!(b.crossed([1.0, 0.61]), "beyond a side");
        assert!(b.crossed([1.0, -0.61]), "beyond the other side");
    }

    #[test]
    fn only_the_far_edge_is_across_and_forward_points_to_it() {
        let b = board(PI);
        assert_eq!(b.exit([2.01, 0.0]), Some(Exit::Far));
        assert_eq!(
            b.exit([2.01, 0.7]),
            Some(Exit::Far),
            "a far corner is across"
        );
        assert_eq!(b.exit([1.0, 0.61]), Some(Exit::Side));
        assert_eq!(b.exit([1.0, -0.61]), Some(Exit::Side));
        assert_eq!(b.exit([-0.3, 0.0]), None, "backed out");
        assert_eq!(b.exit([1.0, 0.0]), None);
        assert_eq!(b.forward(), [1.0, 0.0]);
        let up = board(-PI / 2.0); // enters by y_min, crosses to y_max
        assert_eq!(up.forward(), [0.0, 1.0]);
        assert_eq!(up.exit([1.0, 0.61]), Some(Exit::Far));
        assert_eq!(up.exit([2.01, 0.0]), Some(Exit::Side));
    }

    #[test]
    fn the_experiment_board_region_is_its_peg_board() {
        let s = WorldScenario::parse(PEG_BOARD_TOML).unwrap();
        let l = Layout::seeded(&s, 1000);
        let (world, b) = board_world(&l, 18, 0).unwrap();
        assert_eq!(world.pegs.len(), 40);
        // The default starts among the pegs, the edge board at the edge; same pegs.
        assert!(
            (1.0..=1.3).contains(&world.start.head_m[0]),
            "{:?}",
            world.start
        );
        let edge = WorldScenario::parse(PEG_BOARD_EDGE_TOML).unwrap();
        let (edge_world, _) = board_world(&Layout::seeded(&edge, 1000), 18, 0).unwrap();
        assert_eq!(edge_world.pegs, world.pegs);
        assert!(edge_world.start.head_m[0] < 0.5);
        assert_eq!(b.region.x_m, [0.0, 2.0]);
        assert_eq!(b.region.y_m, [-0.6, 0.6]);
        assert_eq!(b.entry, Edge::XMin);
        // Another seed, another layout.
        let (other, _) = board_world(&Layout::seeded(&s, 1001), 18, 0).unwrap();
        assert_ne!(world.pegs, other.pegs);
    }

    #[test]
    fn explicit_pegs_give_their_bounding_box_and_no_pegs_no_board() {
        let s = WorldScenario::parse(
            "[[peg]]\nx_m = 0.5\ny_m = -0.2\ndiameter_m = 0.04\n\
             [[peg]]\nx_m = 1.5\ny_m = 0.3\ndiameter_m = 0.04\n\
             [start]\nhead_m = [0.2, 0.0]\n",
        )
        .unwrap();
        let w = s.generate(18).unwrap();
        let r = board_region(&s, &w).unwrap();
        assert_eq!((r.x_m, r.y_m), ([0.5, 1.5], [-0.2, 0.3]));
        let flat = WorldScenario::parse("").unwrap();
        let l = Layout {
            name: "flat".into(),
            scenario: flat,
            identity: 0,
        };
        assert!(matches!(
            board_world(&l, 18, 0),
            Err(LabError::NoBoard { .. })
        ));
    }
}
