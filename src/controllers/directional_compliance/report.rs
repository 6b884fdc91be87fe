//! Directional compliance's report: its signals (names in `super::report_spec`), the
//! travelling windows and the body sections as fields.

use super::absition::Mode;
use super::controller::{DOR, DirectionalCompliance, FIXED_SIGNALS, LAT};
use crate::controller_interface::report::{
    ControllerReport, MAX_WINDOWS as REPORT_WINDOWS, WindowField,
};

impl DirectionalCompliance {
    /// The report: fixed signals, per-section absitions and modes, the fields.
    pub(super) fn fill_report(&self, out: &mut ControllerReport) {
        out.clear();
        let planes = self.planes();
        let windows_in = |mode: Mode| {
            let mut n = 0;
            for w in self.manager.windows() {
                let centre = centre_of(w.window.a, w.window.b);
                n += (0..planes)
                    .filter(|&p| self.sections.mode_at(centre, p) == mode)
                    .count();
            }
            n as f64
        };
        let sections_in = |mode: Mode| {
            (0..planes)
                .map(|p| self.sections.count_in(p, mode))
                .sum::<usize>() as f64
        };
        let t = &self.config.thresholds;
        let s = &mut out.signals;
        s[0] = self.mean_amplitude(LAT);
        s[1] = self.mean_amplitude(DOR);
        s[2] = self.phase.deviation;
        s[3] = self.manager.len() as f64;
        s[4] = t.low_rad_s;
        s[5] = t.high_rad_s;
        s[6] = self.calibration.state_code();
        s[7] = self.calibration.progress();
        s[8] = windows_in(Mode::Pdc);
        s[9] = windows_in(Mode::Ndc);
        s[10] = sections_in(Mode::Pdc);
        s[11] = sections_in(Mode::Ndc);
        s[12] = self.switches as f64;
        s[13] = if planes > 1 { self.ramp } else { f64::NAN };
        s[14..FIXED_SIGNALS].copy_from_slice(&self.heading.signals());
        // Per section, per plane: absition then mode (`super::report_spec`).
        let mut at = FIXED_SIGNALS;
        for p in 0..2 {
            for k in 0..self.sections.count() {
                let sp = self.sections.get(k, p);
                let (absition, mode) = if p < planes {
                    (sp.absition.absition, sp.absition.mode.code())
                } else {
                    (f64::NAN, f64::NAN)
                };
                s[at] = absition;
                s[at + 1] = mode;
                at += 2;
            }
        }
        for p in 0..planes {
            self.fill_field(p, &mut out.fields[p]);
            self.fill_sections(p, &mut out.fields[planes + p]);
        }
    }

    fn fill_field(&self, plane: usize, out: &mut WindowField) {
        out.count = self.manager.len();
        for (k, w) in self.manager.windows().take(REPORT_WINDOWS).enumerate() {
            let centre = centre_of(w.window.a, w.window.b);
            out.a[k] = w.window.a;
            out.b[k] = w.window.b;
            out.columns[0][k] = self.amplitude0(plane) + w.payload.amplitude[plane].deviation;
            out.columns[1][k] = self.sections.index_of(centre) as f64;
            out.columns[2][k] = self.sections.mode_at(centre, plane).code();
            out.columns[3][k] = self.forces[plane][k];
            out.columns[4][k] = if plane == LAT {
                self.spatial_freq() + w.payload.spatial_freq.deviation
            } else {
                self.spatial_freq()
            };
        }
    }

    /// The sections of `plane` as a field: edges, mean deviation, absition, mode, offset.
    fn fill_sections(&self, plane: usize, out: &mut WindowField) {
        let offsets = self.calibration.offsets();
        let offsets = if plane == LAT {
            offsets.lateral_rad
        } else {
            offsets.dorsal_rad
        };
        out.count = self.sections.count();
        for k in 0..self.sections.count() {
            let sp = self.sections.get(k, plane);
            (out.a[k], out.b[k]) = self.sections.edges(k);
            out.columns[0][k] = sp.mean.mean();
            out.columns[1][k] = sp.absition.absition;
            out.columns[2][k] = sp.absition.mode.code();
            out.columns[3][k] = offsets.get(k);
            out.columns[4][k] = sp.change.mean();
            out.columns[5][k] = sp.still(&self.config.hold);
        }
    }
}

/// A window's centre in normalised arc length (open ends clipped to the body).
pub(super) fn centre_of(a: f64, b: f64) -> f64 {
    0.5 * (a.max(0.0) + b.min(1.0))
}
