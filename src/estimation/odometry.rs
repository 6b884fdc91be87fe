//! Contact odometry: where the body has gone, from the assumption that the links
//! resting on the ground do not slip.
//!
//! The estimator knows every link's centre relative to the head in world axes (the
//! kinematics turned by the fused attitude), not where the head is. A gait that lifts
//! part of its body (sidewinding, rolling) sets the rest down and peels it off again
//! without sliding: those links stay put in the world, so the head moved by minus
//! their mean motion relative to it. Each cycle the lowest links are taken as the
//! ones on the ground, weighted by how close to the lowest they are. A body lying
//! flat (slithering) has every link "down" and they all slide: the estimate then holds
//! the centroid still, which is wrong by the body's true drift; [`ContactOdometry::lifted`]
//! says whether the last cycle had a lift to stand on.

use nalgebra::Vector3;

/// A link this much above the lowest is off the ground (weight 0); the weight falls
/// linearly from 1 at the lowest. Twice the height error a 1° tilt error makes over
/// half the body (18 links of 6.4 cm).
pub const CONTACT_BAND_M: f64 = 0.02;

/// The body is lifted when its highest link is this far above its lowest.
pub const LIFT_M: f64 = 0.03;

/// The odometry's state: the last links and where the head is.
#[derive(Debug, Clone)]
pub struct ContactOdometry {
    last: Vec<Vector3<f64>>,
    started: bool,
    head_m: Vector3<f64>,
    lifted: bool,
}

impl ContactOdometry {
    pub fn new(links: usize) -> Self {
        Self {
            last: vec![Vector3::zeros(); links],
            started: false,
            head_m: Vector3::zeros(),
            lifted: false,
        }
    }

    /// The head's position in the estimate's world frame (zero where it started).
    pub fn head_m(&self) -> Vector3<f64> {
        self.head_m
    }

    /// Whether the last update saw part of the body lifted (the estimate stands on
    /// contacts that stay put) rather than all of it down (it assumes no drift).
    pub fn lifted(&self) -> bool {
        self.lifted
    }

    /// The links were not seen for a while (an invalid estimate): the next update starts
    /// from its own links instead of integrating the gap.
    pub fn pause(&mut self) {
        self.started = false;
    }

    /// Advances with this cycle's link centres relative to the head, world axes (as
    /// many as at construction). No allocation.
    pub fn update(&mut self, links: &[Vector3<f64>]) {
        let (low, high) = links
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.z), hi.max(p.z))
            });
        if self.started {
            let mut moved = Vector3::zeros();
            let mut weight = 0.0;
            for (now, before) in links.iter().zip(&self.last) {
                let w = (1.0 - (now.z - low) / CONTACT_BAND_M).max(0.0);
                moved += w * (now - before);
                weight += w;
            }
            if weight > 0.0 {
                // Only the ground plane: the vertical follows the attitude.
                let d = -moved / weight;
                self.head_m += Vector3::new(d.x, d.y, 0.0);
            }
        }
        self.lifted = high - low >= LIFT_M;
        self.last.copy_from_slice(links);
        self.started = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_that_stay_down_carry_the_head_and_lifted_ones_do_not() {
        let mut o = ContactOdometry::new(3);
        // Relative to the head (link 0, lifted 5 cm), links 1 and 2 rest on the ground:
        // the head moves +x by 1 cm a cycle while they stay put, so relative to it they
        // move -x.
        let mut links = [
            Vector3::new(0.0, 0.0, 0.05),
            Vector3::new(0.1, 0.0, 0.0),
            Vector3::new(0.2, 0.0, 0.0),
        ];
        o.update(&links);
        for _ in 0..10 {
            for l in links[1..].iter_mut() {
                l.x -= 0.01;
            }
            o.update(&links);
        }
        // The head is the only link lifted: had it counted, the estimate would be short.
        assert!((o.head_m() - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12);
        assert!(o.lifted());
        // After a gap the links jump; paused, the jump is not taken for motion.
        o.pause();
        links[1].x += 0.3;
        o.update(&links);
        assert!((o.head_m() - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12);
    }
}
