//! Validation of a parsed world scenario: every number finite, sizes positive, regions
//! non-empty, pole sections increasing. Errors name the file and the key.

use super::scenario::{
    PegBoard, PegFence, PegRow, PoleGen, Region, RockPile, ScenarioError, StartGen, WorldScenario,
};

/// Most pegs or rocks one generator may make (keeps a typo from hanging the sampler).
pub const MAX_COUNT: usize = 10_000;

type R = Result<(), ScenarioError>;

impl WorldScenario {
    /// Check every key; called by `load`, `parse` and `generate`.
    pub fn validate(&self) -> R {
        let f = &self.friction;
        self.non_negative("friction.mu", f.mu)?;
        if let Some(mu) = f.peg_mu {
            self.non_negative("friction.peg_mu", mu)?;
        }
        if let Some(a) = f.anisotropic {
            self.non_negative("friction.anisotropic.mu_axial", a.mu_axial)?;
            self.non_negative("friction.anisotropic.mu_lateral", a.mu_lateral)?;
        }
        for (i, b) in self.peg_boards.iter().enumerate() {
            self.peg_board(&format!("peg_board[{i}]"), b)?;
        }
        for (i, r) in self.peg_rows.iter().enumerate() {
            self.peg_row(&format!("peg_row[{i}]"), r)?;
        }
        for (i, f) in self.peg_fences.iter().enumerate() {
            self.peg_fence(&format!("peg_fence[{i}]"), f)?;
        }
        for (i, p) in self.pegs.iter().enumerate() {
            let k = format!("peg[{i}]");
            self.finite(&format!("{k}.x_m"), p.x_m)?;
            self.finite(&format!("{k}.y_m"), p.y_m)?;
            self.positive(&format!("{k}.diameter_m"), p.diameter_m)?;
            self.positive(&format!("{k}.height_m"), p.height_m)?;
        }
        for (i, p) in self.peg_files.iter().enumerate() {
            let k = format!("peg_file[{i}]");
            if let Some(d) = p.diameter_m {
                self.positive(&format!("{k}.diameter_m"), d)?;
            }
            self.positive(&format!("{k}.height_m"), p.height_m)?;
        }
        for (i, p) in self.poles.iter().enumerate() {
            self.pole(&format!("pole[{i}]"), p)?;
        }
        for (i, r) in self.rock_piles.iter().enumerate() {
            self.rock_pile(&format!("rock_pile[{i}]"), r)?;
        }
        for (i, w) in self.walls.iter().enumerate() {
            let k = format!("wall[{i}]");
            for (j, v) in w.from_m.iter().chain(&w.to_m).enumerate() {
                let name = if j < 2 { "from_m" } else { "to_m" };
                self.finite(&format!("{k}.{name}"), *v)?;
            }
            if w.from_m == w.to_m {
                return Err(self.invalid(format!("{k}.to_m"), "equals from_m (zero length)"));
            }
            self.positive(&format!("{k}.height_m"), w.height_m)?;
            self.positive(&format!("{k}.thickness_m"), w.thickness_m)?;
        }
        self.start_gen(&self.start)
    }

    fn peg_board(&self, k: &str, b: &PegBoard) -> R {
        self.count(&format!("{k}.count"), b.count)?;
        self.positive(&format!("{k}.diameter_m"), b.diameter_m)?;
        self.positive(&format!("{k}.height_m"), b.height_m)?;
        self.positive(&format!("{k}.min_spacing_m"), b.min_spacing_m)?;
        if b.min_spacing_m < b.diameter_m {
            return Err(self.invalid(
                format!("{k}.min_spacing_m"),
                format!(
                    "{} is less than diameter_m {} (centre to centre: pegs would overlap)",
                    b.min_spacing_m, b.diameter_m
                ),
            ));
        }
        self.region(&format!("{k}.region"), &b.region)
    }

    fn peg_row(&self, k: &str, r: &PegRow) -> R {
        self.finite(&format!("{k}.start_m"), r.start_m[0])?;
        self.finite(&format!("{k}.start_m"), r.start_m[1])?;
        self.finite(&format!("{k}.direction_rad"), r.direction_rad)?;
        self.count(&format!("{k}.count"), r.count)?;
        self.positive(&format!("{k}.diameter_m"), r.diameter_m)?;
        self.positive(&format!("{k}.height_m"), r.height_m)?;
        let forms = [
            r.spacing_m.is_some(),
            r.wave.is_some(),
            r.serpenoid.is_some(),
        ];
        if forms.iter().filter(|&&b| b).count() != 1 {
            return Err(self.invalid(
                k,
                "give exactly one of spacing_m, wave, serpenoid (they set the spacing)",
            ));
        }
        if let Some(s) = r.spacing_m {
            self.positive(&format!("{k}.spacing_m"), s)?;
        }
        if let Some(o) = r.lateral_offset_m {
            self.non_negative(&format!("{k}.lateral_offset_m"), o)?;
        }
        if let Some(w) = r.wave {
            self.positive(&format!("{k}.wave.wavelength_m"), w.wavelength_m)?;
            self.positive(&format!("{k}.wave.amplitude_m"), w.amplitude_m)?;
        }
        if let Some(s) = r.serpenoid {
            self.positive(&format!("{k}.serpenoid.waves_per_body"), s.waves_per_body)?;
            self.positive(
                &format!("{k}.serpenoid.joint_amplitude_rad"),
                s.joint_amplitude_rad,
            )?;
            if s.joint_amplitude_rad >= std::f64::consts::FRAC_PI_2 {
                return Err(self.invalid(
                    format!("{k}.serpenoid.joint_amplitude_rad"),
                    "must be below π/2",
                ));
            }
        }
        Ok(())
    }

    fn peg_fence(&self, k: &str, f: &PegFence) -> R {
        self.finite(&format!("{k}.start_m"), f.start_m[0])?;
        self.finite(&format!("{k}.start_m"), f.start_m[1])?;
        self.finite(&format!("{k}.direction_rad"), f.direction_rad)?;
        self.positive(&format!("{k}.length_m"), f.length_m)?;
        self.positive(&format!("{k}.diameter_m"), f.diameter_m)?;
        self.positive(&format!("{k}.height_m"), f.height_m)?;
        self.non_negative(&format!("{k}.jitter_m"), f.jitter_m)?;
        let [lo, hi] = f.gap_m;
        self.positive(&format!("{k}.gap_m"), lo)?;
        self.finite(&format!("{k}.gap_m"), hi)?;
        if hi < lo {
            return Err(self.invalid(
                format!("{k}.gap_m"),
                format!("[{lo}, {hi}]: the maximum is below the minimum"),
            ));
        }
        if f.length_m / (lo + f.diameter_m) > MAX_COUNT as f64 {
            return Err(self.invalid(
                format!("{k}.length_m"),
                format!("more than {MAX_COUNT} pegs at the smallest gap"),
            ));
        }
        Ok(())
    }

    fn pole(&self, k: &str, p: &PoleGen) -> R {
        self.finite(&format!("{k}.x_m"), p.x_m)?;
        self.finite(&format!("{k}.y_m"), p.y_m)?;
        if let Some(mu) = p.mu {
            self.non_negative(&format!("{k}.mu"), mu)?;
        }
        match (&p.sections, &p.taper) {
            (Some(s), None) => {
                if s.is_empty() {
                    return Err(self.invalid(format!("{k}.sections"), "is empty"));
                }
                let mut below = 0.0;
                for (j, sec) in s.iter().enumerate() {
                    let sk = format!("{k}.sections[{j}]");
                    self.positive(&format!("{sk}.top_m"), sec.top_m)?;
                    self.positive(&format!("{sk}.diameter_m"), sec.diameter_m)?;
                    if sec.top_m <= below {
                        return Err(self.invalid(
                            format!("{sk}.top_m"),
                            format!(
                                "{} is not above the section below (top {below}): sections \
                                 go bottom to top with increasing top_m",
                                sec.top_m
                            ),
                        ));
                    }
                    below = sec.top_m;
                }
                Ok(())
            }
            (None, Some(t)) => {
                self.positive(&format!("{k}.taper.height_m"), t.height_m)?;
                self.positive(&format!("{k}.taper.bottom_diameter_m"), t.bottom_diameter_m)?;
                self.positive(&format!("{k}.taper.top_diameter_m"), t.top_diameter_m)?;
                if t.steps == 0 || t.steps > 1000 {
                    return Err(self.invalid(format!("{k}.taper.steps"), "must be 1..=1000"));
                }
                Ok(())
            }
            _ => Err(self.invalid(k, "give exactly one of sections, taper")),
        }
    }

    fn rock_pile(&self, k: &str, r: &RockPile) -> R {
        self.count(&format!("{k}.count"), r.count)?;
        self.range(&format!("{k}.size_m"), r.size_m, true)?;
        self.region(&format!("{k}.region"), &r.region)?;
        if !(4..=256).contains(&r.points) {
            return Err(self.invalid(format!("{k}.points"), "must be 4..=256"));
        }
        self.range(&format!("{k}.flatness"), r.flatness, true)?;
        if !(r.jitter.is_finite() && (0.0..0.9).contains(&r.jitter)) {
            return Err(self.invalid(format!("{k}.jitter"), "must be in [0, 0.9)"));
        }
        Ok(())
    }

    fn start_gen(&self, s: &StartGen) -> R {
        if let Some(h) = &s.head_m {
            if !(2..=3).contains(&h.len()) {
                return Err(self.invalid("start.head_m", "needs [x, y] or [x, y, z]"));
            }
            for v in h {
                self.finite("start.head_m", *v)?;
            }
        }
        if let Some(y) = s.yaw_rad {
            self.finite("start.yaw_rad", y)?;
        }
        for v in &s.joint_angles_rad {
            self.finite("start.joint_angles_rad", *v)?;
        }
        if let Some(r) = &s.random {
            if s.head_m.is_some() || s.yaw_rad.is_some() {
                return Err(self.invalid(
                    "start.random",
                    "give either head_m/yaw_rad or random, not both",
                ));
            }
            self.region("start.random.region", &r.region)?;
            self.range("start.random.yaw_range_rad", r.yaw_range_rad, false)?;
        }
        Ok(())
    }

    fn region(&self, k: &str, r: &Region) -> R {
        for (name, [a, b]) in [("x_m", r.x_m), ("y_m", r.y_m)] {
            let key = format!("{k}.{name}");
            self.finite(&key, a)?;
            self.finite(&key, b)?;
            if a >= b {
                return Err(self.invalid(key, format!("[{a}, {b}] is empty (need a < b)")));
            }
        }
        Ok(())
    }

    /// `[min, max]` with min ≤ max (and both > 0 when `positive`).
    fn range(&self, k: &str, [a, b]: [f64; 2], positive: bool) -> R {
        if positive {
            self.positive(k, a)?;
            self.positive(k, b)?;
        } else {
            self.finite(k, a)?;
            self.finite(k, b)?;
        }
        if a > b {
            return Err(self.invalid(k, format!("[{a}, {b}]: min above max")));
        }
        Ok(())
    }

    fn count(&self, k: &str, n: usize) -> R {
        if n > MAX_COUNT {
            return Err(self.invalid(k, format!("{n} is above the limit {MAX_COUNT}")));
        }
        Ok(())
    }

    fn finite(&self, k: &str, v: f64) -> R {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.invalid(k, format!("{v} is not finite")))
        }
    }

    fn positive(&self, k: &str, v: f64) -> R {
        self.finite(k, v)?;
        if v > 0.0 {
            Ok(())
        } else {
            Err(self.invalid(k, format!("{v} must be positive")))
        }
    }

    fn non_negative(&self, k: &str, v: f64) -> R {
        self.finite(k, v)?;
        if v >= 0.0 {
            Ok(())
        } else {
            Err(self.invalid(k, format!("{v} must not be negative")))
        }
    }
}
