//! What a wave controller follows: the gait's nominal parameters and the phase it took
//! over at. Shared by the controllers so each continues the selector's wave the same way,
//! and follows the operator's changes of the parameters the same way: a change while
//! engaged ([`Nominal::follow`]) ramps every field from where it is to the new value by
//! the daemon's smoothstep, no faster than the joints can follow
//! ([`FOLLOW_JOINT_RATE_RAD_S`], [`FOLLOW_ACCEL_RAD_S2`]); the temporal phase is the
//! integral of the ramped ωT, so it stays continuous (C1) through any change of speed.

use super::interface::{Handover, NominalMismatch};
use crate::gait::params::Field;
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};

/// How fast a followed change may move a joint by itself (amplitude, offset, spatial
/// frequency, phase shift, taper), rad/s at the ramp's steepest: about a seventh of
/// the SEA module's speed, leaving the rest to the wave.
pub const FOLLOW_JOINT_RATE_RAD_S: f64 = 0.5;
/// How fast a followed change of ωT changes it at the ramp's steepest, rad/s².
pub const FOLLOW_ACCEL_RAD_S2: f64 = 4.0;
/// The shortest ramp, s, and the one for the helix's radius and pitch (whose effect on
/// the joints is not linear).
pub const FOLLOW_MIN_S: f64 = 0.2;
pub const FOLLOW_HELIX_S: f64 = 1.0;

/// One ramp of the nominal parameters: from `from` at `t0_s` (phase `phase0_rad`) to
/// `to` over `duration_s` (0: none, `from == to`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ramp {
    t0_s: f64,
    phase0_rad: f64,
    from: GaitParams,
    to: GaitParams,
    duration_s: f64,
}

impl Ramp {
    fn steady(params: &GaitParams, t0_s: f64, phase0_rad: f64) -> Self {
        Self {
            t0_s,
            phase0_rad,
            from: *params,
            to: *params,
            duration_s: 0.0,
        }
    }

    /// Ramp progress at `t_s`, 0..1.
    fn u(&self, t_s: f64) -> f64 {
        if self.duration_s > 0.0 {
            ((t_s - self.t0_s) / self.duration_s).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    fn values_at(&self, t_s: f64) -> GaitParams {
        let u = self.u(t_s);
        if u >= 1.0 {
            return self.to;
        }
        let w = u * u * (3.0 - 2.0 * u);
        let mut p = self.from;
        for f in Field::ALL {
            let (a, b) = (f.get(&self.from), f.get(&self.to));
            f.set(&mut p, a + (b - a) * w);
        }
        p
    }

    /// `ψ₀ + ∫ ωT dt` from the ramp's start: ωT rises by smoothstep, whose integral
    /// over `[0, u]` is `u³ − u⁴/2` (half the ramp's time at its end). Before the
    /// ramp's start the first speed extends backwards.
    fn phase_at(&self, t_s: f64) -> f64 {
        let (w0, w1) = (self.from.temporal_freq_rad_s, self.to.temporal_freq_rad_s);
        let dt = t_s - self.t0_s;
        if dt <= 0.0 || self.duration_s <= 0.0 {
            let w = if dt <= 0.0 { w0 } else { w1 };
            return self.phase0_rad + w * dt;
        }
        let d = self.duration_s;
        if dt < d {
            let u = dt / d;
            self.phase0_rad + w0 * dt + (w1 - w0) * d * (u * u * u - 0.5 * u * u * u * u)
        } else {
            self.phase0_rad + w0 * d + 0.5 * (w1 - w0) * d + w1 * (dt - d)
        }
    }
}

/// How long a followed change from `a` to `b` ramps, s: the steepest field sets it.
pub fn follow_time_s(a: &GaitParams, b: &GaitParams) -> f64 {
    let reach = a
        .amplitude_lat_rad
        .abs()
        .max(a.amplitude_dor_rad.abs())
        .max(b.amplitude_lat_rad.abs())
        .max(b.amplitude_dor_rad.abs());
    let dor = a.amplitude_dor_rad.abs().max(b.amplitude_dor_rad.abs());
    let mut d = FOLLOW_MIN_S;
    for f in Field::ALL {
        let delta = (f.get(b) - f.get(a)).abs();
        if delta == 0.0 {
            continue;
        }
        // Joint angle per unit of the field, at most.
        let per_unit = match f {
            Field::AmplitudeLat | Field::AmplitudeDor | Field::OffsetLat | Field::OffsetDor => 1.0,
            Field::SpatialFreq | Field::Taper => reach,
            Field::PhaseShift => dor,
            Field::TemporalFreq => {
                d = d.max(1.5 * delta / FOLLOW_ACCEL_RAD_S2);
                continue;
            }
            Field::HelixRadius | Field::HelixPitch => {
                d = d.max(FOLLOW_HELIX_S);
                continue;
            }
        };
        // Smoothstep's steepest slope is 1.5 times the mean.
        d = d.max(1.5 * delta * per_unit / FOLLOW_JOINT_RATE_RAD_S);
    }
    d
}

/// Nominal parameters, the takeover's phase and time, and the ramp of a followed change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nominal {
    /// The nominal parameters as of the last [`Nominal::advance`] (mid-ramp after a
    /// followed change; the operator's once it has ended).
    pub params: GaitParams,
    /// The selector's phase ψ at the takeover, rad, and its time, s.
    pub phase0_rad: f64,
    pub t0_s: f64,
    ramp: Ramp,
}

impl Nominal {
    /// `params` from phase 0 at t = 0 (before any takeover).
    pub fn new(params: &GaitParams) -> Self {
        Self {
            params: *params,
            phase0_rad: 0.0,
            t0_s: 0.0,
            ramp: Ramp::steady(params, 0.0, 0.0),
        }
    }

    /// What a takeover hands over.
    pub fn engaged(h: &Handover<'_>) -> Self {
        Self::at_phase(h.params, h.phase_rad, h.t_s)
    }

    /// `params` from phase `phase0_rad` at `t0_s`.
    pub fn at_phase(params: &GaitParams, phase0_rad: f64, t0_s: f64) -> Self {
        Self {
            params: *params,
            phase0_rad,
            t0_s,
            ramp: Ramp::steady(params, t0_s, phase0_rad),
        }
    }

    /// The operator's nominal parameters (where a ramp ends).
    pub fn target(&self) -> &GaitParams {
        &self.ramp.to
    }

    /// Follows a change to `params` from `t_s`: a new ramp from the values and phase at
    /// `t_s` (mid-ramp too), so nothing jumps. Returns the ramp's duration, s.
    pub fn follow(&mut self, t_s: f64, params: &GaitParams) -> f64 {
        let from = self.ramp.values_at(t_s);
        let phase0_rad = self.ramp.phase_at(t_s);
        let duration_s = follow_time_s(&from, params);
        self.ramp = Ramp {
            t0_s: t_s,
            phase0_rad,
            from,
            to: *params,
            duration_s,
        };
        duration_s
    }

    /// Whether a followed change is still ramping at `t_s`.
    pub fn ramping(&self, t_s: f64) -> bool {
        self.ramp.u(t_s) < 1.0
    }

    /// Moves [`Nominal::params`] to their values at `t_s` (each step, before reading them).
    pub fn advance(&mut self, t_s: f64) {
        self.params = self.ramp.values_at(t_s);
    }

    /// The nominal parameters at `t_s`.
    pub fn params_at(&self, t_s: f64) -> GaitParams {
        self.ramp.values_at(t_s)
    }

    /// The nominal temporal phase at `t_s`: `ψ₀ + ∫ωT dt` (`ψ₀ + ωT·(t − t₀)` without a
    /// followed change).
    pub fn phase_at(&self, t_s: f64) -> f64 {
        self.ramp.phase_at(t_s)
    }

    /// Adds the steering offsets of each joint's plane to `set_points_rad`.
    pub fn add_offsets(&self, layout: &BodyLayout, set_points_rad: &mut [f64]) {
        for (x, plane) in set_points_rad.iter_mut().zip(&layout.planes) {
            *x += match plane {
                Plane::Lateral => self.params.offset_lat_rad,
                Plane::Dorsal => self.params.offset_dor_rad,
            };
        }
    }
}

/// `value` of `field` must lie in `[min, max]`.
pub fn within(field: &'static str, value: f64, min: f64, max: f64) -> Result<(), NominalMismatch> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(NominalMismatch {
            field,
            value,
            min,
            max,
        })
    }
}

/// The lateral offset of `params` must leave room in the joints' range for a lateral
/// amplitude of up to `reach_rad`.
pub fn lateral_room(params: &GaitParams, reach_rad: f64) -> Result<(), NominalMismatch> {
    let room = JOINT_LIMIT_RAD - reach_rad;
    within("offset_lat_rad", params.offset_lat_rad, -room, room)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slithering() -> GaitParams {
        GaitParams::default_for(crate::gait::GaitKind::Slithering)
    }

    /// Issue 45: a followed change, even one arriving mid-ramp, moves neither the
    /// phase nor the parameters by a jump, and ωT (the phase's slope) is continuous.
    #[test]
    fn a_followed_change_is_continuous_in_value_phase_and_speed() {
        let p = slithering();
        let mut n = Nominal::new(&p);
        n.ramp = Ramp::steady(&p, 1.0, 0.3);
        let dt = 1e-3;
        let mut t = 1.0;
        let (mut last_phase, mut last_speed) = (n.phase_at(t), p.temporal_freq_rad_s);
        let mut last_amp = p.amplitude_lat_rad;
        for k in 0..7000 {
            // A new speed every 0.5 s for 6 s, and an amplitude and offset change once.
            if k % 500 == 0 && k < 6000 {
                let mut q = *n.target();
                q.temporal_freq_rad_s = if (k / 500) % 2 == 0 { 2.0 } else { 0.5 };
                if k == 1500 {
                    q.amplitude_lat_rad += 0.3;
                    q.offset_lat_rad = 0.2;
                }
                let d = n.follow(t, &q);
                assert!(d >= FOLLOW_MIN_S, "{d}");
            }
            t += dt;
            let phase = n.phase_at(t);
            let speed = (phase - last_phase) / dt;
            assert!(
                (speed - last_speed).abs() < 0.05,
                "ωT jumps at {t}: {last_speed} -> {speed}"
            );
            n.advance(t);
            let amp = n.params.amplitude_lat_rad;
            assert!(
                (amp - last_amp).abs() <= 1.6 * FOLLOW_JOINT_RATE_RAD_S * dt,
                "the amplitude moves faster than the follow rate at {t}"
            );
            (last_phase, last_speed, last_amp) = (phase, speed, amp);
        }
        assert!(!n.ramping(t));
        assert_eq!(n.params, *n.target());
    }

    /// Over a whole ramp the phase gains the mean of the two speeds times its time.
    #[test]
    fn the_phase_through_a_ramp_is_the_integral_of_the_speed() {
        let mut p = slithering();
        p.temporal_freq_rad_s = 1.0;
        let mut n = Nominal::new(&p);
        let mut q = p;
        q.temporal_freq_rad_s = 3.0;
        let d = n.follow(0.0, &q);
        assert_eq!(d, (1.5 * 2.0 / FOLLOW_ACCEL_RAD_S2).max(FOLLOW_MIN_S));
        assert!((n.phase_at(d) - 2.0 * d).abs() < 1e-12);
        assert!((n.phase_at(d + 1.0) - (2.0 * d + 3.0)).abs() < 1e-12);
        // Numerically: the trapezoid rule over the ramp agrees.
        let steps = 10_000;
        let h = d / steps as f64;
        let integral: f64 = (0..steps)
            .map(|k| {
                0.5 * h
                    * (n.params_at(k as f64 * h).temporal_freq_rad_s
                        + n.params_at((k + 1) as f64 * h).temporal_freq_rad_s)
            })
            .sum();
        assert!((integral - n.phase_at(d)).abs() < 1e-6, "{integral}");
    }

    #[test]
    fn bigger_changes_ramp_longer() {
        let p = slithering();
        let mut q = p;
        q.offset_lat_rad = 0.25;
        let small = follow_time_s(&p, &q);
        q.offset_lat_rad = 0.5;
        assert!(follow_time_s(&p, &q) > small);
        assert_eq!(follow_time_s(&p, &p), FOLLOW_MIN_S);
    }

    #[test]
    fn an_offset_with_no_room_says_why_not_an_inverted_range() {
        let mut p = GaitParams::default();
        let ok = lateral_room(&p, 1.2);
        assert!(ok.is_ok());
        p.offset_lat_rad = 0.5;
        let e = lateral_room(&p, 1.2).unwrap_err().to_string();
        assert!(
            e.contains("offset_lat_rad = 0.5") && e.contains("[-0.37"),
            "{e}"
        );
        p.offset_lat_rad = 0.0;
        let e = lateral_room(&p, 1.8).unwrap_err().to_string();
        assert!(e.contains("exceeds the joint limit"), "{e}");
    }

    /// Issue 25: the room is exact: its printed end is accepted, the next double is not.
    #[test]
    fn the_offset_s_room_is_exact_and_printed_as_it_is() {
        let mut p = GaitParams {
            offset_lat_rad: 1.0,
            ..GaitParams::default()
        };
        let e = lateral_room(&p, 1.2).unwrap_err();
        assert_eq!(e.max, JOINT_LIMIT_RAD - 1.2);
        let printed = e.to_string();
        let max: f64 = printed
            .rsplit(", ")
            .next()
            .unwrap()
            .trim_end_matches(']')
            .parse()
            .unwrap();
        assert_eq!(max, e.max, "{printed}");
        p.offset_lat_rad = max;
        assert!(lateral_room(&p, 1.2).is_ok());
        p.offset_lat_rad = max.next_up();
        assert!(lateral_room(&p, 1.2).is_err(), "one ulp beyond");
        p.offset_lat_rad = 1e308;
        let e = lateral_room(&p, 1.2).unwrap_err().to_string();
        assert!(e.contains("1e308") && e.len() < 120, "{e}");
    }
}
