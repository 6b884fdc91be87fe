//! The body as the gaits see it (`BodyLayout`): where the joints are, their plane
//! (lateral / dorsal) and normalised arc length. (A lab "layout" is one world of an
//! experiment: `lab::layout`.)

/// Joint plane. Neighbouring joints alternate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Plane {
    Lateral,
    Dorsal,
}

/// The body as the gaits see it. Joint 0 is nearest the head.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyLayout {
    /// Plane of each joint.
    pub planes: Vec<Plane>,
    /// Arc length of each joint from the head, normalised by body length (0..1).
    pub s: Vec<f64>,
    /// Length of one module, m.
    pub module_length_m: f64,
}

impl BodyLayout {
    /// `n` modules of `module_length_m` whose joint 0 lies in `first`; joint `i` sits at
    /// `s_i = (i + 1) / (n + 1)` (joints between modules, head and tail caps at the ends).
    pub fn alternating(n: usize, first: Plane, module_length_m: f64) -> Self {
        let planes = (0..n)
            .map(|i| match (i % 2 == 0, first) {
                (true, p) => p,
                (false, Plane::Lateral) => Plane::Dorsal,
                (false, Plane::Dorsal) => Plane::Lateral,
            })
            .collect();
        let s = (0..n)
            .map(|i| (i as f64 + 1.0) / (n as f64 + 1.0))
            .collect();
        BodyLayout {
            planes,
            s,
            module_length_m,
        }
    }

    pub fn len(&self) -> usize {
        self.planes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.planes.is_empty()
    }

    /// The length, m, that normalised arc length 1 stands for: one module length per
    /// mean joint spacing (`(n + 1) · l` for [`BodyLayout::alternating`]).
    pub fn body_length_m(&self) -> f64 {
        let n = self.s.len();
        if n >= 2 {
            let spacing = (self.s[n - 1] - self.s[0]) / (n as f64 - 1.0);
            if spacing.is_finite() && spacing > 0.0 {
                return self.module_length_m / spacing;
            }
        }
        (n as f64 + 1.0) * self.module_length_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alternating_layout_planes_and_body_length() {
        let l = BodyLayout::alternating(18, Plane::Lateral, 0.064);
        assert_eq!(l.len(), 18);
        assert_eq!(l.planes[0], Plane::Lateral);
        assert_eq!(l.planes[1], Plane::Dorsal);
        assert_eq!(l.planes[17], Plane::Dorsal);
        assert!((l.body_length_m() - 19.0 * 0.064).abs() < 1e-12);
        let one = BodyLayout::alternating(1, Plane::Dorsal, 0.05);
        assert!((one.body_length_m() - 0.1).abs() < 1e-12);
    }
}
