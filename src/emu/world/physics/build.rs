//! Turning a [`WorldSpec`] and a [`PhysicsConfig`] into rapier bodies, colliders and
//! joints.

use nalgebra::Isometry3;
use rapier3d::prelude::*;

use super::kinematics::{axis_of, chain_poses, head_pose, to_rapier};
use super::{PhysicsConfig, PhysicsError};
use crate::emu::plant::plane_of;
use crate::emu::world::WorldSpec;
use crate::module::{MODULE_DIAMETER_M, MODULE_LENGTH_M, MODULE_MASS_KG};

/// Joint limit, rad.
pub const JOINT_LIMIT_RAD: f64 = std::f64::consts::FRAC_PI_2;

/// Collision group of the world's (fixed) colliders.
const WORLD_GROUP: Group = Group::GROUP_32;
/// The links' groups: link `k` is in bit `k % 31`, so its filter can leave out its
/// neighbours (see [`link_groups`]).
const SNAKE_GROUPS: Group = Group::ALL.difference(WORLD_GROUP);
const SNAKE_BITS: usize = 31;

/// `user_data` of fixed world colliders whose friction the anisotropy applies to.
pub const TAG_SKIN_SURFACE: u128 = 1;
/// `user_data` of pole colliders (fixed; their own isotropic `mu`).
pub const TAG_POLE: u128 = 2;
/// `user_data` of a snake link collider: `TAG_LINK_BASE + link index`.
pub const TAG_LINK_BASE: u128 = 1000;

/// The chain as built: one body per link, one joint per module.
pub struct Chain {
    pub links: Vec<RigidBodyHandle>,
    /// The links' colliders.
    pub colliders: Vec<ColliderHandle>,
    pub joints: Vec<ImpulseJointHandle>,
    /// Joint axis of each joint, in both links' frames.
    pub axes: Vec<Vector>,
}

fn v(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as f32, y as f32, z as f32)
}

/// Static geometry from `spec` (ground, pegs, poles, rocks, walls).
pub fn build_world(world: &mut PhysicsWorld, spec: &WorldSpec) -> Result<(), PhysicsError> {
    let groups = InteractionGroups::new(WORLD_GROUP, SNAKE_GROUPS, InteractionTestMode::And);
    let mu = spec.friction.mu as f32;
    let fixed = world.bodies.insert(RigidBodyBuilder::fixed());
    let skin = |b: ColliderBuilder| {
        b.friction(mu)
            .friction_combine_rule(own_coefficient_against_skin(mu, mu))
            .collision_groups(groups)
            .user_data(TAG_SKIN_SURFACE)
    };
    let add = |w: &mut PhysicsWorld, c: ColliderBuilder| {
        w.colliders.insert_with_parent(c, fixed, &mut w.bodies);
    };
    if spec.ground {
        add(
            world,
            skin(ColliderBuilder::cuboid(500.0, 500.0, 0.5)).translation(v(0.0, 0.0, -0.5)),
        );
    }
    // Parry's cylinders stand along y: turn them to z.
    let upright = Vector::X * std::f32::consts::FRAC_PI_2;
    for p in &spec.pegs {
        let cylinder =
            ColliderBuilder::cylinder((0.5 * p.height_m) as f32, (0.5 * p.diameter_m) as f32)
                .translation(v(p.x_m, p.y_m, 0.5 * p.height_m))
                .rotation(upright);
        // Pegs of their own friction touch like poles: isotropic, their own coefficient.
        let peg = match spec.friction.peg_mu {
            None => skin(cylinder),
            Some(peg_mu) => cylinder
                .friction(peg_mu as f32)
                .friction_combine_rule(own_coefficient_against_skin(peg_mu as f32, mu))
                .collision_groups(groups)
                .user_data(TAG_POLE),
        };
        add(world, peg);
    }
    for pole in &spec.poles {
        for s in &pole.sections {
            let c = ColliderBuilder::cylinder(
                (0.5 * (s.z1_m - s.z0_m)) as f32,
                (0.5 * s.diameter_m) as f32,
            )
            .translation(v(pole.x_m, pole.y_m, 0.5 * (s.z0_m + s.z1_m)))
            .rotation(upright)
            .friction(pole.mu as f32)
            .friction_combine_rule(own_coefficient_against_skin(pole.mu as f32, mu))
            .collision_groups(groups)
            .user_data(TAG_POLE);
            add(world, c);
        }
    }
    for r in &spec.rocks {
        let pts: Vec<Vector> = r.points_m.iter().map(|p| v(p[0], p[1], p[2])).collect();
        let c = ColliderBuilder::convex_hull(&pts).ok_or(PhysicsError::BadRock)?;
        add(
            world,
            skin(c).translation(v(r.center_m[0], r.center_m[1], r.center_m[2])),
        );
    }
    for w in &spec.walls {
        let (dx, dy) = (w.to_m[0] - w.from_m[0], w.to_m[1] - w.from_m[1]);
        let len = dx.hypot(dy);
        let c = ColliderBuilder::cuboid(
            (0.5 * len) as f32,
            (0.5 * w.thickness_m) as f32,
            (0.5 * w.height_m) as f32,
        )
        .translation(v(
            0.5 * (w.from_m[0] + w.to_m[0]),
            0.5 * (w.from_m[1] + w.to_m[1]),
            0.5 * w.height_m,
        ))
        .rotation(Vector::Z * dy.atan2(dx) as f32);
        add(world, skin(c));
    }
    Ok(())
}

/// The combine rule that makes a world collider of friction `own` keep its own
/// coefficient against the skin's `skin_mu`: the links use rule `Average` (the lowest),
/// so this one decides, and `Max`/`Min` of the pair is `own` exactly. Skin on skin
/// (both `Average` of `skin_mu`) is `skin_mu`: a self-contact is never frictionless.
pub fn own_coefficient_against_skin(own: f32, skin_mu: f32) -> CoefficientCombineRule {
    if own >= skin_mu {
        CoefficientCombineRule::Max
    } else {
        CoefficientCombineRule::Min
    }
}

/// Collision groups of link `k` of `links`. With self-collision, a link meets the
/// world and every link at least 3 away: its filter leaves out itself and the links 1
/// and 2 away, so the broad phase never makes those pairs (adjacent links overlap at
/// the joint, links 2 apart cannot touch within the ±π/2 limits). Past 31 links the
/// bits repeat, so the filter takes every link and the joints (`contacts_enabled
/// (false)`) alone keep adjacent links apart.
fn link_groups(k: usize, links: usize, self_collision: bool) -> InteractionGroups {
    let bit = |j: usize| Group::from_bits_truncate(1 << (j % SNAKE_BITS));
    let filter = if !self_collision {
        WORLD_GROUP
    } else if links <= SNAKE_BITS {
        let near = (k.saturating_sub(2)..=(k + 2).min(links - 1))
            .fold(Group::NONE, |g, j| g.union(bit(j)));
        WORLD_GROUP.union(SNAKE_GROUPS.difference(near))
    } else {
        WORLD_GROUP.union(SNAKE_GROUPS)
    };
    InteractionGroups::new(bit(k), filter, InteractionTestMode::And)
}

/// The start pose's link poses: from the spec's head pose and joint angles, or from
/// `override_head` when given (e.g. a body already coiled around a pole).
pub fn start_poses(
    spec: &WorldSpec,
    config: &PhysicsConfig,
    override_head: Option<Isometry3<f64>>,
) -> Vec<Isometry3<f64>> {
    let n = config.modules;
    let angles: Vec<f64> = (0..n)
        .map(|i| {
            spec.start
                .joint_angles_rad
                .get(i)
                .copied()
                .unwrap_or(0.0)
                .clamp(-JOINT_LIMIT_RAD, JOINT_LIMIT_RAD)
        })
        .collect();
    if let Some(head) = override_head {
        return chain_poses(head, config.first_plane, &angles, MODULE_LENGTH_M);
    }
    let mut h = spec.start.head_m;
    h[2] += 0.5 * MODULE_DIAMETER_M;
    // Rolled about the head link's own x axis (along the body).
    let head = head_pose(h, spec.start.yaw_rad, MODULE_LENGTH_M)
        * nalgebra::UnitQuaternion::from_axis_angle(
            &nalgebra::Vector3::x_axis(),
            spec.start.roll_rad,
        );
    let mut poses = chain_poses(head, config.first_plane, &angles, MODULE_LENGTH_M);
    // A shaped body (an arc curling down, say) would start inside the ground: lift it
    // so its lowest point is `head_m.z` above z = 0, as a straight body's is.
    let lift = spec.start.head_m[2] - lowest_point_m(&poses);
    if lift > 0.0 {
        for p in &mut poses {
            p.translation.vector.z += lift;
        }
    }
    poses
}

/// Lowest z of the links' capsules at `poses`.
fn lowest_point_m(poses: &[Isometry3<f64>]) -> f64 {
    let (half_len, radius) = (
        0.5 * MODULE_LENGTH_M - 0.5 * MODULE_DIAMETER_M,
        0.5 * MODULE_DIAMETER_M,
    );
    poses
        .iter()
        .map(|p| {
            let axis = p.rotation * nalgebra::Vector3::x();
            p.translation.vector.z - half_len * axis.z.abs() - radius
        })
        .fold(f64::INFINITY, f64::min)
}

/// Links (capsules of the module's length and diameter and mass, skin friction
/// `skin_mu`) and revolute impulse joints between them, with contacts between the two
/// links of a joint disabled; `skin_hooks`: the links' contacts go through the
/// skin-friction hook.
pub fn build_chain(
    world: &mut PhysicsWorld,
    config: &PhysicsConfig,
    poses: &[Isometry3<f64>],
    skin_mu: f32,
    skin_hooks: bool,
) -> Chain {
    let radius = 0.5 * MODULE_DIAMETER_M;
    let half_len = 0.5 * MODULE_LENGTH_M;
    let hooks = if skin_hooks {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    let mut links = Vec::with_capacity(poses.len());
    let mut colliders = Vec::with_capacity(poses.len());
    for (k, pose) in poses.iter().enumerate() {
        let body = RigidBodyBuilder::dynamic()
            .pose(to_rapier(pose))
            .can_sleep(false)
            .angular_damping(config.link_angular_damping as f32);
        let h = world.bodies.insert(body);
        // Rule Average (the lowest): against the world the surface's rule decides
        // (`own_coefficient_against_skin`), against another link it is `skin_mu`.
        let c = ColliderBuilder::capsule_x((half_len - radius) as f32, radius as f32)
            .mass(MODULE_MASS_KG as f32)
            .friction(skin_mu)
            .friction_combine_rule(CoefficientCombineRule::Average)
            .restitution(0.0)
            .collision_groups(link_groups(k, poses.len(), config.self_collision))
            .active_hooks(hooks)
            .user_data(TAG_LINK_BASE + k as u128);
        colliders.push(world.colliders.insert_with_parent(c, h, &mut world.bodies));
        links.push(h);
    }
    let lim = JOINT_LIMIT_RAD as f32;
    let mut joints = Vec::with_capacity(config.modules);
    let mut axes = Vec::with_capacity(config.modules);
    for i in 0..config.modules {
        let a = axis_of(plane_of(config.first_plane, i));
        let axis = v(a.x, a.y, a.z);
        let joint = RevoluteJointBuilder::new(axis)
            .local_anchor1(v(-half_len, 0.0, 0.0))
            .local_anchor2(v(half_len, 0.0, 0.0))
            .limits([-lim, lim])
            .contacts_enabled(false);
        joints.push(
            world
                .impulse_joints
                .insert(links[i], links[i + 1], joint, true),
        );
        axes.push(axis);
    }
    Chain {
        links,
        colliders,
        joints,
        axes,
    }
}
