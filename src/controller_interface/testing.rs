//! Helpers for testing controllers outside the loop (unit tests, benches, the
//! allocation tests): observations of scripted torques, and engaging a controller as
//! if the selector had run its gait from t = 0.

use super::interface::{BodyEstimate, Controller, Handover, Imu, Observation, TickClock};
use crate::gait::{BodyLayout, GaitParams};

/// Storage for the parts of an observation a test does not script.
pub struct ObservationBuf {
    velocity: Vec<f64>,
    imu: Vec<Imu>,
    body: BodyEstimate,
}

impl ObservationBuf {
    pub fn new(joints: usize) -> Self {
        Self {
            velocity: vec![0.0; joints],
            // At rest: the accelerometers read gravity (up along each module's z).
            imu: vec![
                Imu {
                    accel_m_s2: [0.0, 0.0, 9.81],
                    gyro_rad_s: [0.0; 3],
                };
                joints
            ],
            body: BodyEstimate::default(),
        }
    }

    /// Positions and reported torques as given; zero velocities, resting IMUs, no
    /// body estimate.
    pub fn observe<'a>(&'a self, position_rad: &'a [f64], torque_nm: &'a [f64]) -> Observation<'a> {
        Observation {
            position_rad,
            velocity_rad_s: &self.velocity,
            torque_nm,
            imu: &self.imu,
            body: &self.body,
        }
    }
}

/// Runs `c` for `seconds` at 1 kHz from t = 0 with the body held straight and the
/// reported torques of each step `torque(set_points)` of the one before; returns the
/// last set-points.
pub fn run_with_torques<const N: usize>(
    c: &mut dyn Controller,
    seconds: f64,
    torque: impl Fn(&[f64]) -> [f64; N],
) -> Vec<f64> {
    let buf = ObservationBuf::new(N);
    let (pos, mut tau, mut out) = ([0.0; N], [0.0; N], vec![0.0; N]);
    let mut clock = TickClock::default();
    for k in 0..(seconds * 1000.0) as usize {
        c.step(
            clock.tick(k as f64 * 1e-3),
            &buf.observe(&pos, &tau),
            &mut out,
        );
        tau = torque(&out);
    }
    out
}

/// Handed-over set-points of a straight body (up to this many joints).
static STRAIGHT: [f64; 1024] = [0.0; 1024];

/// Engages `c` at `t_s` with the phase the selector would have reached by then running
/// `params` from phase 0 (`ωT·t_s`), so its output continues the open-loop gait.
/// Allocates nothing (bodies of up to 1024 joints).
pub fn engage_at(c: &mut dyn Controller, layout: &BodyLayout, params: &GaitParams, t_s: f64) {
    c.engage(&Handover {
        t_s,
        phase_rad: params.temporal_freq_rad_s * t_s,
        set_points_rad: &STRAIGHT[..layout.len()],
        params,
        layout,
    });
}

/// A report spec with two signals and one windowed field, for tests of what consumes
/// reports (telemetry views, the recorder).
pub fn sample_report_spec() -> super::report::ReportSpec {
    use super::report::{FieldSpec, ReportSpec, SignalSpec};
    ReportSpec {
        signals: vec![
            SignalSpec::new("amplitude_mean_rad", "rad"),
            SignalSpec::new("windows", "count"),
        ],
        fields: vec![FieldSpec {
            name: "amplitude".into(),
            centralization: "windowed".into(),
            enabled: true,
            columns: vec![
                SignalSpec::new("value", "rad"),
                SignalSpec::new("force", "N"),
            ],
        }],
    }
}
