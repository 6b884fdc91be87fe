//! The body sections of directional compliance (reference 001, Fig. 2; issue 26): a
//! fixed set of equal stretches of the body, each with its mean amplitude over about one
//! gait cycle, its absition, its mode, per plane. A jam is fixed to the terrain and to a
//! place on the body, so it is the section, not the travelling window, that sees it for
//! as long as it lasts; the windows take the mode of the section their centre is in.
//! Pure and allocation-free (fixed capacity).

use super::absition::{Absition, Mode, Weighing};
use super::config::{HoldConfig, MAX_SECTIONS, Thresholds};

/// Sub-intervals of the mean's span: the boxcar mean is kept as the last `BINS`
/// sub-interval means (fixed storage whatever the span).
const BINS: usize = 32;

/// A boxcar mean over a span of time, kept in `BINS` sub-intervals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boxcar {
    bins: [f64; BINS],
    /// Completed bins (up to `BINS`), the next one to overwrite.
    filled: usize,
    next: usize,
    /// The sub-interval being accumulated: ∫ x dt and its length.
    open_sum: f64,
    open_s: f64,
    bin_s: f64,
}

impl Boxcar {
    pub fn new(span_s: f64) -> Self {
        Self {
            bins: [0.0; BINS],
            filled: 0,
            next: 0,
            open_sum: 0.0,
            open_s: 0.0,
            bin_s: span_s / BINS as f64,
        }
    }

    /// Adds `x` held for `dt_s`; returns whether a sub-interval closed.
    pub fn add(&mut self, x: f64, dt_s: f64) -> bool {
        self.open_sum += x * dt_s;
        self.open_s += dt_s;
        if self.open_s < self.bin_s {
            return false;
        }
        self.bins[self.next] = self.open_sum / self.open_s;
        self.next = (self.next + 1) % BINS;
        self.filled = (self.filled + 1).min(BINS);
        self.open_sum = 0.0;
        self.open_s = 0.0;
        true
    }

    /// Whether a whole span has passed.
    pub fn full(&self) -> bool {
        self.filled == BINS
    }

    /// The mean over the last span (over what there is before a whole span has passed;
    /// 0 before anything was added).
    pub fn mean(&self) -> f64 {
        let (mut sum, mut time) = (self.open_sum, self.open_s);
        for &b in &self.bins[..self.filled] {
            sum += b * self.bin_s;
            time += self.bin_s;
        }
        if time > 0.0 { sum / time } else { 0.0 }
    }
}

/// The mean one span ago: the last `BINS` means, taken as each sub-interval closes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lagged {
    values: [f64; BINS],
    filled: usize,
    next: usize,
}

impl Lagged {
    const EMPTY: Lagged = Lagged {
        values: [0.0; BINS],
        filled: 0,
        next: 0,
    };

    fn push(&mut self, v: f64) {
        self.values[self.next] = v;
        self.next = (self.next + 1) % BINS;
        self.filled = (self.filled + 1).min(BINS);
    }

    /// The oldest value kept, once a whole span is kept.
    fn span_ago(&self) -> Option<f64> {
        (self.filled == BINS).then(|| self.values[self.next])
    }
}

/// One section in one plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionPlane {
    /// `Ā − A₀`: the mean of the section's amplitude deviation over the span.
    pub mean: Boxcar,
    pub lagged: Lagged,
    /// How much the mean changed over a span, averaged over a span, rad.
    pub change: Boxcar,
    pub absition: Absition,
}

impl SectionPlane {
    /// The share of `Ā − A₀ − c` that accumulates (1 with the hold off; 0 until two
    /// spans have passed with it on: stillness is not known yet).
    pub fn still(&self, hold: &HoldConfig) -> f64 {
        if hold.still_rad <= 0.0 {
            return 1.0;
        }
        if !self.change.full() {
            return 0.0;
        }
        let (s, a) = (hold.still_rad, self.change.mean());
        s * s / (s * s + a * a)
    }
}

/// Every section's state; `count` of them along the body, equal in arc length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sections {
    count: usize,
    state: [[SectionPlane; 2]; MAX_SECTIONS],
}

impl Sections {
    /// `count` sections (1..=[`MAX_SECTIONS`]) whose means span `span_s`, every one in
    /// `mode` with zero absition.
    pub fn new(count: usize, span_s: f64, mode: Mode) -> Self {
        let fresh = SectionPlane {
            mean: Boxcar::new(span_s),
            lagged: Lagged::EMPTY,
            change: Boxcar::new(span_s),
            absition: Absition::new(mode),
        };
        Self {
            count: count.clamp(1, MAX_SECTIONS),
            state: [[fresh; 2]; MAX_SECTIONS],
        }
    }

    pub fn count(&self) -> usize {
        self.count
    }

    /// The section holding normalised arc length `s` (clipped to the body).
    pub fn index_of(&self, s: f64) -> usize {
        ((s.clamp(0.0, 1.0) * self.count as f64).floor() as usize).min(self.count - 1)
    }

    /// Section `k`'s edges in normalised arc length.
    pub fn edges(&self, k: usize) -> (f64, f64) {
        let n = self.count as f64;
        (k as f64 / n, (k + 1) as f64 / n)
    }

    pub fn get(&self, k: usize, plane: usize) -> &SectionPlane {
        &self.state[k][plane]
    }

    /// The mode of the section holding `s`, in `plane`.
    pub fn mode_at(&self, s: f64, plane: usize) -> Mode {
        self.state[self.index_of(s)][plane].absition.mode
    }

    /// One step: every section's amplitude deviation now (`deviation[plane][k]`, the
    /// mean over the section's joints of that plane), its friction offset
    /// (`offset[plane][k]`), over `dt_s`, weighed by `hold` (a section stays in PDC or
    /// NDC at most `max_dwell_s`); with `switching`, the modes change by the
    /// thresholds. Returns the number of mode changes.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        planes: usize,
        deviation: &[[f64; MAX_SECTIONS]; 2],
        offset: &[[f64; MAX_SECTIONS]; 2],
        dt_s: f64,
        hold: &HoldConfig,
        max_dwell_s: f64,
        switching: Option<&Thresholds>,
    ) -> u64 {
        let mut changes = 0;
        for k in 0..self.count {
            for p in 0..planes {
                let sp = &mut self.state[k][p];
                let closed = sp.mean.add(deviation[p][k], dt_s);
                let mean = sp.mean.mean();
                if let Some(before) = sp.lagged.span_ago() {
                    sp.change.add((mean - before).abs(), dt_s);
                }
                if closed {
                    sp.lagged.push(mean);
                }
                let w = Weighing {
                    still: sp.still(hold),
                    leak_s: hold.leak_s,
                    max_dwell_s,
                };
                changes += u64::from(sp.absition.observe(mean, offset[p][k], dt_s, &w, switching));
            }
        }
        changes
    }

    /// Every section back to `mode` with zero absition (after a calibration), keeping
    /// the means.
    pub fn restart_absitions(&mut self, mode: Mode) {
        for s in &mut self.state {
            for p in s {
                p.absition = Absition::new(mode);
            }
        }
    }

    /// Sections of `plane` in `mode`.
    pub fn count_in(&self, plane: usize, mode: Mode) -> usize {
        self.state[..self.count]
            .iter()
            .filter(|s| s[plane].absition.mode == mode)
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controllers::directional_compliance::Reference;

    #[test]
    fn the_boxcar_forgets_what_is_older_than_its_span() {
        let mut b = Boxcar::new(1.0);
        assert_eq!(b.mean(), 0.0);
        for _ in 0..500 {
            b.add(2.0, 1e-3);
        }
        assert!((b.mean() - 2.0).abs() < 1e-9, "before a whole span");
        for _ in 0..1500 {
            b.add(-1.0, 1e-3);
        }
        assert!((b.mean() + 1.0).abs() < 1e-9, "{}", b.mean());
        // A sine over whole periods averages out.
        let mut b = Boxcar::new(2.0);
        for k in 0..10_000 {
            b.add((std::f64::consts::TAU * k as f64 * 1e-3).sin(), 1e-3);
        }
        assert!(b.mean().abs() < 0.02, "{}", b.mean());
    }

    #[test]
    fn sections_tile_the_body() {
        let s = Sections::new(3, 6.0, Mode::Nc);
        assert_eq!(s.index_of(-0.5), 0);
        assert_eq!(s.index_of(0.2), 0);
        assert_eq!(s.index_of(0.5), 1);
        assert_eq!(s.index_of(0.9), 2);
        assert_eq!(s.index_of(1.0), 2);
        assert_eq!(s.edges(1), (1.0 / 3.0, 2.0 / 3.0));
        assert_eq!(Sections::new(9, 1.0, Mode::Nc).count(), MAX_SECTIONS);
        assert_eq!(Sections::new(0, 1.0, Mode::Nc).count(), 1);
    }

    /// A section held squeezed accumulates for as long as the jam lasts (a travelling
    /// window would have left it) and switches; the others stay in NC.
    #[test]
    fn a_held_section_switches_and_the_others_do_not() {
        let t = Thresholds {
            low_rad_s: -0.5,
            high_rad_s: 0.5,
            reference: Reference::Threshold,
            shift_rad: 0.0,
        };
        let mut s = Sections::new(3, 2.0, Mode::Nc);
        let mut dev = [[0.0; MAX_SECTIONS]; 2];
        dev[0][2] = -0.3; // the tail squeezed flat
        dev[0][0] = 0.2 * 0.0;
        let offset = [[0.0; MAX_SECTIONS]; 2];
        let mut changes = 0;
        for _ in 0..5000 {
            changes += s.update(
                1,
                &dev,
                &offset,
                1e-3,
                &HoldConfig::PLAIN,
                f64::INFINITY,
                Some(&t),
            );
        }
        assert_eq!(changes, 1);
        assert_eq!(s.mode_at(0.9, 0), Mode::Pdc);
        assert_eq!(s.mode_at(0.1, 0), Mode::Nc);
        assert_eq!(s.count_in(0, Mode::Pdc), 1);
        s.restart_absitions(Mode::Nc);
        assert_eq!(s.count_in(0, Mode::Pdc), 0);
    }

    /// With the hold on, a section squeezed and still (held) accumulates and switches;
    /// one squeezed as much on average but whose mean keeps changing (carried past
    /// obstacles) does not. With the hold off both switch.
    #[test]
    fn only_a_still_section_counts_as_held() {
        let t = Thresholds {
            low_rad_s: -1.0,
            high_rad_s: 1.0,
            reference: Reference::Threshold,
            shift_rad: 0.0,
        };
        let hold = HoldConfig {
            still_rad: 0.02,
            leak_s: 5.0,
            max_dwell_cycles: 0.0,
        };
        for (h, moving_switches) in [(hold, false), (HoldConfig::PLAIN, true)] {
            let mut s = Sections::new(3, 2.0, Mode::Nc);
            let offset = [[0.0; MAX_SECTIONS]; 2];
            for k in 0..60_000 {
                let t_s = k as f64 * 1e-3;
                let mut dev = [[0.0; MAX_SECTIONS]; 2];
                dev[0][0] = -0.3; // head: held
                // tail: between -0.1 and -0.5, a span each
                dev[0][2] = if ((t_s / 2.0) as u64).is_multiple_of(2) {
                    -0.1
                } else {
                    -0.5
                };
                s.update(1, &dev, &offset, 1e-3, &h, f64::INFINITY, Some(&t));
            }
            assert_eq!(s.mode_at(0.1, 0), Mode::Pdc, "{h:?}");
            assert_eq!(s.mode_at(0.5, 0), Mode::Nc, "{h:?}");
            assert_eq!(s.mode_at(0.9, 0) == Mode::Pdc, moving_switches, "{h:?}");
            if h.still_rad > 0.0 {
                let tail = s.get(2, 0);
                assert!(tail.still(&h) < 0.05, "{:?}", tail.change.mean());
                assert!(tail.absition.absition.abs() < 0.5, "{tail:?}");
                assert!(s.get(0, 0).still(&h) > 0.99);
            }
        }
    }
}
