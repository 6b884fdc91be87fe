//! Skin friction against the world's surfaces: rapier's Coulomb cone where a contact
//! sticks, an explicit Coulomb force where it slides, and the anisotropy on top.
//!
//! Why not rapier's cone alone: rapier solves each contact's two tangent impulses as a
//! coupled 2×2 block and then caps the impulse's magnitude (a radial projection onto the
//! cone). Where the contact's effective mass is anisotropic (a slender link in a
//! jointed chain is), the fixed point of that projection leaves the slip parallel to
//! `K·λ`, not to `λ`: a sliding contact's friction is off the slip's opposite by about
//! 30° on average (measured, independent of iterations, substeps and softness), and
//! open-loop slithering on isotropic ground drifted backwards 0.058 m per cycle where
//! the quasi-static Coulomb model of the same shapes and loads says 0.041
//! (docs/measurements/physics.md, "Slithering on open ground"). So, per skin contact and
//! substep, with `v` the slip at the contact point and `s` = [`slide_share`]`(|v|)` of
//! the slip under the link's centre
//! (0 below [`STICK_BELOW_M_S`], 1 above [`SLIDE_ABOVE_M_S`]):
//! - the hook ([`SkinFriction`]) gives rapier's cone `(1 − s)·µ_min` of the manifold
//!   (µ_min = min(µ_axial, µ_lateral); µ when isotropic): it holds what sticks;
//! - [`PhysicsPlant::apply_skin_friction`] adds `−s·µ_min·N·v̂` at each contact point
//!   (antiparallel to that point's slip, `N` its normal force of the previous
//!   substep) and, if anisotropic, the orthotropic remainder `−N·[(µ_axial − µ_min)·v_a·â
//!   + (µ_lateral − µ_min)·v_l] / max(|v|, v_ε)` (`v_a·â` the slip along the link's
//!   axis, `v_l` across, `v_ε` = [`STICK_SPEED_M_S`] regularising the stick), at most
//!   the impulse that stops the point's slip ([`stopping_impulse`]).
//!
//! Total: the principal-axis anisotropic Coulomb model, the force opposing the slip
//! wherever the contact slides. Poles and pegs of their own coefficient and skin on
//! skin keep rapier's cone (their contacts are not with a skin surface).

use rapier3d::prelude::*;

use super::PhysicsPlant;
use super::build::{TAG_LINK_BASE, TAG_SKIN_SURFACE};
use crate::emu::world::Anisotropic;

/// Slip speed regularising the explicit anisotropic remainder, m/s.
pub const STICK_SPEED_M_S: f32 = 1e-2;
/// Below this slip speed rapier's cone carries all the friction, m/s.
pub const STICK_BELOW_M_S: f32 = 5e-3;
/// Above this slip speed the explicit sliding force carries all of it, m/s.
pub const SLIDE_ABOVE_M_S: f32 = 1.5e-2;

/// The share of the friction given to the explicit sliding force at slip speed
/// `speed` (m/s): 0 at rest, 1 when clearly sliding, linear between.
pub fn slide_share(speed: f32) -> f32 {
    ((speed - STICK_BELOW_M_S) / (SLIDE_ABOVE_M_S - STICK_BELOW_M_S)).clamp(0.0, 1.0)
}

/// The hook (stateless; reads the bodies' velocities from the context).
pub struct SkinFriction {
    pub coefficients: Anisotropic,
    /// False: rapier's cone carries all of `µ_min`
    /// (`PhysicsConfig::explicit_sliding_friction` false).
    pub explicit_sliding: bool,
}

impl SkinFriction {
    fn mu_min(&self) -> f32 {
        self.coefficients.mu_axial.min(self.coefficients.mu_lateral) as f32
    }
}

/// The link and the surface of a link–skin-surface pair, and whether the link is the
/// pair's collider 1.
fn link_and_surface(
    colliders: &ColliderSet,
    c1: ColliderHandle,
    c2: ColliderHandle,
) -> Option<(&Collider, &Collider, bool)> {
    let (a, b) = (colliders.get(c1)?, colliders.get(c2)?);
    let is = |l: &Collider, s: &Collider| {
        l.user_data >= TAG_LINK_BASE && s.user_data == TAG_SKIN_SURFACE
    };
    if is(a, b) {
        Some((a, b, true))
    } else if is(b, a) {
        Some((b, a, false))
    } else {
        None
    }
}

/// Slip velocity of `point` on `link`'s body relative to `surface`'s, in the plane
/// normal to `n`.
fn slip(
    bodies: &RigidBodySet,
    link: &Collider,
    surface: &Collider,
    point: Vector,
    n: Vector,
) -> Vector {
    let of = |c: &Collider| {
        c.parent()
            .and_then(|h| bodies.get(h))
            .map_or(Vector::ZERO, |b| b.velocity_at_point(point))
    };
    let v = of(link) - of(surface);
    v - n * v.dot(n)
}

/// The bottom of `link`'s round section along `n` (pointing into the link): where it
/// touches a surface, seen from its centre.
fn touch_point(link: &Collider, n: Vector) -> Vector {
    link.translation() - n * (0.5 * crate::module::MODULE_DIAMETER_M as f32)
}

/// The largest impulse (N·s) that a force along `dir` at `point` on `body` can give
/// before it has stopped the slip `speed` there, counting the body alone (its mass and
/// its inertia about `point`). An explicit friction is one substep late: uncapped, it
/// reverses a slip it should only have stopped, and a link's roll inertia (m·r²/2) is so
/// small that the reversal became a chatter about the links' own axes among pegs
/// (±1 rad/s). The body alone is the conservative reading: the chain's joints only add
/// effective mass.
fn stopping_impulse(body: &RigidBody, point: Vector, dir: Vector, speed: f32) -> f32 {
    let mp = body.mass_properties();
    let r = point - body.center_of_mass();
    let rxd = r.cross(dir);
    let inv_mass =
        dir.dot(mp.effective_inv_mass * dir) + rxd.dot(mp.effective_world_inv_inertia * rxd);
    if inv_mass > 0.0 {
        speed / inv_mass
    } else {
        0.0
    }
}

/// A manifold's normal (rapier's: from collider 1 to collider 2) turned to point into
/// the link.
fn into_link(normal: Vector, link_is_1: bool) -> Vector {
    if link_is_1 { -normal } else { normal }
}

impl PhysicsHooks for SkinFriction {
    fn modify_solver_contacts(&self, ctx: &mut ContactModificationContext) {
        let Some((link, surface, link_is_1)) =
            link_and_surface(ctx.colliders, ctx.collider1, ctx.collider2)
        else {
            return;
        };
        let bodies = ctx.bodies;
        if let ModifiableContacts::Rigid(m) = &mut ctx.contacts {
            let mu = self.mu_min();
            *m.friction = if self.explicit_sliding {
                let n = into_link(*m.normal, link_is_1);
                let v = slip(bodies, link, surface, touch_point(link, n), n);
                (1.0 - slide_share(v.length())) * mu
            } else {
                mu
            };
        }
    }
}

impl PhysicsPlant {
    /// Adds the explicit part of the skin friction (module docs) for a substep of `h` s.
    pub(super) fn apply_skin_friction(&mut self, h: f64) {
        let Some(hooks) = &self.hooks else {
            return;
        };
        let a = hooks.coefficients;
        let base = hooks.mu_min();
        let (extra_a, extra_l) = (a.mu_axial as f32 - base, a.mu_lateral as f32 - base);
        let anisotropic = extra_a > 0.0 || extra_l > 0.0;
        for (k, &ch) in self.chain.colliders.iter().enumerate() {
            let body_h = self.chain.links[k];
            for pair in self.world.narrow_phase.contact_pairs_with(ch) {
                let Some((link, surface, link_is_1)) =
                    link_and_surface(&self.world.colliders, pair.collider1, pair.collider2)
                else {
                    continue;
                };
                if !pair.has_any_active_contact() {
                    continue;
                }
                let axis = *self.world.bodies[body_h].rotation() * Vector::X;
                for m in pair.manifolds() {
                    let n = into_link(m.data.normal, link_is_1);
                    let at = axis - n * axis.dot(n);
                    // The manifold's share, as the hook decided it (same slip, same point).
                    let s = if hooks.explicit_sliding {
                        let v = slip(&self.world.bodies, link, surface, touch_point(link, n), n);
                        slide_share(v.length())
                    } else {
                        0.0
                    };
                    let points = m.points.iter().filter(|p| p.data.impulse > 0.0).count();
                    for pt in &m.points {
                        let n_force = pt.data.impulse / h as f32;
                        if n_force <= 0.0 {
                            continue;
                        }
                        let local = if link_is_1 { pt.local_p1 } else { pt.local_p2 };
                        let point = *link.position() * local;
                        let v = slip(&self.world.bodies, link, surface, point, n);
                        let speed = v.length();
                        let mut force = Vector::ZERO;
                        if s > 0.0 && speed > 0.0 {
                            force -= v * (s * base * n_force / speed);
                        }
                        if anisotropic && at.length() > 1e-6 {
                            let at = at / at.length();
                            let va = v.dot(at);
                            let vl = v - at * va;
                            force -= (at * (extra_a * va) + vl * extra_l)
                                * (n_force / speed.max(STICK_SPEED_M_S));
                        }
                        // The manifold's points share the link's stopping impulse.
                        let magnitude = force.length();
                        if magnitude > 0.0 {
                            let body = &self.world.bodies[body_h];
                            let cap = stopping_impulse(body, point, force / magnitude, speed)
                                / (points as f32 * h as f32);
                            if magnitude > cap {
                                force *= cap / magnitude;
                            }
                        }
                        self.world.bodies[body_h].add_force_at_point(force, point, false);
                    }
                }
            }
        }
    }
}
