//! Sigmoid activation windows (SPEC §4): a smooth rectangle over `[a, b]` in
//! normalised arc length,
//! `w(s) = 1/(1+e^{−m(s−a)}) + 1/(1+e^{m(s−b)}) − 1`,
//! and its integral from the head, which the integrated wave phase needs.

/// One window's edges in normalised arc length. `a = −∞` / `b = +∞` leave that side
/// open (the head's and tail's windows, and a central parameter's window).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    pub a: f64,
    pub b: f64,
}

/// Beyond this |x| the logistic is 0 or 1 and softplus 0 or x to within 2e-16: far
/// windows then cost no transcendental functions.
pub(super) const SATURATED: f64 = 36.0;

/// `ln(1 + e^x)` without overflow.
#[inline]
fn softplus(x: f64) -> f64 {
    if x > SATURATED {
        x
    } else if x < -SATURATED {
        0.0
    } else {
        x.max(0.0) + (-x.abs()).exp().ln_1p()
    }
}

#[inline]
fn logistic(x: f64) -> f64 {
    if x > SATURATED {
        1.0
    } else if x < -SATURATED {
        0.0
    } else if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

impl Window {
    /// The whole body (a centralised parameter).
    pub const EVERYWHERE: Window = Window {
        a: f64::NEG_INFINITY,
        b: f64::INFINITY,
    };

    /// Weight at `s` for edge steepness `m` (per unit of normalised arc length).
    #[inline]
    pub fn weight(&self, s: f64, m: f64) -> f64 {
        let left = if self.a.is_finite() {
            logistic(m * (s - self.a))
        } else {
            1.0
        };
        let right = if self.b.is_finite() {
            logistic(m * (self.b - s))
        } else {
            1.0
        };
        left + right - 1.0
    }

    /// `∫₀^s w(u) du`.
    #[inline]
    pub fn integral(&self, s: f64, m: f64) -> f64 {
        // ∫ logistic(m(u−a)) du = softplus(m(u−a))/m; ∫ logistic(m(b−u)) du = −softplus(m(b−u))/m.
        let left = if self.a.is_finite() {
            (softplus(m * (s - self.a)) - softplus(-m * self.a)) / m
        } else {
            s
        };
        let right = if self.b.is_finite() {
            (softplus(m * self.b) - softplus(m * (self.b - s))) / m
        } else {
            s
        };
        left + right - s
    }
}

/// Steepness for an edge about `width` wide (10 % to 90 % of the step) in normalised
/// arc length: `m = 2·ln 9 / width`.
pub fn steepness_for_width(width: f64) -> f64 {
    2.0 * 9f64.ln() / width
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_is_a_smooth_rectangle_and_neighbours_sum_to_one() {
        let m = steepness_for_width(0.5 / 19.0);
        let w = Window { a: 0.2, b: 0.5 };
        assert!(w.weight(0.35, m) > 0.999);
        assert!(w.weight(0.1, m) < 1e-3 && w.weight(0.6, m) < 1e-3);
        assert!((w.weight(0.2, m) - 0.5).abs() < 1e-9);
        let next = Window { a: 0.5, b: 0.8 };
        let head = Window {
            a: f64::NEG_INFINITY,
            b: 0.2,
        };
        let tail = Window {
            a: 0.8,
            b: f64::INFINITY,
        };
        for k in 0..=100 {
            let s = k as f64 / 100.0;
            let sum: f64 = [head, w, next, tail].iter().map(|x| x.weight(s, m)).sum();
            assert!((sum - 1.0).abs() < 1e-9, "s {s}: {sum}");
        }
    }

    #[test]
    fn integral_matches_quadrature() {
        let m = 60.0;
        for w in [
            Window { a: 0.2, b: 0.5 },
            Window { a: -0.1, b: 0.3 },
            Window {
                a: 0.7,
                b: f64::INFINITY,
            },
            Window {
                a: f64::NEG_INFINITY,
                b: 0.4,
            },
            Window::EVERYWHERE,
        ] {
            let n = 20_000;
            let mut acc = 0.0;
            for k in 0..n {
                let u = (k as f64 + 0.5) / n as f64;
                acc += w.weight(u, m) / n as f64;
                if (k + 1) % 5000 == 0 {
                    let s = (k + 1) as f64 / n as f64;
                    assert!((w.integral(s, m) - acc).abs() < 1e-6, "{w:?} at {s}");
                }
            }
        }
    }
}
