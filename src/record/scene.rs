//! The 3-D channels, as Foxglove's well-known schemas: the world (`foxglove.SceneUpdate`,
//! frame `world`), the body drawn from its joint angles (`foxglove.SceneUpdate`, frame
//! `body`), and the frames (`foxglove.FrameTransforms`: `world → body`, and
//! `world → link_k` for every ground-truth link in simulation).

use foxglove::schemas::{
    Color, CubePrimitive, CylinderPrimitive, FrameTransform, FrameTransforms, Point3, Pose,
    Quaternion, SceneEntity, SceneUpdate, Timestamp, TriangleListPrimitive, Vector3,
};
use nalgebra::{Isometry3, UnitQuaternion};

use super::cycle::CycleRecord;
use super::kinematics::link_poses_in_body;
use crate::emu::LinkPose;
use crate::emu::world::WorldSpec;
use crate::gait::BodyLayout;
use crate::module::MODULE_DIAMETER_M;

pub const WORLD_FRAME: &str = "world";
pub const BODY_FRAME: &str = "body";

/// Frame of ground-truth link `k` (0: the head).
pub fn link_frame(k: usize) -> String {
    format!("link_{k}")
}

const GROUND: Color = rgba(0.55, 0.57, 0.55, 1.0);
const PEG: Color = rgba(0.60, 0.45, 0.30, 1.0);
const POLE: Color = rgba(0.45, 0.45, 0.60, 1.0);
const ROCK: Color = rgba(0.50, 0.48, 0.45, 1.0);
const WALL: Color = rgba(0.70, 0.70, 0.72, 1.0);
const HEAD: Color = rgba(0.85, 0.20, 0.15, 1.0);
const MODULE: Color = rgba(0.95, 0.60, 0.10, 1.0);

const fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

fn v3(x: f64, y: f64, z: f64) -> Option<Vector3> {
    Some(Vector3 { x, y, z })
}

fn quat(q: &UnitQuaternion<f64>) -> Quaternion {
    Quaternion {
        x: q.i,
        y: q.j,
        z: q.k,
        w: q.w,
    }
}

fn pose(p: &Isometry3<f64>) -> Option<Pose> {
    let t = p.translation.vector;
    Some(Pose {
        position: v3(t.x, t.y, t.z),
        orientation: Some(quat(&p.rotation)),
    })
}

fn at(x: f64, y: f64, z: f64) -> Option<Pose> {
    pose(&Isometry3::translation(x, y, z))
}

fn upright_cylinder(
    x: f64,
    y: f64,
    z0: f64,
    z1: f64,
    diameter: f64,
    color: Color,
) -> CylinderPrimitive {
    CylinderPrimitive {
        pose: at(x, y, 0.5 * (z0 + z1)),
        size: v3(diameter, diameter, z1 - z0),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(color),
    }
}

/// The world, drawn once (and re-sent to late live subscribers).
pub fn world_scene(world: &WorldSpec, timestamp: Timestamp) -> SceneUpdate {
    let mut e = SceneEntity {
        timestamp: Some(timestamp),
        frame_id: WORLD_FRAME.into(),
        id: "world".into(),
        ..Default::default()
    };
    if world.ground {
        // Ground top at z = 0, large enough to hold every obstacle and the start.
        let (lo, hi) = extent(world);
        let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
        let (sx, sy) = ((hi[0] - lo[0]).max(4.0), (hi[1] - lo[1]).max(4.0));
        e.cubes.push(CubePrimitive {
            pose: at(cx, cy, -0.005),
            size: v3(sx, sy, 0.01),
            color: Some(GROUND),
        });
    }
    for p in &world.pegs {
        e.cylinders.push(upright_cylinder(
            p.x_m,
            p.y_m,
            0.0,
            p.height_m,
            p.diameter_m,
            PEG,
        ));
    }
    for pole in &world.poles {
        for s in &pole.sections {
            e.cylinders.push(upright_cylinder(
                pole.x_m,
                pole.y_m,
                s.z0_m,
                s.z1_m,
                s.diameter_m,
                POLE,
            ));
        }
    }
    for r in &world.rocks {
        if let Some(t) = rock_triangles(&r.points_m) {
            e.triangles.push(TriangleListPrimitive {
                pose: at(r.center_m[0], r.center_m[1], r.center_m[2]),
                color: Some(ROCK),
                ..t
            });
        }
    }
    for w in &world.walls {
        let (dx, dy) = (w.to_m[0] - w.from_m[0], w.to_m[1] - w.from_m[1]);
        let yaw = UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), dy.atan2(dx));
        let centre = nalgebra::Translation3::new(
            0.5 * (w.from_m[0] + w.to_m[0]),
            0.5 * (w.from_m[1] + w.to_m[1]),
            0.5 * w.height_m,
        );
        e.cubes.push(CubePrimitive {
            pose: pose(&Isometry3::from_parts(centre, yaw)),
            size: v3(dx.hypot(dy), w.thickness_m, w.height_m),
            color: Some(WALL),
        });
    }
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![e],
    }
}

/// The ground-plane box (x, y) holding the obstacles and the start, with a 1 m margin.
fn extent(world: &WorldSpec) -> ([f64; 2], [f64; 2]) {
    let mut pts: Vec<[f64; 2]> = vec![[world.start.head_m[0], world.start.head_m[1]]];
    pts.extend(world.pegs.iter().map(|p| [p.x_m, p.y_m]));
    pts.extend(world.poles.iter().map(|p| [p.x_m, p.y_m]));
    pts.extend(world.rocks.iter().map(|r| [r.center_m[0], r.center_m[1]]));
    pts.extend(world.walls.iter().flat_map(|w| [w.from_m, w.to_m]));
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in pts.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - 1.0);
            hi[k] = hi[k].max(p[k] + 1.0);
        }
    }
    if lo[0] > hi[0] {
        return ([-2.0; 2], [2.0; 2]);
    }
    (lo, hi)
}

/// A rock's convex hull as an indexed triangle list (None when the points are
/// degenerate, e.g. fewer than four or all in a plane).
fn rock_triangles(points: &[[f64; 3]]) -> Option<TriangleListPrimitive> {
    use rapier3d::math::Vector;
    let pts: Vec<Vector> = points
        .iter()
        .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let (vertices, faces) = rapier3d::parry::transformation::try_convex_hull(&pts).ok()?;
    if faces.is_empty() {
        return None;
    }
    Some(TriangleListPrimitive {
        points: vertices
            .iter()
            .map(|v| Point3 {
                x: f64::from(v.x),
                y: f64::from(v.y),
                z: f64::from(v.z),
            })
            .collect(),
        indices: faces.iter().flatten().copied().collect(),
        ..Default::default()
    })
}

/// Draws the body and its frames from cycle records; keeps its buffers between calls.
pub struct BodyDrawer {
    layout: BodyLayout,
    poses: Vec<Isometry3<f64>>,
    link_frames: Vec<String>,
}

impl BodyDrawer {
    pub fn new(layout: BodyLayout) -> Self {
        let links = layout.len() + 1;
        Self {
            layout,
            poses: Vec::with_capacity(links),
            link_frames: (0..links.max(1)).map(link_frame).collect(),
        }
    }

    /// The body in the `body` frame: a cylinder per link (the head red), shaped by the
    /// measured joint angles.
    pub fn body_scene(&mut self, rec: &CycleRecord, timestamp: Timestamp) -> SceneUpdate {
        let angles = rec.joints().iter().map(|j| f64::from(j.position_rad));
        link_poses_in_body(&self.layout, angles, &mut self.poses);
        // Cylinders stand along z: turn each onto its link's x axis.
        let along_x = UnitQuaternion::from_axis_angle(
            &nalgebra::Vector3::y_axis(),
            std::f64::consts::FRAC_PI_2,
        );
        let (l, d) = (self.layout.module_length_m, MODULE_DIAMETER_M);
        let cylinders = self
            .poses
            .iter()
            .enumerate()
            .map(|(k, p)| CylinderPrimitive {
                pose: pose(&Isometry3::from_parts(p.translation, p.rotation * along_x)),
                size: v3(d, d, l),
                bottom_scale: 1.0,
                top_scale: 1.0,
                color: Some(if k == 0 { HEAD } else { MODULE }),
            })
            .collect();
        SceneUpdate {
            deletions: Vec::new(),
            entities: vec![SceneEntity {
                timestamp: Some(timestamp),
                frame_id: BODY_FRAME.into(),
                id: "body".into(),
                frame_locked: true,
                cylinders,
                ..Default::default()
            }],
        }
    }

    /// `world → body` (the head link's ground-truth pose, identity without ground
    /// truth) and `world → link_k` for every ground-truth link.
    pub fn transforms(&mut self, rec: &CycleRecord, timestamp: Timestamp) -> FrameTransforms {
        let links = rec.link_poses();
        while self.link_frames.len() < links.len() {
            let k = self.link_frames.len();
            self.link_frames.push(link_frame(k));
        }
        let identity = LinkPose {
            position_m: [0.0; 3],
            quat_wxyz: [1.0, 0.0, 0.0, 0.0],
        };
        let head = links.first().copied().unwrap_or(identity);
        let mut transforms = Vec::with_capacity(links.len() + 1);
        transforms.push(transform(BODY_FRAME, &head, timestamp));
        for (k, p) in links.iter().enumerate() {
            transforms.push(transform(&self.link_frames[k], p, timestamp));
        }
        FrameTransforms { transforms }
    }
}

fn transform(child: &str, p: &LinkPose, timestamp: Timestamp) -> FrameTransform {
    let [w, x, y, z] = p.quat_wxyz;
    FrameTransform {
        timestamp: Some(timestamp),
        parent_frame_id: WORLD_FRAME.into(),
        child_frame_id: child.into(),
        translation: v3(p.position_m[0], p.position_m[1], p.position_m[2]),
        rotation: Some(Quaternion { x, y, z, w }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::world::{Peg, Pole, PoleSection, Rock, Wall};
    use crate::gait::Plane;

    #[test]
    fn the_world_has_a_primitive_per_obstacle() {
        let world = WorldSpec {
            pegs: vec![Peg {
                x_m: 1.0,
                y_m: 0.5,
                diameter_m: 0.1,
                height_m: 0.3,
            }],
            poles: vec![Pole {
                x_m: -1.0,
                y_m: 0.0,
                sections: vec![
                    PoleSection {
                        z0_m: 0.0,
                        z1_m: 0.5,
                        diameter_m: 0.2,
                    },
                    PoleSection {
                        z0_m: 0.5,
                        z1_m: 1.0,
                        diameter_m: 0.1,
                    },
                ],
                mu: 0.5,
            }],
            rocks: vec![Rock {
                center_m: [0.0, 2.0, 0.0],
                points_m: vec![
                    [0.0, 0.0, 0.0],
                    [0.2, 0.0, 0.0],
                    [0.0, 0.2, 0.0],
                    [0.0, 0.0, 0.2],
                ],
            }],
            walls: vec![Wall {
                from_m: [0.0, -1.0],
                to_m: [2.0, -1.0],
                height_m: 0.2,
                thickness_m: 0.05,
            }],
            ..WorldSpec::default()
        };
        let s = world_scene(&world, Timestamp::new(1, 0));
        let e = &s.entities[0];
        assert_eq!(e.frame_id, WORLD_FRAME);
        assert_eq!(e.cubes.len(), 2, "ground + wall");
        assert_eq!(e.cylinders.len(), 3, "peg + two pole sections");
        assert_eq!(e.triangles.len(), 1);
        assert_eq!(e.triangles[0].indices.len(), 12, "a tetrahedron");
        let peg = e.cylinders[0]
            .pose
            .and_then(|p| p.position)
            .expect("peg pose");
        assert!((peg.z - 0.15).abs() < 1e-12, "a peg stands on the ground");
        let wall = e.cubes[1].size.expect("wall size");
        assert!((wall.x - 2.0).abs() < 1e-12);
    }

    #[test]
    fn the_body_has_a_cylinder_per_link_and_frames_follow_ground_truth() {
        let layout = BodyLayout::alternating(3, Plane::Lateral, 0.1);
        let mut d = BodyDrawer::new(layout);
        let mut rec = CycleRecord::EMPTY;
        rec.modules = 3;
        let s = d.body_scene(&rec, Timestamp::new(0, 0));
        assert_eq!(s.entities[0].cylinders.len(), 4);
        assert_eq!(s.entities[0].frame_id, BODY_FRAME);
        let tf = d.transforms(&rec, Timestamp::new(0, 0));
        assert_eq!(
            tf.transforms.len(),
            1,
            "world → body only, without ground truth"
        );
        rec.links = 4;
        rec.link_poses[0].position_m = [1.0, 2.0, 0.03];
        let tf = d.transforms(&rec, Timestamp::new(0, 0));
        assert_eq!(tf.transforms.len(), 5);
        assert_eq!(tf.transforms[0].child_frame_id, BODY_FRAME);
        assert_eq!(tf.transforms[1].child_frame_id, "link_0");
        assert_eq!(tf.transforms[4].child_frame_id, "link_3");
        let t = tf.transforms[0].translation.expect("translation");
        assert_eq!((t.x, t.y), (1.0, 2.0));
    }
}
