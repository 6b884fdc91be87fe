//! The window manager (SPEC §4): travelling half-wave windows anchored to the wave's
//! zero crossings (`φ = kπ`). Window `k` covers `φ ∈ [kπ, (k+1)π]`; as the phase runs,
//! a new window is born at the head (with the caller's nominal payload) and the one that
//! passes off the tail is dropped with its payload; when the local spatial frequency
//! changes, the crossings move, so windows resize, shift and change in number.
//! Head and tail windows are open-ended so the body is always covered.

use std::collections::VecDeque;

use super::window::Window;

/// One travelling window: its half-wave index, edges, and what the caller keeps in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Travelling<T> {
    pub k: i64,
    pub window: Window,
    pub payload: T,
}

/// Counts of what the last update did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WindowEvents {
    pub born_at_head: usize,
    pub dropped_at_tail: usize,
    pub born_at_tail: usize,
    pub dropped_at_head: usize,
}

/// What the caller knows of φ along the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slope {
    /// φ increases from head to tail: the cell a crossing lies in is found by a short
    /// search from where that crossing was (the cell a scan from the head would stop in).
    Increasing,
    /// Anything: the grid is scanned from the head.
    Unknown,
}

/// Windows head to tail. Capacity fixed at construction: updates allocate nothing.
#[derive(Debug, Clone)]
pub struct WindowManager<T> {
    windows: VecDeque<Travelling<T>>,
    grid: Grid,
    capacity: usize,
}

impl<T: Copy> WindowManager<T> {
    /// `grid_points` samples of the phase along the body (a few per joint) locate the
    /// crossings; at most `capacity` windows.
    pub fn new(grid_points: usize, capacity: usize) -> Self {
        Self {
            windows: VecDeque::with_capacity(capacity),
            grid: Grid::new(grid_points.max(2)),
            capacity,
        }
    }

    pub fn windows(&self) -> impl ExactSizeIterator<Item = &Travelling<T>> + '_ {
        self.windows.iter()
    }

    pub fn windows_mut(&mut self) -> impl Iterator<Item = &mut Travelling<T>> + '_ {
        self.windows.iter_mut()
    }

    pub fn payloads_mut(&mut self) -> impl Iterator<Item = &mut T> + '_ {
        self.windows.iter_mut().map(|w| &mut w.payload)
    }

    pub fn len(&self) -> usize {
        self.windows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.windows.is_empty()
    }

    pub fn clear(&mut self) {
        self.windows.clear();
    }

    /// Re-anchors the windows to the crossings of `phase_at` (φ along the body, meant to
    /// increase from head to tail; `slope` says whether it is known to); new windows get
    /// `nominal`. Only the grid points the search needs are evaluated.
    pub fn update(
        &mut self,
        phase_at: impl Fn(f64) -> f64,
        nominal: T,
        slope: Slope,
    ) -> WindowEvents {
        let mut ev = WindowEvents::default();
        let grid = &mut self.grid;
        grid.next_update();
        let g = grid.len();
        let pi = std::f64::consts::PI;
        let k_head = (grid.at(0, &phase_at) / pi).floor() as i64;
        let k_tail = (grid.at(g - 1, &phase_at) / pi).floor() as i64;
        let k_tail = k_tail.max(k_head).min(k_head + self.capacity as i64 - 1);
        // Drop what left the body, then add what entered, at each end.
        while self.windows.front().is_some_and(|w| w.k < k_head) {
            self.windows.pop_front();
            ev.dropped_at_head += 1;
        }
        while self.windows.back().is_some_and(|w| w.k > k_tail) {
            self.windows.pop_back();
            ev.dropped_at_tail += 1;
        }
        if self.windows.is_empty() {
            for k in k_head..=k_tail {
                self.windows.push_back(Travelling {
                    k,
                    window: Window::EVERYWHERE,
                    payload: nominal,
                });
            }
        }
        while let Some(front) = self.windows.front().map(|w| w.k).filter(|&k| k > k_head) {
            self.windows.push_front(Travelling {
                k: front - 1,
                window: Window::EVERYWHERE,
                payload: nominal,
            });
            ev.born_at_head += 1;
        }
        while let Some(back) = self.windows.back().map(|w| w.k).filter(|&k| k < k_tail) {
            self.windows.push_back(Travelling {
                k: back + 1,
                window: Window::EVERYWHERE,
                payload: nominal,
            });
            ev.born_at_tail += 1;
        }
        // Edges at the crossings φ = kπ between neighbours.
        let last = self.windows.len() - 1;
        let mut cursor = 0;
        for idx in 0..=last {
            let Travelling { k, window, .. } = self.windows[idx];
            let a = if idx == 0 {
                f64::NEG_INFINITY
            } else {
                self.windows[idx - 1].window.b
            };
            let b = if idx == last {
                f64::INFINITY
            } else {
                let target = (k + 1) as f64 * pi;
                cursor = match slope {
                    Slope::Unknown => grid.scan(cursor, target, &phase_at),
                    Slope::Increasing => {
                        // Where this edge was (a new window has none).
                        let was = (window.b * (g - 1) as f64).floor();
                        let hint = if was.is_finite() { was as usize } else { 0 };
                        let hint = hint.clamp(cursor, g - 2);
                        grid.search(cursor, hint, target, &phase_at)
                    }
                };
                grid.crossing(cursor, target, &phase_at)
            };
            self.windows[idx].window = Window { a, b };
        }
        ev
    }
}

/// φ at `g` evenly spaced points from head (s = 0) to tail (s = 1), each evaluated when
/// an update first asks for it.
#[derive(Debug, Clone)]
struct Grid {
    phase: Vec<f64>,
    /// The update in which each point was last evaluated.
    evaluated: Vec<u64>,
    update: u64,
}

impl Grid {
    fn new(g: usize) -> Self {
        Self {
            phase: vec![0.0; g],
            evaluated: vec![0; g],
            update: 0,
        }
    }

    fn len(&self) -> usize {
        self.phase.len()
    }

    fn next_update(&mut self) {
        self.update += 1;
    }

    fn s(&self, k: usize) -> f64 {
        k as f64 / (self.len() - 1) as f64
    }

    fn at(&mut self, k: usize, phase_at: &impl Fn(f64) -> f64) -> f64 {
        if self.evaluated[k] != self.update {
            self.phase[k] = phase_at(self.s(k));
            self.evaluated[k] = self.update;
        }
        self.phase[k]
    }

    /// Does cell `c` (points `c`, `c + 1`) reach `target`? The last cell always does.
    fn reaches(&mut self, c: usize, target: f64, phase_at: &impl Fn(f64) -> f64) -> bool {
        c + 2 >= self.len() || {
            let below = self.at(c + 1, phase_at) < target;
            !below
        }
    }

    /// The first cell from `from` that reaches `target`, walking.
    fn scan(&mut self, from: usize, target: f64, phase_at: &impl Fn(f64) -> f64) -> usize {
        let mut c = from;
        while !self.reaches(c, target, phase_at) {
            c += 1;
        }
        c
    }

    /// What [`Self::scan`] finds when φ increases: galloping out from `hint` to bracket
    /// the first reaching cell, then bisecting, so a crossing that moved less than a cell
    /// costs two evaluations.
    fn search(
        &mut self,
        from: usize,
        hint: usize,
        target: f64,
        phase_at: &impl Fn(f64) -> f64,
    ) -> usize {
        // `no` does not reach (or is `from − 1`), `yes` reaches.
        let (mut no, mut yes) = (None, hint);
        let mut step = 1;
        if self.reaches(hint, target, phase_at) {
            while no.is_none() && yes > from {
                let probe = yes.saturating_sub(step).max(from);
                if self.reaches(probe, target, phase_at) {
                    yes = probe;
                } else {
                    no = Some(probe);
                }
                step *= 2;
            }
        } else {
            no = Some(hint);
            yes = loop {
                let probe = (no.unwrap() + step).min(self.len() - 2);
                if self.reaches(probe, target, phase_at) {
                    break probe;
                }
                no = Some(probe);
                step *= 2;
            };
        }
        let Some(mut no) = no else { return yes };
        while yes - no > 1 {
            let mid = no + (yes - no) / 2;
            if self.reaches(mid, target, phase_at) {
                yes = mid;
            } else {
                no = mid;
            }
        }
        yes
    }

    /// Where φ crosses `target` in cell `c`, interpolated linearly.
    fn crossing(&mut self, c: usize, target: f64, phase_at: &impl Fn(f64) -> f64) -> f64 {
        let (p0, p1) = (self.at(c, phase_at), self.at(c + 1, phase_at));
        let (s0, s1) = (self.s(c), self.s(c + 1));
        if (p1 - p0).abs() > 1e-12 {
            s0 + (target - p0) / (p1 - p0) * (s1 - s0)
        } else {
            s1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// φ(s) = ωS·s − Ω for a uniform wave.
    fn uniform(ws: f64, omega: f64) -> impl Fn(f64) -> f64 {
        move |s| ws * s - omega
    }

    #[test]
    fn windows_cover_half_waves_and_travel_tailwards() {
        let mut m: WindowManager<u32> = WindowManager::new(200, 16);
        m.update(uniform(3.0 * PI, 0.3), 0, Slope::Increasing);
        // 1.5 waves → 3 half waves, partly 4 windows on the body.
        assert_eq!(m.len(), 4);
        let inner: Vec<Window> = m.windows().map(|w| w.window).collect();
        for w in &inner[1..inner.len() - 1] {
            assert!(((w.b - w.a) - 1.0 / 3.0).abs() < 1e-6, "{w:?}");
        }
        // Edge between windows 0 and 1 at φ = kπ: s = (kπ + Ω)/ωS.
        let e = inner[0].b;
        assert!(((3.0 * PI * e - 0.3) / PI - (3.0 * PI * e - 0.3) / PI).abs() < 1e-12);
        assert!(
            ((3.0 * PI * e - 0.3).rem_euclid(PI)).min(PI - (3.0 * PI * e - 0.3).rem_euclid(PI))
                < 1e-3
        );
        // As Ω grows the edges move towards the tail.
        m.update(uniform(3.0 * PI, 0.6), 0, Slope::Increasing);
        assert!(m.windows().next().unwrap().window.b > e);
    }

    #[test]
    fn windows_are_born_at_the_head_with_nominal_and_dropped_at_the_tail_with_state() {
        let mut m: WindowManager<u32> = WindowManager::new(200, 16);
        m.update(uniform(3.0 * PI, 0.1), 7, Slope::Increasing);
        for p in m.payloads_mut() {
            *p = 99; // state learnt from terrain
        }
        let mut born = 0;
        let mut dropped = 0;
        let mut omega = 0.1;
        while born == 0 {
            omega += 0.01;
            let ev = m.update(uniform(3.0 * PI, omega), 7, Slope::Increasing);
            born += ev.born_at_head;
            dropped += ev.dropped_at_tail;
        }
        assert_eq!(
            m.windows().next().unwrap().payload,
            7,
            "new head window is nominal"
        );
        assert!(m.windows().skip(1).all(|w| w.payload == 99));
        // Run on until the body has seen two waves pass: every learnt window has left at
        // the tail (one half wave per π of phase).
        while omega < 0.1 + 4.5 * PI {
            omega += 0.01;
            dropped += m
                .update(uniform(3.0 * PI, omega), 7, Slope::Increasing)
                .dropped_at_tail;
        }
        assert!(dropped >= 4, "{dropped}");
        assert!(m.windows().all(|w| w.payload == 7));
    }

    #[test]
    fn a_higher_local_spatial_frequency_shrinks_its_window_and_pulls_the_rest_forward() {
        let mut m: WindowManager<()> = WindowManager::new(400, 16);
        m.update(uniform(3.0 * PI, 0.0), (), Slope::Increasing);
        let before: Vec<f64> = m.windows().map(|w| w.window.b).collect();
        // ωS = 4π over the front third, 3π behind (phase continuous).
        let front = |s: f64| {
            if s < 1.0 / 3.0 {
                4.0 * PI * s
            } else {
                4.0 * PI / 3.0 + 3.0 * PI * (s - 1.0 / 3.0)
            }
        };
        m.update(front, (), Slope::Increasing);
        let after: Vec<f64> = m.windows().map(|w| w.window.b).collect();
        assert!(after[0] < before[0] - 0.05, "{before:?} -> {after:?}");
        assert!(after.len() >= before.len());
    }

    /// For increasing phases the search near the last edges finds what the scan finds,
    /// to the bit, while the wave runs either way, speeds up and changes shape.
    #[test]
    fn searching_near_the_last_edges_finds_what_a_scan_finds() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for grid in [2, 5, 27, 1033] {
            let mut near: WindowManager<u32> = WindowManager::new(grid, 16);
            let mut scan = near.clone();
            // φ(s) = Σ slope_j over [j/4, (j+1)/4] up to s, − Ω.
            let (mut slopes, mut omega) = ([3.0 * PI; 4], 0.0);
            for step in 0..4000 {
                for w in &mut slopes {
                    *w = (*w + 0.4 * (uniform() - 0.5)).clamp(0.25 * PI, 8.0 * PI);
                }
                omega += match step % 500 {
                    0 => 2.0 * (uniform() - 0.5), // a jump
                    k if k < 250 => 0.05 * uniform(),
                    _ => -0.05 * uniform(),
                };
                let phase = |s: f64| {
                    let whole = (4.0 * s).floor().clamp(0.0, 3.0) as usize;
                    let below: f64 = slopes[..whole].iter().sum::<f64>() * 0.25;
                    below + slopes[whole] * (s - 0.25 * whole as f64) - omega
                };
                let a = near.update(phase, 1, Slope::Increasing);
                let b = scan.update(phase, 1, Slope::Unknown);
                assert_eq!(a, b, "grid {grid} step {step}");
                let edges = |m: &WindowManager<u32>| -> Vec<(i64, Window)> {
                    m.windows().map(|w| (w.k, w.window)).collect()
                };
                assert_eq!(edges(&near), edges(&scan), "grid {grid} step {step}");
            }
        }
    }
}
