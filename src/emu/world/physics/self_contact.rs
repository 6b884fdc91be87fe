//! Counting self-contacts: onsets of touching between two links that are not joined by
//! a joint (with the collision groups of `build.rs` only links 3 or more apart meet).
//!
//! A pair *touches* once its deepest contact point reaches the surface (distance ≤ 0)
//! and counts as apart again only when that distance exceeds [`SEPARATION_M`] or the
//! broad phase drops the pair: a contact that rests or slides, chattering around zero,
//! counts once. Rapier's own `has_any_active_contact` also holds for speculative
//! contacts up to its 2 cm prediction distance, too loose for links 5 cm thick.
//!
//! Everything is sized for all pairs at construction: an update never allocates.

use rapier3d::prelude::*;

use super::build::TAG_LINK_BASE;

/// Gap past which a touching pair counts as apart, m.
pub const SEPARATION_M: f32 = 1e-3;

pub(super) struct SelfContacts {
    links: usize,
    /// Per pair `a * links + b` (`a < b`): touching after the last update.
    touching: Vec<bool>,
    /// The last update that found the pair in the narrow phase.
    seen: Vec<u64>,
    /// The touching pairs (capacity for all of them).
    now: Vec<usize>,
    updates: u64,
    onsets: u64,
}

impl SelfContacts {
    pub fn new(links: usize) -> Self {
        Self {
            links,
            touching: vec![false; links * links],
            seen: vec![0; links * links],
            now: Vec::with_capacity(links * links / 2),
            updates: 0,
            onsets: 0,
        }
    }

    /// Contact onsets since the start.
    pub fn onsets(&self) -> u64 {
        self.onsets
    }

    /// Pairs touching after the last update.
    pub fn pairs_now(&self) -> usize {
        self.now.len()
    }

    /// Reads the narrow phase after a rigid-body step; `colliders[k]` is link `k`'s.
    pub fn update(&mut self, world: &PhysicsWorld, colliders: &[ColliderHandle]) {
        self.updates += 1;
        let stamp = self.updates;
        for (k, &ch) in colliders.iter().enumerate() {
            for pair in world.narrow_phase.contact_pairs_with(ch) {
                let other = if pair.collider1 == ch {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(j) = world
                    .colliders
                    .get(other)
                    .and_then(|c| c.user_data.checked_sub(TAG_LINK_BASE))
                else {
                    continue;
                };
                let j = j as usize;
                // Each pair once, from its lower link; joined links never.
                if j < k + 2 {
                    continue;
                }
                let idx = k * self.links + j;
                self.seen[idx] = stamp;
                let dist = pair
                    .find_deepest_contact()
                    .map_or(f32::INFINITY, |(_, c)| c.dist);
                if !self.touching[idx] && dist <= 0.0 {
                    self.touching[idx] = true;
                    self.onsets += 1;
                    self.now.push(idx);
                } else if self.touching[idx] && dist > SEPARATION_M {
                    self.touching[idx] = false;
                }
            }
        }
        // Forget the pairs that came apart or left the narrow phase.
        let (touching, seen) = (&mut self.touching, &self.seen);
        self.now.retain(|&idx| {
            touching[idx] &= seen[idx] == stamp;
            touching[idx]
        });
    }
}
