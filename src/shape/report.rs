//! A fixed-size picture of a controller's compliance (windows, shape parameters, shape
//! forces), filled every cycle without allocating: what the daemon publishes in its
//! telemetry.

use super::slithering_config::Centralization;
use super::window::Window;
use super::window_manager::WindowEvents;

/// Windows kept per field (a per-joint field of a 64-module body has 32).
pub const REPORT_MAX_WINDOWS: usize = 32;

/// One parameter field: its windows' edges, values and last shape forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldReport {
    /// Whether the parameter complies (off: it stays at its nominal value).
    pub enabled: bool,
    pub centralization: Centralization,
    /// Windows on the body; only the first [`REPORT_MAX_WINDOWS`] are kept.
    pub count: usize,
    /// Edges in normalised arc length (infinite: the side is open).
    pub a: [f64; REPORT_MAX_WINDOWS],
    pub b: [f64; REPORT_MAX_WINDOWS],
    /// Each window's value (for the temporal phase: its lag `Ω_j − ωT·t`, rad).
    pub value: [f64; REPORT_MAX_WINDOWS],
    /// Each window's shape force.
    pub force: [f64; REPORT_MAX_WINDOWS],
}

impl FieldReport {
    pub const EMPTY: FieldReport = FieldReport {
        enabled: false,
        centralization: Centralization::Central,
        count: 0,
        a: [0.0; REPORT_MAX_WINDOWS],
        b: [0.0; REPORT_MAX_WINDOWS],
        value: [0.0; REPORT_MAX_WINDOWS],
        force: [0.0; REPORT_MAX_WINDOWS],
    };

    /// Windows kept (`count` capped at the capacity).
    pub fn len(&self) -> usize {
        self.count.min(REPORT_MAX_WINDOWS)
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Copies a field in; `value_offset` is subtracted from every value. Missing
    /// forces (before the first step) are 0.
    pub fn fill(
        &mut self,
        enabled: bool,
        centralization: Centralization,
        windows: &[Window],
        values: &[f64],
        forces: &[f64],
        value_offset: f64,
    ) {
        self.enabled = enabled;
        self.centralization = centralization;
        self.count = windows.len();
        for (k, w) in windows.iter().take(REPORT_MAX_WINDOWS).enumerate() {
            self.a[k] = w.a;
            self.b[k] = w.b;
            self.value[k] = values.get(k).map_or(f64::NAN, |v| v - value_offset);
            self.force[k] = forces.get(k).copied().unwrap_or(0.0);
        }
    }
}

/// Everything a controller reports about its compliance after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComplianceReport {
    /// False when the controller reports nothing (or has not stepped yet).
    pub available: bool,
    /// Amplitude (rad), spatial frequency (rad per body length) and temporal phase
    /// (lag, rad), in `Param` order. Empty for controllers without windows.
    pub fields: [FieldReport; 3],
    /// Means over the lateral joints.
    pub amplitude_mean_rad: f64,
    pub spatial_freq_mean_rad: f64,
    /// Ω − ωT·t: negative when the wave runs late.
    pub phase_lag_rad: f64,
    /// Travelling windows on the body (0 when no parameter is windowed).
    pub travelling_windows: usize,
    /// Births and drops of the last step.
    pub events: WindowEvents,
}

impl ComplianceReport {
    pub const EMPTY: ComplianceReport = ComplianceReport {
        available: false,
        fields: [FieldReport::EMPTY; 3],
        amplitude_mean_rad: f64::NAN,
        spatial_freq_mean_rad: f64::NAN,
        phase_lag_rad: f64::NAN,
        travelling_windows: 0,
        events: WindowEvents {
            born_at_head: 0,
            dropped_at_tail: 0,
            born_at_tail: 0,
            dropped_at_head: 0,
        },
    };

    pub fn clear(&mut self) {
        *self = Self::EMPTY;
    }
}

impl Default for ComplianceReport {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_is_copied_capped_and_offset() {
        let windows: Vec<Window> = (0..40)
            .map(|k| Window {
                a: k as f64,
                b: k as f64 + 1.0,
            })
            .collect();
        let values: Vec<f64> = (0..40).map(|k| 10.0 + k as f64).collect();
        let mut f = FieldReport::EMPTY;
        f.fill(true, Centralization::PerJoint, &windows, &values, &[], 10.0);
        assert_eq!((f.count, f.len()), (40, REPORT_MAX_WINDOWS));
        assert_eq!(
            (f.a[3], f.b[3], f.value[3], f.force[3]),
            (3.0, 4.0, 3.0, 0.0)
        );
    }
}
