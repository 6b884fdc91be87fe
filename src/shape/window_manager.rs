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

/// Windows head to tail. Capacity fixed at construction: updates allocate nothing.
#[derive(Debug, Clone)]
pub struct WindowManager<T> {
    windows: VecDeque<Travelling<T>>,
    grid_s: Vec<f64>,
    grid_phase: Vec<f64>,
    capacity: usize,
}

impl<T: Copy> WindowManager<T> {
    /// `grid_points` samples of the phase along the body (a few per joint) locate the
    /// crossings; at most `capacity` windows.
    pub fn new(grid_points: usize, capacity: usize) -> Self {
        let g = grid_points.max(2);
        Self {
            windows: VecDeque::with_capacity(capacity),
            grid_s: (0..g).map(|k| k as f64 / (g - 1) as f64).collect(),
            grid_phase: vec![0.0; g],
            capacity,
        }
    }

    pub fn windows(&self) -> impl ExactSizeIterator<Item = &Travelling<T>> + '_ {
        self.windows.iter()
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

    /// Re-anchors the windows to the crossings of `phase_at` (φ along the body,
    /// increasing from head to tail); new windows get `nominal`.
    pub fn update(&mut self, phase_at: impl Fn(f64) -> f64, nominal: T) -> WindowEvents {
        let mut ev = WindowEvents::default();
        for (p, &s) in self.grid_phase.iter_mut().zip(&self.grid_s) {
            *p = phase_at(s);
        }
        let g = self.grid_phase.len();
        let pi = std::f64::consts::PI;
        let k_head = (self.grid_phase[0] / pi).floor() as i64;
        let k_tail = (self.grid_phase[g - 1] / pi).floor() as i64;
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
            let k = self.windows[idx].k;
            let a = if idx == 0 {
                f64::NEG_INFINITY
            } else {
                self.windows[idx - 1].window.b
            };
            let b = if idx == last {
                f64::INFINITY
            } else {
                let target = (k + 1) as f64 * pi;
                while cursor + 2 < g && self.grid_phase[cursor + 1] < target {
                    cursor += 1;
                }
                let (p0, p1) = (self.grid_phase[cursor], self.grid_phase[cursor + 1]);
                let (s0, s1) = (self.grid_s[cursor], self.grid_s[cursor + 1]);
                if (p1 - p0).abs() > 1e-12 {
                    s0 + (target - p0) / (p1 - p0) * (s1 - s0)
                } else {
                    s1
                }
            };
            self.windows[idx].window = Window { a, b };
        }
        ev
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
        m.update(uniform(3.0 * PI, 0.3), 0);
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
        m.update(uniform(3.0 * PI, 0.6), 0);
        assert!(m.windows().next().unwrap().window.b > e);
    }

    #[test]
    fn windows_are_born_at_the_head_with_nominal_and_dropped_at_the_tail_with_state() {
        let mut m: WindowManager<u32> = WindowManager::new(200, 16);
        m.update(uniform(3.0 * PI, 0.1), 7);
        for p in m.payloads_mut() {
            *p = 99; // state learnt from terrain
        }
        let mut born = 0;
        let mut dropped = 0;
        let mut omega = 0.1;
        while born == 0 {
            omega += 0.01;
            let ev = m.update(uniform(3.0 * PI, omega), 7);
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
            dropped += m.update(uniform(3.0 * PI, omega), 7).dropped_at_tail;
        }
        assert!(dropped >= 4, "{dropped}");
        assert!(m.windows().all(|w| w.payload == 7));
    }

    #[test]
    fn a_higher_local_spatial_frequency_shrinks_its_window_and_pulls_the_rest_forward() {
        let mut m: WindowManager<()> = WindowManager::new(400, 16);
        m.update(uniform(3.0 * PI, 0.0), ());
        let before: Vec<f64> = m.windows().map(|w| w.window.b).collect();
        // ωS = 4π over the front third, 3π behind (phase continuous).
        let front = |s: f64| {
            if s < 1.0 / 3.0 {
                4.0 * PI * s
            } else {
                4.0 * PI / 3.0 + 3.0 * PI * (s - 1.0 / 3.0)
            }
        };
        m.update(front, ());
        let after: Vec<f64> = m.windows().map(|w| w.window.b).collect();
        assert!(after[0] < before[0] - 0.05, "{before:?} -> {after:?}");
        assert!(after.len() >= before.len());
    }
}
