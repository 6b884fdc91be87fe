//! The fusion on synthetic runs: the body's own estimate (contact odometry that may
//! drift, a heading) and a source whose world is the estimate's turned and shifted,
//! with latency, noise, dropouts, outliers and a re-based world.

use super::*;
use crate::estimation::external_pose::{ExternalFix, PoseInput, pose_input};

const DT: f64 = 1e-3;
/// The source's world: the estimate's turned by PSI and shifted by SHIFT.
const PSI: f64 = 0.5;
const SHIFT: [f64; 2] = [2.0, -1.0];

/// A body moving along a gentle arc at 0.1 m/s; its own odometry drifts sideways at
/// `drift` m/s.
struct Run {
    e: WorldPositionEstimator,
    input: PoseInput,
    t: f64,
    drift: f64,
    /// Fixes every this many cycles, measured `latency` before they arrive.
    every: u64,
    latency: f64,
    orientation: bool,
    cycle: u64,
    /// The source's rebase (added to every fix from now on).
    rebase: [f64; 2],
    /// A jump the odometry reads (added to it from now on: motion that never was).
    jump: [f64; 2],
    body: BodyEstimate,
}

/// The chassis' true position and heading in the estimate's world at `t`.
fn truth(t: f64) -> ([f64; 2], f64) {
    let heading = 0.05 * t;
    let r = 0.1 / 0.05;
    ([r * heading.sin(), r * (1.0 - heading.cos())], heading)
}

fn to_source(p: [f64; 2]) -> [f64; 2] {
    let r = rotate(PSI, p);
    [r[0] + SHIFT[0], r[1] + SHIFT[1]]
}

impl Run {
    fn new(config: FusionConfig, every: u64, latency: f64, orientation: bool) -> Self {
        let (input, reader) = pose_input(None);
        Self {
            e: WorldPositionEstimator::new(reader, config),
            input,
            t: 0.0,
            drift: 0.0,
            every,
            latency,
            orientation,
            cycle: 0,
            rebase: [0.0; 2],
            jump: [0.0; 2],
            body: BodyEstimate::NONE,
        }
    }

    /// Runs `seconds`, fixes on while `fixes`; returns the largest position error
    /// while tracking (against the truth in the source's world).
    fn run(&mut self, seconds: f64, fixes: bool) -> f64 {
        let mut worst: f64 = 0.0;
        let end = self.t + seconds;
        while self.t < end {
            self.t += DT;
            self.cycle += 1;
            let (p, heading) = truth(self.t);
            let q = [(heading / 2.0).cos(), 0.0, 0.0, (heading / 2.0).sin()];
            self.body = BodyEstimate {
                valid: true,
                odometry_m: [
                    p[0] + self.jump[0],
                    p[1] + self.drift * self.t + self.jump[1],
                ],
                heading_rad: heading,
                orientation_wxyz: q,
                head_wxyz: q,
                ..BodyEstimate::NONE
            };
            let t_meas = self.t - self.latency;
            if fixes && self.cycle.is_multiple_of(self.every) && t_meas > 0.0 {
                let (pm, hm) = truth(t_meas);
                let s = to_source(pm);
                let yaw = hm + PSI;
                let fix = ExternalFix {
                    stamp_unix_ns: 0,
                    position_m: [s[0] + self.rebase[0], s[1] + self.rebase[1], 0.0],
                    orientation_wxyz: self
                        .orientation
                        .then(|| [(yaw / 2.0).cos(), 0.0, 0.0, (yaw / 2.0).sin()]),
                    position_sd_m: Some(0.002),
                    source: "test".into(),
                };
                self.input.write_loop_time(t_meas, &fix, 0).unwrap();
            }
            let obs = Observation::NONE;
            self.e.update(self.t, &obs, &mut self.body);
            let w = self.body.world;
            if w.valid() {
                let s = to_source(p);
                let s = [s[0] + self.rebase[0], s[1] + self.rebase[1]];
                worst = worst.max((w.position_m[0] - s[0]).hypot(w.position_m[1] - s[1]));
            }
        }
        worst
    }

    fn world(&self) -> WorldPosition {
        self.body.world
    }
}

#[test]
fn a_motion_capture_source_is_tracked_with_its_latency_compensated() {
    // 100 Hz, 15 ms late, the body's odometry drifting 5 cm/s sideways.
    let mut r = Run::new(FusionConfig::default(), 10, 0.015, true);
    r.drift = 0.05;
    let worst = r.run(0.2, true);
    let w = r.world();
    assert_eq!(w.state, PositionState::Tracking, "{w:?}");
    assert!((w.yaw_offset_rad - PSI).abs() < 1e-6, "{w:?}");
    let worst = worst.max(r.run(20.0, true));
    assert!(worst < 0.005, "worst error {worst} m");
    let w = r.world();
    // The velocity in the source's world: 0.1 m/s along the heading turned by ψ (plus
    // what the odometry's drift has not been corrected of between fixes).
    let speed = w.velocity_m_s[0].hypot(w.velocity_m_s[1]);
    assert!((speed - 0.1).abs() < 0.01, "{w:?}");
    let (_, heading) = truth(r.t);
    assert!((w.heading_rad - wrap_pi(heading + PSI)).abs() < 1e-6);
    assert_eq!(w.rejected, 0);
    assert!(w.accepted > 1900, "{w:?}");
}

#[test]
fn the_latency_matters_and_is_compensated() {
    // 100 ms late at 0.1 m/s: 1 cm behind if the fix were taken as of its arrival.
    let mut r = Run::new(FusionConfig::default(), 100, 0.1, true);
    let worst = r.run(10.0, true);
    assert!(worst < 0.002, "worst error {worst} m");
}

#[test]
fn a_source_that_stops_goes_stale_and_resumes() {
    let mut r = Run::new(FusionConfig::default(), 10, 0.015, true);
    r.drift = 0.05;
    r.run(2.0, true);
    assert!(r.world().valid());
    // Occluded for 2 s: stale after max_age_s, never a stale position as valid.
    r.run(0.4, false);
    assert_eq!(r.world().state, PositionState::Tracking);
    r.run(1.6, false);
    let w = r.world();
    assert_eq!(w.state, PositionState::Stale, "{w:?}");
    assert!(!w.valid() && w.age_s > 1.9);
    // Back: tracking again, the drift since corrected by the next fixes.
    let worst = r.run(2.0, true);
    assert!(r.world().valid());
    assert!(
        worst < 0.12,
        "the first fix after the gap corrects 10 cm of drift: {worst}"
    );
    assert!(r.run(1.0, true) < 0.005);
}

#[test]
fn outliers_are_rejected_and_a_rebased_source_is_aligned_afresh() {
    let mut r = Run::new(FusionConfig::default(), 10, 0.015, true);
    r.run(1.0, true);
    // One wild fix (a marker swap): rejected, the position unmoved.
    r.rebase = [1.0, 0.0];
    r.run(0.01, true);
    r.rebase = [0.0, 0.0];
    let worst = r.run(1.0, true);
    let w = r.world();
    assert_eq!(w.rejected, 1, "{w:?}");
    assert!(worst < 0.005, "{worst}");
    // The source re-based its world by 2 m: ten rejections, then aligned afresh.
    r.rebase = [0.0, 2.0];
    r.run(0.5, true);
    let w = r.world();
    assert_eq!(w.alignments, 2, "{w:?}");
    assert_eq!(w.rejected, 11, "{w:?}");
    assert!(r.run(1.0, true) < 0.005);
}

#[test]
fn a_position_only_source_aligns_once_the_body_has_moved() {
    let mut r = Run::new(FusionConfig::default(), 10, 0.015, false);
    r.run(2.0, true);
    assert_eq!(r.world().state, PositionState::Aligning, "0.2 m travelled");
    r.run(2.0, true);
    let w = r.world();
    assert_eq!(w.state, PositionState::Tracking, "{w:?}");
    assert!((w.yaw_offset_rad - PSI).abs() < 0.02, "{w:?}");
    assert!(r.run(5.0, true) < 0.01);
}

#[test]
fn a_marker_on_the_head_is_tracked_at_its_offset() {
    let config = FusionConfig {
        tracked: Tracked::Head,
        marker_offset_m: [0.05, 0.0],
        ..FusionConfig::default()
    };
    let (input, reader) = pose_input(None);
    let mut e = WorldPositionEstimator::new(reader, config);
    let obs = Observation::NONE;
    // The chassis at (1, 0) facing +y; the head 0.4 m ahead of it (+y), turned as it.
    let q = [
        std::f64::consts::FRAC_PI_4.cos(),
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_4.sin(),
    ];
    let mut b = BodyEstimate {
        valid: true,
        odometry_m: [1.0, 0.0],
        position_m: [0.0, -0.4, 0.0],
        heading_rad: std::f64::consts::FRAC_PI_2,
        orientation_wxyz: q,
        head_wxyz: q,
        ..BodyEstimate::NONE
    };
    e.update(0.001, &obs, &mut b);
    // The source (the same world) sees the marker 5 cm ahead of the head: (1, 0.45).
    let fix = ExternalFix {
        stamp_unix_ns: 0,
        position_m: [1.0, 0.45, 0.0],
        orientation_wxyz: Some(q),
        position_sd_m: None,
        source: "test".into(),
    };
    input.write_loop_time(0.001, &fix, 0).unwrap();
    e.update(0.002, &obs, &mut b);
    let w = b.world;
    assert!(w.valid(), "{w:?}");
    assert!(w.yaw_offset_rad.abs() < 1e-9, "{w:?}");
    assert!(
        (w.position_m[0] - 1.0).abs() < 1e-9 && w.position_m[1].abs() < 1e-9,
        "{w:?}"
    );
}

#[test]
fn a_fix_from_before_the_history_is_late() {
    // 3 s late, more than the 2 s of history: each one counted late, none taken.
    let mut r = Run::new(FusionConfig::default(), 10, 3.0, true);
    r.run(3.5, true);
    let w = r.world();
    assert_eq!(
        (w.late, w.accepted, w.state),
        (50, 0, PositionState::None),
        "{w:?}"
    );
}

/// Contact odometry among pegs jumps when the links' contacts change. The fused position
/// follows the jump until the next fix, which then corrects it: the jump widens the
/// gate, so the fix is not rejected as an outlier (without `drift_per_m` it was, for
/// ten fixes, a second of a position 0.3 m off at 10 Hz).
#[test]
fn an_odometry_jump_is_corrected_by_the_next_fix_not_followed() {
    let error_after_jump = |config: FusionConfig| {
        // 10 Hz, 100 ms late, as the lab's degraded source.
        let mut r = Run::new(config, 100, 0.1, true);
        r.run(5.0, true);
        assert_eq!(r.world().state, PositionState::Tracking);
        r.jump = [0.3, 0.0];
        r.run(0.35, true);
        let (p, _) = truth(r.t);
        let s = to_source(p);
        let w = r.world();
        (w.position_m[0] - s[0]).hypot(w.position_m[1] - s[1])
    };
    let now = error_after_jump(FusionConfig::default());
    assert!(now < 0.05, "{now} m off after three fixes");
    let before = error_after_jump(FusionConfig {
        drift_per_m: 0.0,
        ..FusionConfig::default()
    });
    assert!(before > 0.2, "without it: {before} m off");
}
