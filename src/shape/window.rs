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
const SATURATED: f64 = 36.0;

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

/// Logistic and softplus terms at a point. Of one finite edge at `x`, with
/// `y = m(s − x)`: `rise` and `softplus_rise` of `y` (for the window that starts there),
/// `fall` and `softplus_fall` of `−y` (for the one that ends there), from one `exp` and
/// one `ln_1p` (none when saturated), to the bit what [`Window::weight`] and
/// [`Window::integral`] compute. Of a window: its left edge's rise, its right edge's fall.
#[derive(Debug, Clone, Copy)]
struct Terms {
    rise: f64,
    fall: f64,
    softplus_rise: f64,
    softplus_fall: f64,
}

impl Terms {
    /// An open side: logistic 1 (its softplus is not used).
    const OPEN: Terms = Terms::new(1.0, 1.0, 0.0, 0.0);

    /// With `softplus` false only the logistics are computed (the softplus terms are 0).
    #[inline]
    fn edge(y: f64, softplus: bool) -> Self {
        let sp = |x: f64| if softplus { x } else { 0.0 };
        if y > SATURATED {
            Terms::new(1.0, 0.0, sp(y), 0.0)
        } else if y < -SATURATED {
            Terms::new(0.0, 1.0, 0.0, sp(-y))
        } else {
            let e = (-y.abs()).exp();
            let (near, far) = (1.0 / (1.0 + e), e / (1.0 + e));
            let (rise, fall) = if y >= 0.0 { (near, far) } else { (far, near) };
            let l = sp(e.ln_1p());
            Terms::new(rise, fall, sp(y.max(0.0)) + l, sp((-y).max(0.0)) + l)
        }
    }

    /// A window's weight and integral from its terms and its edges' softplus at the head.
    #[inline]
    fn values(self, w: &Window, (head_a, head_b): (f64, f64), m: f64, s: f64) -> (f64, f64) {
        let left = if w.a.is_finite() {
            (self.softplus_rise - head_a) / m
        } else {
            s
        };
        let right = if w.b.is_finite() {
            (head_b - self.softplus_fall) / m
        } else {
            s
        };
        (self.rise + self.fall - 1.0, left + right - s)
    }

    /// The edge at `x` (open when infinite) seen from `s`.
    #[inline]
    fn at(x: f64, s: f64, m: f64, softplus: bool) -> Self {
        if x.is_finite() {
            Terms::edge(m * (s - x), softplus)
        } else {
            Terms::OPEN
        }
    }

    /// Of a window: its left edge's rise, its right edge's fall.
    #[inline]
    fn window(left: &Terms, right: &Terms) -> Terms {
        Terms {
            fall: right.fall,
            softplus_fall: right.softplus_fall,
            ..*left
        }
    }

    const fn new(rise: f64, fall: f64, softplus_rise: f64, softplus_fall: f64) -> Self {
        Self {
            rise,
            fall,
            softplus_rise,
            softplus_fall,
        }
    }
}

/// Windows made ready for evaluation at one steepness: the integrals' constants (each
/// edge's softplus at the head) are computed once, and an edge two neighbours share is
/// evaluated once per point.
#[derive(Debug, Clone)]
pub struct WindowSet {
    windows: Vec<Window>,
    /// Per window, `softplus(−m·a)` and `softplus(m·b)` (unused on an open side).
    head: Vec<(f64, f64)>,
    m: f64,
}

impl WindowSet {
    /// The whole body, room for `capacity` windows.
    pub fn new(m: f64, capacity: usize) -> Self {
        let mut set = Self {
            windows: Vec::with_capacity(capacity),
            head: Vec::with_capacity(capacity),
            m,
        };
        set.set([Window::EVERYWHERE]);
        set
    }

    /// Replaces the windows (no allocation within the capacity).
    pub fn set(&mut self, windows: impl IntoIterator<Item = Window>) {
        self.windows.clear();
        self.windows.extend(windows);
        let mut head = std::mem::take(&mut self.head);
        head.clear();
        self.each(0.0, true, |_, _, t| {
            head.push((t.softplus_rise, t.softplus_fall))
        });
        self.head = head;
    }

    /// Becomes a copy of `other` (no allocation within the capacity).
    pub fn copy_from(&mut self, other: &WindowSet) {
        self.windows.clear();
        self.windows.extend_from_slice(&other.windows);
        self.head.clear();
        self.head.extend_from_slice(&other.head);
        self.m = other.m;
    }

    pub fn windows(&self) -> &[Window] {
        &self.windows
    }

    /// `f(j, w_j(s), ∫₀^s w_j)` for each window in order.
    #[inline]
    pub fn sample(&self, s: f64, mut f: impl FnMut(usize, f64, f64)) {
        self.each(s, true, |j, w, t| {
            let (weight, integral) = t.values(w, self.head[j], self.m, s);
            f(j, weight, integral);
        });
    }

    /// [`Self::sample`] at every point of `s` at once, window by window: window `j` at
    /// `s[i]` into `weight[j·n + i]` and `integral[j·n + i]` (`n` points). Each edge is
    /// evaluated once over all points; the values are the same to the bit.
    pub fn sample_columns(
        &self,
        s: &[f64],
        edges: &mut EdgeColumns,
        weight: &mut [f64],
        integral: &mut [f64],
    ) {
        let (m, n) = (self.m, s.len());
        let EdgeColumns { left, right } = edges;
        let mut shared = f64::NAN; // the previous window's right edge, now in `left`
        let columns = weight
            .chunks_exact_mut(n.max(1))
            .zip(integral.chunks_exact_mut(n.max(1)));
        for ((w, &head), (weight, integral)) in self.windows.iter().zip(&self.head).zip(columns) {
            if w.a != shared {
                edge_column(left, s, w.a, m);
            }
            edge_column(right, s, w.b, m);
            let cells = weight.iter_mut().zip(integral.iter_mut());
            for (((weight, integral), (l, r)), &s) in
                cells.zip(left.iter().zip(right.iter())).zip(s)
            {
                (*weight, *integral) = Terms::window(l, r).values(w, head, m, s);
            }
            std::mem::swap(left, right);
            shared = w.b;
        }
    }

    /// `Σ_j values_j·w_j(s)`.
    #[inline]
    pub fn weighted_sum(&self, values: &[f64], s: f64) -> f64 {
        let mut sum = 0.0;
        self.each(s, false, |j, _, t| {
            sum += values[j] * (t.rise + t.fall - 1.0)
        });
        sum
    }

    /// `f(j, window, terms)` of each window at `s`; an edge shared with the previous
    /// window is evaluated once.
    #[inline]
    fn each(&self, s: f64, softplus: bool, mut f: impl FnMut(usize, &Window, Terms)) {
        let m = self.m;
        // The previous window's right edge.
        let (mut shared, mut prev) = (f64::NAN, Terms::OPEN);
        for (j, w) in self.windows.iter().enumerate() {
            let left = if w.a == shared {
                prev
            } else {
                Terms::at(w.a, s, m, softplus)
            };
            let right = Terms::at(w.b, s, m, softplus);
            (shared, prev) = (w.b, right);
            f(j, w, Terms::window(&left, &right));
        }
    }
}

/// Room for one edge's terms at each of a fixed number of points, twice (the left and
/// right edges of a window), for [`WindowSet::sample_columns`].
#[derive(Debug, Clone)]
pub struct EdgeColumns {
    left: Vec<Terms>,
    right: Vec<Terms>,
}

impl EdgeColumns {
    pub fn new(points: usize) -> Self {
        Self {
            left: vec![Terms::OPEN; points],
            right: vec![Terms::OPEN; points],
        }
    }
}

/// The terms of the edge at `x` at each point of `s`.
fn edge_column(out: &mut [Terms], s: &[f64], x: f64, m: f64) {
    for (t, &s) in out.iter_mut().zip(s) {
        *t = Terms::at(x, s, m, true);
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
