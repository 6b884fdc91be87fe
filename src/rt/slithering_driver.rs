//! The loop's side of compliant slithering: a slithering controller (set through
//! `params.set`) takes over the joints from the gait selector once the selector has
//! finished blending into slithering, and hands them back when the gait changes, the
//! loop holds, or the controller is replaced.
//!
//! - **Takeover without a jump.** The controller's nominal phase is `ωT·t_c` on its own
//!   clock; it is fed `t_c = t − shift`, the shift chosen at takeover so that its phase
//!   equals the selector's slithering phase. It is reset first, so its first step is a
//!   fresh controller's: the serpenoid the selector was sending. The lateral and dorsal
//!   offsets (steering) are added to its output as the selector adds them.
//! - **Hand back.** The selector re-syncs to the set-points sent last cycle and blends
//!   from there into its active gait. A replaced controller takes over after that
//!   blend, as a new one does.
//! - **Nothing allocates or frees.** Controllers are built on the control side; the one
//!   replaced is sent back through a bounded channel to be dropped there.
//! - **Safety.** Its set-points pass the same per-joint slew limit as the selector's;
//!   the velocity feed-forward is their difference quotient.
use crossbeam_channel::{Sender, TrySendError};

use crate::gait::{GaitKind, GaitSelector, Plane};
use crate::rt::compliance::{ComplianceSetting, ComplianceTelemetry, ControllerChange, Engagement};
use crate::shape::{ComplianceReport, JointController, Measured};

/// Slowest nominal wave a controller takes over (|ωT|, rad/s): a standing wave has no
/// phase to match.
const MIN_TEMPORAL_FREQ_RAD_S: f64 = 1e-6;

/// The slithering controller and its state in the loop.
pub struct SlitheringDriver {
    controller: Option<Box<dyn JointController>>,
    setting: ComplianceSetting,
    engagement: Engagement,
    /// Controller time = loop time − `shift_s`.
    shift_s: f64,
    retired: Sender<Box<dyn JointController>>,
    /// Set-points of the last cycle that ran the gait, and its time.
    last_pos: Vec<f64>,
    last_t_s: Option<f64>,
    report: ComplianceReport,
    windows_born: u64,
    windows_dropped: u64,
    takeovers: u64,
    freed_in_loop: u64,
}

impl SlitheringDriver {
    /// No controller yet; replaced ones go to `retired`.
    pub fn new(joints: usize, retired: Sender<Box<dyn JointController>>) -> Self {
        Self {
            controller: None,
            setting: ComplianceSetting::OPEN_LOOP,
            engagement: Engagement::Off,
            shift_s: 0.0,
            retired,
            last_pos: vec![0.0; joints],
            last_t_s: None,
            report: ComplianceReport::EMPTY,
            windows_born: 0,
            windows_dropped: 0,
            takeovers: 0,
            freed_in_loop: 0,
        }
    }

    pub fn engagement(&self) -> Engagement {
        self.engagement
    }

    pub fn has_controller(&self) -> bool {
        self.controller.is_some()
    }

    /// Applies a controller change at a cycle boundary. A controller that was driving
    /// first hands the joints back to the selector (from `commanded`, the set-points
    /// sent last cycle); the new one takes over when the selector's blend ends.
    pub fn install(
        &mut self,
        change: ControllerChange,
        selector: &mut GaitSelector,
        commanded: &[f64],
        t_s: f64,
    ) {
        self.hand_back(selector, commanded, t_s);
        self.setting = change.setting();
        let old = match change {
            ControllerChange::OpenLoop => {
                self.engagement = Engagement::Off;
                self.controller.take()
            }
            ControllerChange::Install(c) => {
                self.engagement = Engagement::Waiting;
                self.controller.replace(c.controller)
            }
        };
        self.windows_born = 0;
        self.windows_dropped = 0;
        self.takeovers = 0;
        if let Some(old) = old {
            self.retire(old);
        }
    }

    /// Sends the controller of a refused change back unused.
    pub fn refuse(&mut self, change: ControllerChange) {
        if let ControllerChange::Install(c) = change {
            self.retire(c.controller);
        }
    }

    fn retire(&mut self, controller: Box<dyn JointController>) {
        match self.retired.try_send(controller) {
            Ok(()) => {}
            // Only when the control side stopped draining: freeing here is an
            // allocator call in the loop, counted so it shows.
            Err(TrySendError::Full(c) | TrySendError::Disconnected(c)) => {
                self.freed_in_loop += 1;
                drop(c);
            }
        }
    }

    /// If the controller drives, gives the joints back to the selector: it restarts
    /// from `commanded` and blends into its active gait over the blend time. Call after
    /// changing the selector's gait.
    pub fn hand_back(&mut self, selector: &mut GaitSelector, commanded: &[f64], t_s: f64) {
        if self.engagement == Engagement::Engaged {
            selector.resync(commanded, t_s);
            self.engagement = Engagement::Waiting;
        }
    }

    /// The loop does not run the gait this cycle (hold, limp) or restarts it from the
    /// measured pose: the controller stops driving, and takes over again (reset) once
    /// the selector has blended back into slithering.
    pub fn pause(&mut self) {
        if self.engagement == Engagement::Engaged {
            self.engagement = Engagement::Waiting;
        }
    }

    /// Called after the selector's update with its set-points in `pos`/`vel`: replaces
    /// them with the controller's when it drives slithering, taking over first when the
    /// selector has just finished blending into slithering.
    pub fn drive(
        &mut self,
        t_s: f64,
        selector: &GaitSelector,
        measured: &Measured<'_>,
        pos: &mut [f64],
        vel: &mut [f64],
    ) {
        debug_assert!(
            self.engagement != Engagement::Engaged || selector.active() == GaitKind::Slithering,
            "a gait change hands back first"
        );
        if self.engagement == Engagement::Waiting {
            self.try_take_over(t_s, selector);
        }
        if self.engagement == Engagement::Engaged {
            self.step(t_s, selector, measured, pos, vel);
        }
        self.last_pos.copy_from_slice(pos);
        self.last_t_s = Some(t_s);
    }

    fn try_take_over(&mut self, t_s: f64, selector: &GaitSelector) {
        let Some(c) = self.controller.as_mut() else {
            return;
        };
        let omega_t = c.temporal_freq_rad_s();
        let ready = selector.active() == GaitKind::Slithering
            && selector.blend_progress() >= 1.0
            && omega_t.abs() > MIN_TEMPORAL_FREQ_RAD_S;
        if ready {
            c.reset();
            self.shift_s = t_s - selector.phase() / omega_t;
            self.engagement = Engagement::Engaged;
            self.takeovers += 1;
        }
    }

    fn step(
        &mut self,
        t_s: f64,
        selector: &GaitSelector,
        measured: &Measured<'_>,
        pos: &mut [f64],
        vel: &mut [f64],
    ) {
        let Some(c) = self.controller.as_mut() else {
            return;
        };
        c.step(t_s - self.shift_s, measured, pos);
        let p = selector.table().get(GaitKind::Slithering);
        for (x, plane) in pos.iter_mut().zip(&selector.layout().planes) {
            *x += match plane {
                Plane::Lateral => p.offset_lat_rad,
                Plane::Dorsal => p.offset_dor_rad,
            };
        }
        // Without a previous cycle there is nothing to limit against.
        let dt = self.last_t_s.map(|last| (t_s - last).max(0.0));
        let vmax = selector.max_joint_speed_rad_s();
        for ((x, v), &last) in pos.iter_mut().zip(vel.iter_mut()).zip(&self.last_pos) {
            match dt {
                Some(dt) if dt > 0.0 => {
                    let step = (*x - last).clamp(-vmax * dt, vmax * dt);
                    *x = last + step;
                    *v = step / dt;
                }
                Some(_) => {
                    *x = last;
                    *v = 0.0;
                }
                None => *v = 0.0,
            }
        }
        c.compliance_report(&mut self.report);
        let ev = self.report.events;
        self.windows_born += (ev.born_at_head + ev.born_at_tail) as u64;
        self.windows_dropped += (ev.dropped_at_tail + ev.dropped_at_head) as u64;
    }

    /// Fills the telemetry's compliance part.
    pub fn publish(&self, out: &mut ComplianceTelemetry) {
        out.setting = self.setting;
        out.engagement = self.engagement;
        if self.engagement == Engagement::Engaged {
            out.report = self.report;
        } else {
            out.report.clear();
        }
        out.windows_born = self.windows_born;
        out.windows_dropped = self.windows_dropped;
        out.takeovers = self.takeovers;
        out.freed_in_loop = self.freed_in_loop;
    }
}

#[cfg(test)]
#[path = "slithering_driver_tests.rs"]
mod tests;
