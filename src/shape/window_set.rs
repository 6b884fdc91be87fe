//! Windows made ready for evaluation (SPEC §4): a field's windows at one steepness,
//! evaluated at a point or at many with as few `exp` and `ln_1p` as possible, and to
//! the bit the values [`Window::weight`] and [`Window::integral`] give.

use super::window::{SATURATED, Window};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::window::steepness_for_width;

    /// Shared and separate edges, open sides, saturated and not, points beyond the body.
    #[test]
    fn pointwise_and_column_sampling_give_the_windows_values_to_the_bit() {
        let m = steepness_for_width(0.5 / 19.0);
        let windows = [
            Window {
                a: f64::NEG_INFINITY,
                b: 0.1,
            },
            Window { a: 0.1, b: 0.42 },
            Window { a: 0.45, b: 0.47 },
            Window { a: 0.47, b: 1.3 },
            Window {
                a: 1.3,
                b: f64::INFINITY,
            },
            Window::EVERYWHERE,
        ];
        let mut set = WindowSet::new(m, windows.len());
        set.set(windows);
        let s: Vec<f64> = (0..60).map(|i| -0.1 + i as f64 / 50.0).collect();
        let cells = s.len() * windows.len();
        let (mut weight, mut integral) = (vec![0.0; cells], vec![0.0; cells]);
        set.sample_columns(
            &s,
            &mut EdgeColumns::new(s.len()),
            &mut weight,
            &mut integral,
        );
        let values: Vec<f64> = (0..windows.len()).map(|j| 0.3 + j as f64).collect();
        for (i, &s_i) in s.iter().enumerate() {
            let mut expected_sum = 0.0;
            set.sample(s_i, |j, w, int| {
                let window = &windows[j];
                assert_eq!(w, window.weight(s_i, m), "{window:?} at {s_i}");
                assert_eq!(int, window.integral(s_i, m), "{window:?} at {s_i}");
                assert_eq!(weight[j * s.len() + i], w);
                assert_eq!(integral[j * s.len() + i], int);
                expected_sum += values[j] * w;
            });
            assert_eq!(set.weighted_sum(&values, s_i), expected_sum);
        }
    }
}
