//! What a trial asks of the actuators (issue 25): how often the set-point guard had to
//! slow the set-points, how fast the joints moved and how long they pushed at the torque
//! limit. A controller that chatters (set-points faster than the motors, joints rattling
//! against their springs, torque pinned at the limit) wears a real robot's gearboxes and
//! heats its motors even when it gets through; every experiment reports these so none
//! can hide it.
//!
//! Accumulated once per loop cycle from the modules' own reports (what the daemon reads),
//! allocation-free, then summarised per trial.

/// Per-trial accumulator and result.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Strain {
    /// Cycles counted.
    pub cycles: u64,
    /// Cycles in which the set-point guard slew-limited some joint.
    pub guard_limited_cycles: u64,
    /// Joint-cycles counted (cycles × joints).
    pub joint_cycles: u64,
    /// Joint-cycles whose reported speed was above the motor's speed.
    pub fast_joint_cycles: u64,
    /// Joint-cycles whose reported torque was at the limit (within 5 %).
    pub torque_limit_joint_cycles: u64,
    /// Largest reported joint speed, rad/s.
    pub peak_joint_speed_rad_s: f64,
    /// Sum of |speed| over joint-cycles, rad/s (for the mean).
    sum_joint_speed_rad_s: f64,
}

/// The thresholds a [`Strain`] counts against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainLimits {
    /// The motor's speed, rad/s: a joint reported faster moves on its spring or is
    /// thrown by a contact.
    pub motor_speed_rad_s: f64,
    /// The actuator's torque limit, N·m.
    pub max_torque_nm: f64,
}

impl StrainLimits {
    /// The SEA Snake's module (SPEC §1): 3.46 rad/s, 7 N·m.
    pub const SEA: StrainLimits = StrainLimits {
        motor_speed_rad_s: crate::module::MODULE_MAX_SPEED_RAD_S,
        max_torque_nm: crate::module::MODULE_MAX_TORQUE_NM,
    };
}

/// Share of the torque limit counted as "at the limit".
const AT_LIMIT: f64 = 0.95;

impl Strain {
    /// One cycle: whether the guard limited it, and every joint's reported speed and
    /// torque (non-finite values are skipped).
    pub fn add_cycle(
        &mut self,
        limits: &StrainLimits,
        guard_limited: bool,
        joints: impl Iterator<Item = (f64, f64)>,
    ) {
        self.cycles += 1;
        self.guard_limited_cycles += u64::from(guard_limited);
        for (speed, torque) in joints {
            if !speed.is_finite() || !torque.is_finite() {
                continue;
            }
            let v = speed.abs();
            self.joint_cycles += 1;
            self.sum_joint_speed_rad_s += v;
            self.peak_joint_speed_rad_s = self.peak_joint_speed_rad_s.max(v);
            self.fast_joint_cycles += u64::from(v > limits.motor_speed_rad_s);
            self.torque_limit_joint_cycles +=
                u64::from(torque.abs() >= AT_LIMIT * limits.max_torque_nm);
        }
    }

    /// Share of cycles the guard slew-limited, %.
    pub fn guard_limited_pct(&self) -> f64 {
        pct(self.guard_limited_cycles, self.cycles)
    }

    /// Share of joint-time above the motor's speed, %.
    pub fn fast_pct(&self) -> f64 {
        pct(self.fast_joint_cycles, self.joint_cycles)
    }

    /// Share of joint-time at the torque limit, %.
    pub fn torque_limit_pct(&self) -> f64 {
        pct(self.torque_limit_joint_cycles, self.joint_cycles)
    }

    /// Mean |joint speed|, rad/s (NaN when nothing was counted).
    pub fn mean_joint_speed_rad_s(&self) -> f64 {
        if self.joint_cycles == 0 {
            f64::NAN
        } else {
            self.sum_joint_speed_rad_s / self.joint_cycles as f64
        }
    }

    /// The CSV columns, in [`Strain::csv_row`]'s order.
    pub const CSV_HEADER: &'static str = "guard_limited_pct,peak_joint_speed_rad_s,mean_joint_speed_rad_s,fast_joint_pct,torque_limit_pct";

    /// This trial's CSV cells.
    pub fn csv_row(&self) -> String {
        format!(
            "{:.3},{:.3},{:.4},{:.4},{:.4}",
            self.guard_limited_pct(),
            self.peak_joint_speed_rad_s,
            self.mean_joint_speed_rad_s(),
            self.fast_pct(),
            self.torque_limit_pct()
        )
    }
}

fn pct(part: u64, whole: u64) -> f64 {
    if whole == 0 {
        f64::NAN
    } else {
        100.0 * part as f64 / whole as f64
    }
}

/// A controller's strain over its trials: medians and the worst trial, as the
/// summaries table it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainSummary {
    pub guard_limited_pct_median: f64,
    pub guard_limited_pct_max: f64,
    pub peak_joint_speed_median_rad_s: f64,
    pub peak_joint_speed_max_rad_s: f64,
    pub fast_pct_median: f64,
    pub torque_limit_pct_median: f64,
    pub torque_limit_pct_max: f64,
}

impl StrainSummary {
    pub fn of<'a>(trials: impl Iterator<Item = &'a Strain>) -> StrainSummary {
        let all: Vec<&Strain> = trials.collect();
        let col = |f: fn(&Strain) -> f64| -> Vec<f64> { all.iter().map(|s| f(s)).collect() };
        let guard = col(Strain::guard_limited_pct);
        let peak = col(|s| s.peak_joint_speed_rad_s);
        let torque = col(Strain::torque_limit_pct);
        StrainSummary {
            guard_limited_pct_median: median(&guard),
            guard_limited_pct_max: max(&guard),
            peak_joint_speed_median_rad_s: median(&peak),
            peak_joint_speed_max_rad_s: max(&peak),
            fast_pct_median: median(&col(Strain::fast_pct)),
            torque_limit_pct_median: median(&torque),
            torque_limit_pct_max: max(&torque),
        }
    }

    /// The markdown table's header (one row per controller, after its name).
    pub const TABLE_HEADER: &'static str = "| controller | guard-limited % (median / max) | peak joint speed rad/s (median / max) | above motor speed % (median) | at torque limit % (median / max) |\n| --- | ---: | ---: | ---: | ---: |";

    /// One markdown row.
    pub fn table_row(&self, label: &str) -> String {
        format!(
            "| {label} | {:.2} / {:.2} | {:.1} / {:.1} | {:.2} | {:.2} / {:.2} |",
            self.guard_limited_pct_median,
            self.guard_limited_pct_max,
            self.peak_joint_speed_median_rad_s,
            self.peak_joint_speed_max_rad_s,
            self.fast_pct_median,
            self.torque_limit_pct_median,
            self.torque_limit_pct_max,
        )
    }
}

/// Median of the finite values (NaN when there are none).
fn median(v: &[f64]) -> f64 {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    super::metrics::mean_sd_median(&finite).map_or(f64::NAN, |(_, _, m)| m)
}

fn max(v: &[f64]) -> f64 {
    v.iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(f64::NAN, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_fast_joints_torque_at_the_limit_and_guarded_cycles() {
        let mut s = Strain::default();
        let l = StrainLimits::SEA;
        s.add_cycle(&l, false, [(1.0, 0.5), (-5.0, -6.9)].into_iter());
        s.add_cycle(&l, true, [(0.0, 7.0), (f64::NAN, 1.0)].into_iter());
        assert_eq!((s.cycles, s.joint_cycles), (2, 3));
        assert_eq!(s.guard_limited_pct(), 50.0);
        assert!((s.fast_pct() - 100.0 / 3.0).abs() < 1e-12);
        assert!((s.torque_limit_pct() - 200.0 / 3.0).abs() < 1e-12);
        assert_eq!(s.peak_joint_speed_rad_s, 5.0);
        assert_eq!(s.mean_joint_speed_rad_s(), 2.0);
        assert_eq!(s.csv_row().split(',').count(), 5);
        assert_eq!(Strain::CSV_HEADER.split(',').count(), 5);
    }

    #[test]
    fn the_summary_takes_medians_and_worst_trials() {
        let l = StrainLimits::SEA;
        let trial = |guarded: bool, speed: f64| {
            let mut s = Strain::default();
            s.add_cycle(&l, guarded, [(speed, 0.0)].into_iter());
            s
        };
        let t = [trial(false, 1.0), trial(true, 9.0), trial(false, 2.0)];
        let sum = StrainSummary::of(t.iter());
        assert_eq!(sum.guard_limited_pct_median, 0.0);
        assert_eq!(sum.guard_limited_pct_max, 100.0);
        assert_eq!(sum.peak_joint_speed_median_rad_s, 2.0);
        assert_eq!(sum.peak_joint_speed_max_rad_s, 9.0);
        assert!(sum.table_row("x").starts_with("| x | 0.00 / 100.00 |"));
    }
}
