//! Anisotropic skin friction through rapier's contact modification hook.
//!
//! Rapier holds one friction coefficient per contact manifold and caps the tangent
//! impulse by its magnitude (a true Coulomb cone with the Coulomb friction model).
//! For anisotropic skin the hook picks that coefficient per manifold and per step from
//! the direction the link slides relative to its own axis: with `c`, `s` the cosine
//! and sine between the tangential sliding velocity and the link's axis (projected on
//! the contact plane), `μ = sqrt((μ_axial·c)² + (μ_lateral·s)²)` (the ellipse's
//! radius along the sliding direction). Below [`STICK_SPEED_M_S`] the direction is
//! undefined and the larger coefficient holds. Poles keep their own isotropic `mu`.
//! This is a per-manifold approximation: the friction force stays antiparallel to the
//! slip (an exact elliptical cone would tilt it toward the low-friction axis).

use rapier3d::prelude::*;

use super::build::{TAG_LINK_BASE, TAG_SKIN_SURFACE};
use crate::emu::world::Anisotropic;

/// Sliding speed below which the contact counts as sticking, m/s.
pub const STICK_SPEED_M_S: f32 = 1e-3;

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
        // Which side is the snake's link, which the skin surface.
        let (link_body, normal_sign) =
            if c1.user_data >= TAG_LINK_BASE && c2.user_data == TAG_SKIN_SURFACE {
                (ctx.rigid_body1, 1.0)
            } else if c2.user_data >= TAG_LINK_BASE && c1.user_data == TAG_SKIN_SURFACE {
                (ctx.rigid_body2, -1.0)
            } else {
                return;
            };
        let Some(body) = link_body.and_then(|h| ctx.bodies.get(h)) else {
            return;
        };
        let ModifiableContacts::Rigid(m) = &mut ctx.contacts else {
            return;
        };
        let Some(contact) = m.solver_contacts.first() else {
            return;
        };
        let point = if normal_sign > 0.0 {
            contact.anchor1
        } else {
            contact.anchor2
        };
        let n = *m.normal;
        // The world is static: the slip is the link's own velocity at the contact.
        let vel = body.velocity_at_point(point);
        let slip = vel - n * vel.dot(n);
        let (ma, ml) = (
            self.coefficients.mu_axial as f32,
            self.coefficients.mu_lateral as f32,
        );
        let speed = slip.length();
        let mu = if speed < STICK_SPEED_M_S {
            ma.max(ml)
        } else {
            let axis = body.rotation() * Vector::X;
            let axis_t = axis - n * axis.dot(n);
            let al = axis_t.length();
            if al < 1e-6 {
                ml
            } else {
                let c = slip.dot(axis_t) / (speed * al);
                let s2 = (1.0 - c * c).max(0.0);
                ((ma * c).powi(2) + ml * ml * s2).sqrt()
            }
        };
        *m.friction = mu;
    }
}
