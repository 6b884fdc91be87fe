//! The loop's progress monitor: the stuck detector ([`super::stuck`]) run over the
//! gait the loop is running, started afresh whenever what the body does changes (a
//! request applied, a blend, a hold or limp, a new wave), so a repetition it reports
//! is the present gait's. What the operator sees in `status`, telemetry and the
//! recording, and what the navigator will act on.

use serde::Serialize;

use super::stuck::{StuckConfig, StuckDetector, StuckReason};

/// What the monitor says this cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProgressReport {
    /// The torques have repeated for the configured number of whole cycles.
    pub stuck: bool,
    pub reason: StuckReason,
    /// The last whole cycle's repeat error (NaN until one was measured).
    pub repeat_error: f64,
    /// Seconds since the measurement (re)started.
    pub measuring_s: f64,
}

impl ProgressReport {
    /// Nothing measured.
    pub const NONE: Self = Self {
        stuck: false,
        reason: StuckReason::Measuring,
        repeat_error: f64::NAN,
        measuring_s: 0.0,
    };
}

impl Default for ProgressReport {
    fn default() -> Self {
        Self::NONE
    }
}

/// The detector and when it last started; allocates at construction only.
#[derive(Debug, Clone)]
pub struct ProgressMonitor {
    detector: StuckDetector,
    cycle_s: f64,
    last_t_s: Option<f64>,
    since_s: f64,
}

impl ProgressMonitor {
    pub fn new(config: StuckConfig, joints: usize) -> Self {
        Self {
            detector: StuckDetector::new(config, joints, std::f64::consts::TAU),
            cycle_s: f64::NAN,
            last_t_s: None,
            since_s: 0.0,
        }
    }

    /// Forget what was measured: the next [`ProgressMonitor::update`] starts afresh.
    pub fn restart(&mut self) {
        self.cycle_s = f64::NAN;
        self.last_t_s = None;
    }

    /// At loop time `t_s`, the gait running steadily with a cycle of `cycle_s` s
    /// (`None`: not steady — blending, holding, limp — which restarts the measurement),
    /// the joints' reported torques `torque_nm`.
    pub fn update(&mut self, t_s: f64, cycle_s: Option<f64>, torque_nm: &[f64]) {
        let Some(cycle_s) = cycle_s.filter(|c| c.is_finite() && *c > 0.0) else {
            self.restart();
            return;
        };
        // A new wave (beyond rounding) is a new limit cycle.
        let same = (cycle_s - self.cycle_s).abs() <= 1e-6 * cycle_s;
        let dt = match self.last_t_s {
            Some(last) if same && t_s > last => t_s - last,
            _ => {
                self.detector.reset(cycle_s);
                self.cycle_s = cycle_s;
                self.since_s = 0.0;
                0.0
            }
        };
        self.last_t_s = Some(t_s);
        self.since_s += dt;
        self.detector.update(dt, torque_nm);
    }

    pub fn report(&self) -> ProgressReport {
        if self.last_t_s.is_none() {
            return ProgressReport::default();
        }
        ProgressReport {
            stuck: self.detector.stuck(),
            reason: self.detector.reason(),
            repeat_error: self.detector.repeat_error.unwrap_or(f64::NAN),
            measuring_s: self.since_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn run(m: &mut ProgressMonitor, t0: f64, seconds: f64, cycle_s: Option<f64>) -> f64 {
        let steps = (seconds * 1000.0) as usize;
        let mut tau = [0.0; 3];
        for k in 0..steps {
            let t = t0 + k as f64 * 1e-3;
            for (j, v) in tau.iter_mut().enumerate() {
                *v = (TAU * t / 2.0 + j as f64).sin();
            }
            m.update(t, cycle_s, &tau);
        }
        t0 + steps as f64 * 1e-3
    }

    #[test]
    fn a_steady_repeating_gait_is_stuck_and_any_change_starts_afresh() {
        let mut m = ProgressMonitor::new(StuckConfig::DEFAULT, 3);
        assert_eq!(m.report().reason, StuckReason::Measuring);
        let t = run(&mut m, 0.0, 4.5, Some(2.0));
        let r = m.report();
        assert!(r.stuck, "{r:?}");
        assert!(
            r.repeat_error < 0.1 && (r.measuring_s - 4.5).abs() < 0.01,
            "{r:?}"
        );
        // Blending (not steady) restarts; so does a new wave.
        let t = run(&mut m, t, 0.1, None);
        let r = m.report();
        assert!(!r.stuck && r.reason == StuckReason::Measuring && r.repeat_error.is_nan());
        let t = run(&mut m, t, 1.0, Some(2.0));
        assert!(!m.report().stuck);
        run(&mut m, t, 1.0, Some(2.5));
        let r = m.report();
        assert_eq!(r.reason, StuckReason::Measuring, "{r:?}");
        assert!(r.measuring_s < 1.0);
    }
}
