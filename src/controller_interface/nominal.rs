//! What a wave controller follows: the gait's nominal parameters and the phase it took
//! over at. Shared by the controllers so each continues the selector's wave the same way.

use super::interface::{Handover, NominalMismatch};
use crate::gait::{BodyLayout, GaitParams, JOINT_LIMIT_RAD, Plane};

/// Nominal parameters and the takeover's phase and time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nominal {
    pub params: GaitParams,
    /// The selector's phase ψ at the takeover, rad, and its time, s.
    pub phase0_rad: f64,
    pub t0_s: f64,
}

impl Nominal {
    /// `params` from phase 0 at t = 0 (before any takeover).
    pub fn new(params: &GaitParams) -> Self {
        Self {
            params: *params,
            phase0_rad: 0.0,
            t0_s: 0.0,
        }
    }

    /// What a takeover hands over.
    pub fn engaged(h: &Handover<'_>) -> Self {
        Self {
            params: *h.params,
            phase0_rad: h.phase_rad,
            t0_s: h.t_s,
        }
    }

    /// The nominal temporal phase at `t_s`: `ψ₀ + ωT·(t − t₀)`.
    pub fn phase_at(&self, t_s: f64) -> f64 {
        self.phase0_rad + self.params.temporal_freq_rad_s * (t_s - self.t0_s)
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
