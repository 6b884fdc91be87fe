//! Where the body truly is, from the emulator's links: what the lab's goals, metrics
//! and checks measure against (the estimate never sees it).

use crate::emu::Plant;

/// Mean ground-plane position of the links (the body's geometric centre), m.
pub fn centre(plant: &dyn Plant) -> [f64; 2] {
    let n = plant.link_count().max(1);
    let mut c = [0.0, 0.0];
    for k in 0..plant.link_count() {
        let p = plant.link_pose(k).position_m;
        c = [c[0] + p[0], c[1] + p[1]];
    }
    [c[0] / n as f64, c[1] / n as f64]
}

/// Ground-plane positions of the links, head first, m.
pub(crate) fn links(plant: &dyn Plant) -> Vec<[f64; 2]> {
    (0..plant.link_count())
        .map(|k| ground(plant.link_pose(k).position_m))
        .collect()
}

pub(crate) fn ground([x, y, _]: [f64; 3]) -> [f64; 2] {
    [x, y]
}

/// Mean ground-plane position of the front half of the links (`0 .. links/2`), m.
pub fn front_half_centre(plant: &dyn Plant) -> [f64; 2] {
    front_half_of((0..plant.link_count()).map(|k| {
        let p = plant.link_pose(k).position_m;
        [p[0], p[1]]
    }))
}

/// The front half's centre of link positions given head first (as recorded).
pub fn front_half_of(links: impl ExactSizeIterator<Item = [f64; 2]>) -> [f64; 2] {
    let half = (links.len() / 2).max(1);
    let mut c = [0.0, 0.0];
    for p in links.take(half) {
        c = [c[0] + p[0], c[1] + p[1]];
    }
    [c[0] / half as f64, c[1] / half as f64]
}
