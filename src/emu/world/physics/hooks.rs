//! Anisotropic skin friction: rapier's Coulomb cone for the lower coefficient, plus the
//! rest as an explicit sliding force.
//!
//! Rapier holds one friction coefficient per contact manifold and caps the tangent
//! impulse by its magnitude (a true cone). A single coefficient chosen from the slip
//! direction (the ellipse's radius along it) keeps the force antiparallel to the slip,
//! so a body sliding mostly sideways feels `μ_lateral` along its axis too, and
//! undulation gets no thrust from the anisotropy (measured: slithering still drifted
//! backwards). So:
//! - the hook ([`AnisotropicFriction`]) sets each skin manifold's coefficient to
//!   `μ_min = min(μ_axial, μ_lateral)`: rapier's cone handles sticking and sliding;
//! - [`PhysicsPlant::apply_anisotropic_friction`] adds, per link contact and
//!   substep, the orthotropic remainder `−N·[(μ_axial − μ_min)·v_a·â + (μ_lateral −
//!   μ_min)·v_l] / max(|v_t|, v_ε)` at the contact, with `N` the contact's normal force
//!   of the previous substep, `v_t` the tangential slip split into its component along
//!   the link's axis `v_a·â` and across it `v_l`, and `v_ε` = [`STICK_SPEED_M_S`]
//!   regularising the stick (the remainder fades to zero at rest, where rapier's cone
//!   of `μ_min` holds alone). Total: the principal-axis anisotropic Coulomb model.
//!
//! Poles keep their own isotropic `mu`, and so does skin on skin (a link against
//! another, with self-collision): both touch at the world's `friction.mu`, from the
//! colliders' combine rules (`build.rs`), so neither the hook nor the remainder
//! touches those manifolds. The anisotropy belongs to the skin sliding over the
//! ground along or across its own axis; two links have an axis each, and sleeve on
//! sleeve is taken as the sleeve's base coefficient.

use rapier3d::prelude::*;

use super::PhysicsPlant;
use super::build::{TAG_LINK_BASE, TAG_SKIN_SURFACE};
use crate::emu::world::Anisotropic;

/// Slip speed regularising the explicit remainder, m/s.
pub const STICK_SPEED_M_S: f32 = 1e-2;

/// The hook (stateless; reads the bodies' velocities from the context).
pub struct AnisotropicFriction {
    pub coefficients: Anisotropic,
}

impl PhysicsHooks for AnisotropicFriction {
    fn modify_solver_contacts(&self, ctx: &mut ContactModificationContext) {
        let (Some(c1), Some(c2)) = (
            ctx.colliders.get(ctx.collider1),
            ctx.colliders.get(ctx.collider2),
        ) else {
            return;
        };
        // Only link against a world surface: link–link manifolds keep `mu`.
        let link_and_skin = |a: &Collider, b: &Collider| {
            a.user_data >= TAG_LINK_BASE && b.user_data == TAG_SKIN_SURFACE
        };
        if !(link_and_skin(c1, c2) || link_and_skin(c2, c1)) {
            return;
        }
        if let ModifiableContacts::Rigid(m) = &mut ctx.contacts {
            let a = self.coefficients;
            *m.friction = a.mu_axial.min(a.mu_lateral) as f32;
        }
    }
}

impl PhysicsPlant {
    /// Adds the explicit orthotropic remainder of the skin friction (module docs).
    pub(super) fn apply_anisotropic_friction(&mut self, h: f64) {
        let Some(hooks) = &self.hooks else {
            return;
        };
        let a = hooks.coefficients;
        let base = a.mu_axial.min(a.mu_lateral) as f32;
        let (extra_a, extra_l) = (a.mu_axial as f32 - base, a.mu_lateral as f32 - base);
        let radius = 0.5 * super::build::MODULE_DIAMETER_M as f32;
        for (k, &ch) in self.chain.colliders.iter().enumerate() {
            let link = self.chain.links[k];
            for pair in self.world.narrow_phase.contact_pairs_with(ch) {
                let other = if pair.collider1 == ch {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(oc) = self.world.colliders.get(other) else {
                    continue;
                };
                if oc.user_data != TAG_SKIN_SURFACE || !pair.has_any_active_contact() {
                    continue;
                }
                let imp = pair.total_impulse();
                let n_force = imp.length() / h as f32;
                if n_force <= 0.0 {
                    continue;
                }
                let body = &self.world.bodies[link];
                // The surface's body (fixed for every surface `build_world` makes, but
                // the slip is taken relative to it all the same).
                let surface = oc.parent().and_then(|h| self.world.bodies.get(h));
                let centre = body.translation();
                // Normal into the link (the side of the obstacle it is on).
                let mut n = imp / imp.length();
                if n.dot(centre - oc.translation()) < 0.0 {
                    n = -n;
                }
                let point = centre - n * radius;
                let v = body.velocity_at_point(point)
                    - surface.map_or(Vector::ZERO, |b| b.velocity_at_point(point));
                let vt = v - n * v.dot(n);
                let axis = *body.rotation() * Vector::X;
                let at = axis - n * axis.dot(n);
                if at.length() < 1e-6 {
                    continue;
                }
                let at = at / at.length();
                let va = vt.dot(at);
                let vl = vt - at * va;
                let scale = n_force / vt.length().max(STICK_SPEED_M_S);
                let force = -(at * (extra_a * va) + vl * extra_l) * scale;
                self.world.bodies[link].add_force_at_point(force, point, false);
            }
        }
    }
}
