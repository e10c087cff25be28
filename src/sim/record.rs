//! Read-only views of a [`HandSim`] for episode recordings: the collision geometry of the
//! hand and of the object, the world poses of the hand's colliders, and a frame recorder
//! that samples them (with the object pose and the sensors) every few physics steps.
//!
//! This file is a child module of `sim::world` (declared there with `#[path]`), so it
//! reads the simulator's private state without widening the visibility of any field.
//! Nothing here changes the physics: recording an episode gives the same trajectory as not
//! recording it.
//!
//! Poses are `[x, y, z, qx, qy, qz, qw]` (metres, unit quaternion), world frame (z up,
//! table top at z = 0), rounded to 10 µm and 1e-5 to keep recordings small.
//!
//! ```no_run
//! use grasp::robot::{Robot, Side};
//! use grasp::sim::{HandSim, ObjectSpec, SimConfig};
//!
//! let robot = Robot::builtin(Side::Left);
//! let mut sim = HandSim::new(&robot, ObjectSpec::default_box(), SimConfig::default())?;
//! sim.start_recording(4);
//! for _ in 0..40 {
//!     sim.step_physics();
//! }
//! let frames = sim.take_recording();
//! assert_eq!(frames.len(), 10);
//! assert_eq!(frames[0].hand.len(), sim.hand_geometry().len());
//! # Ok::<(), grasp::sim::SimError>(())
//! ```

use super::HandSim;
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::Pose;
use serde::{Deserialize, Serialize};

/// The shape of one collider in its own frame (metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ShapeGeometry {
    /// A box centred on the origin.
    Box {
        /// Half extents along x, y, z.
        half: [f32; 3],
    },
    /// A ball centred on the origin.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// A capsule: the points within `radius` of the segment `a`-`b`.
    Capsule {
        /// First end of the axis.
        a: [f32; 3],
        /// Second end of the axis.
        b: [f32; 3],
        /// Radius.
        radius: f32,
    },
    /// A cylinder along the y axis, centred on the origin.
    Cylinder {
        /// Half of its length along y.
        half_height: f32,
        /// Radius.
        radius: f32,
    },
    /// A triangle mesh (convex pieces, triangle meshes).
    Mesh {
        /// Vertex positions.
        vertices: Vec<[f32; 3]>,
        /// Triangles as vertex indices, counter-clockwise seen from outside.
        triangles: Vec<[u32; 3]>,
    },
}

/// A shape placed in a parent frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlacedShape {
    /// Pose of the shape's frame in the parent frame, `[x, y, z, qx, qy, qz, qw]`.
    pub pose: [f32; 7],
    /// The shape.
    pub shape: ShapeGeometry,
}

/// One sampled instant of an episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimFrame {
    /// Physics steps since the last reset.
    pub physics_step: u64,
    /// Simulated seconds since the last reset.
    pub t: f64,
    /// World pose of each hand collider, in the order of [`HandSim::hand_geometry`].
    pub hand: Vec<[f32; 7]>,
    /// World pose of the object's body frame (centre of its bounding box).
    pub object: [f32; 7],
    /// Binary fingertip contacts (FF, MF, RF, LF, TH).
    pub tactile: [u8; 5],
    /// Torque levels 0..=5 of the 20 actuators.
    pub torque_level: [u8; 20],
    /// Normal force (N) between the object and each distal phalanx (FF, MF, RF, LF, TH),
    /// as [`HandSim::tip_forces`] measures it (rounded to 1 mN).
    #[serde(default)]
    pub tip_force: [f32; 5],
    /// Normal force (N) between the object and the whole hand (rounded to 1 mN).
    #[serde(default)]
    pub hand_force: f32,
    /// Normal force (N) between the object and the table (rounded to 1 mN).
    #[serde(default)]
    pub table_force: f32,
    /// Height of the lift above its start (m).
    pub lift: f32,
    /// Whether the arm is lifting (the lift target is above its start).
    pub lifting: bool,
}

/// Collects a [`SimFrame`] every `every` physics steps.
#[derive(Debug, Clone)]
pub(super) struct FrameRecorder {
    every: u64,
    frames: Vec<SimFrame>,
}

fn round(x: f32, scale: f32) -> f32 {
    (x * scale).round() / scale
}

/// `pose` as `[x, y, z, qx, qy, qz, qw]`, rounded (10 µm, 1e-5).
pub fn pose_array(pose: &Pose) -> [f32; 7] {
    let (t, q) = (pose.translation, pose.rotation);
    [
        round(t.x, 1e5),
        round(t.y, 1e5),
        round(t.z, 1e5),
        round(q.x, 1e5),
        round(q.y, 1e5),
        round(q.z, 1e5),
        round(q.w, 1e5),
    ]
}

/// Appends the pieces of `shape` placed at `pose` to `out`: compounds are flattened, and
/// a shape kind without a drawing of its own (cone, heightfield, ...) is drawn as its
/// bounding box.
pub fn shape_geometry(shape: &dyn Shape, pose: Pose, out: &mut Vec<PlacedShape>) {
    let v = |p: rapier3d::prelude::Vector| [p.x, p.y, p.z];
    let geometry = match shape.as_typed_shape() {
        TypedShape::Cuboid(c) => ShapeGeometry::Box {
            half: v(c.half_extents),
        },
        TypedShape::Ball(b) => ShapeGeometry::Sphere { radius: b.radius },
        TypedShape::Capsule(c) => ShapeGeometry::Capsule {
            a: v(c.segment.a),
            b: v(c.segment.b),
            radius: c.radius,
        },
        TypedShape::Cylinder(c) => ShapeGeometry::Cylinder {
            half_height: c.half_height,
            radius: c.radius,
        },
        TypedShape::ConvexPolyhedron(p) => {
            let (vertices, triangles) = p.to_trimesh();
            ShapeGeometry::Mesh {
                vertices: vertices.into_iter().map(v).collect(),
                triangles,
            }
        }
        TypedShape::TriMesh(m) => ShapeGeometry::Mesh {
            vertices: m.vertices().iter().copied().map(v).collect(),
            triangles: m.indices().to_vec(),
        },
        TypedShape::Compound(c) => {
            for (p, s) in c.shapes() {
                shape_geometry(s.as_ref(), pose * *p, out);
            }
            return;
        }
        _ => {
            let aabb = shape.compute_local_aabb();
            let centre = aabb.center();
            out.push(PlacedShape {
                pose: pose_array(&(pose * Pose::from_translation(centre))),
                shape: ShapeGeometry::Box {
                    half: v(aabb.half_extents()),
                },
            });
            return;
        }
    };
    out.push(PlacedShape {
        pose: pose_array(&pose),
        shape: geometry,
    });
}

impl HandSim {
    /// The collision shape of every hand collider in its own frame, in a fixed order (the
    /// order of [`HandSim::link_poses`] and [`SimFrame::hand`]). Compound hand colliders
    /// (none today) would show their first piece only.
    pub fn hand_geometry(&self) -> Vec<ShapeGeometry> {
        self.hand_colliders
            .iter()
            .map(|h| {
                let mut parts = Vec::new();
                if let Some(c) = self.sets.colliders.get(*h) {
                    shape_geometry(c.shape(), Pose::IDENTITY, &mut parts);
                }
                parts
                    .into_iter()
                    .next()
                    .map_or(ShapeGeometry::Sphere { radius: 0.0 }, |p| p.shape)
            })
            .collect()
    }

    /// For every hand collider (order of [`HandSim::hand_geometry`]), the finger whose
    /// tactile sensor it belongs to (0..5 = FF, MF, RF, LF, TH: the distal phalanx with its
    /// tip), or `None`.
    pub fn hand_tactile_fingers(&self) -> Vec<Option<u8>> {
        self.hand_colliders
            .iter()
            .map(|h| (0u8..5).find(|f| self.distal_colliders[usize::from(*f)].contains(h)))
            .collect()
    }

    /// The world pose of every hand collider now, in the order of
    /// [`HandSim::hand_geometry`]; valid right after a reset too.
    pub fn link_poses(&self) -> Vec<[f32; 7]> {
        self.hand_colliders
            .iter()
            .map(|h| {
                self.collider_world_pose(*h)
                    .map_or([f32::NAN; 7], |p| pose_array(&p))
            })
            .collect()
    }

    /// The object's collision geometry (convex pieces, support feet included) in its body
    /// frame, the frame whose world pose [`HandSim::object_pose_raw`] gives.
    pub fn object_geometry(&self) -> Vec<PlacedShape> {
        let mut out = Vec::new();
        if let Some(c) = self.sets.colliders.get(self.object_collider) {
            let local = c.position_wrt_parent().copied().unwrap_or(Pose::IDENTITY);
            shape_geometry(c.shape(), local, &mut out);
        }
        out
    }

    /// The state now as a [`SimFrame`].
    pub fn frame(&self) -> SimFrame {
        let s = self.sensors();
        let o = self.object_pose_raw();
        let lift = self.lift_position();
        SimFrame {
            physics_step: self.physics_steps,
            t: self.time(),
            hand: self.link_poses(),
            object: [0, 1, 2, 3, 4, 5, 6].map(|k| round(o[k], 1e5)),
            tactile: s.tactile,
            torque_level: s.torque_level,
            tip_force: s.tip_force.map(|f| round(f as f32, 1e3)),
            hand_force: round(self.hand_object_force() as f32, 1e3),
            table_force: round(self.table_object_force() as f32, 1e3),
            lift: if lift.is_finite() {
                round(lift as f32, 1e5)
            } else {
                0.0
            },
            lifting: self.lift_target > 0.0,
        }
    }

    /// Starts (or restarts) recording: from now on the first physics step after a reset
    /// and every `every`-th one after it (physics step 1, 1 + every, ...) append a
    /// [`SimFrame`]. `every = 0` is taken as 1. Recording survives resets.
    pub fn start_recording(&mut self, every: u64) {
        self.recorder = Some(FrameRecorder {
            every: every.max(1),
            frames: Vec::new(),
        });
    }

    /// Whether a recording is running.
    pub fn is_recording(&self) -> bool {
        self.recorder.is_some()
    }

    /// Stops recording and returns the frames (empty when none was running).
    pub fn take_recording(&mut self) -> Vec<SimFrame> {
        self.recorder.take().map_or_else(Vec::new, |r| r.frames)
    }

    /// Called by `step_physics` after each step: samples a frame when one is due.
    pub(super) fn record_step(&mut self) {
        let due = self
            .recorder
            .as_ref()
            .is_some_and(|r| (self.physics_steps + r.every - 1).is_multiple_of(r.every));
        if due {
            let f = self.frame();
            if let Some(r) = self.recorder.as_mut() {
                r.frames.push(f);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Robot, Side};
    use crate::sim::{ObjectSpec, SimConfig};

    fn sim() -> HandSim {
        HandSim::new(
            &Robot::builtin(Side::Left),
            ObjectSpec::default_box(),
            SimConfig::default(),
        )
        .unwrap()
    }

    #[test]
    fn frames_every_n_steps_from_the_first_step() {
        let mut s = sim();
        assert!(!s.is_recording());
        s.start_recording(4);
        for _ in 0..9 {
            s.step_physics();
        }
        let f = s.take_recording();
        // Steps 1, 5, 9.
        assert_eq!(
            f.iter().map(|f| f.physics_step).collect::<Vec<_>>(),
            [1, 5, 9]
        );
        assert!(!s.is_recording());
        assert_eq!(f[0].hand.len(), s.hand_geometry().len());
        assert!(f[0].hand.iter().flatten().all(|x| x.is_finite()));
        // The box rests on the table: its centre is at its half height, upright.
        let half = s.object().shape.half_extents();
        assert!(
            (f[2].object[2] as f64 - half[2]).abs() < 2e-3,
            "{:?}",
            f[2].object
        );
        assert!((f[2].object[6] - 1.0).abs() < 1e-3);
        assert!(!f[0].lifting);
    }

    #[test]
    fn recording_does_not_change_the_physics() {
        let (mut a, mut b) = (sim(), sim());
        b.start_recording(1);
        for _ in 0..30 {
            a.step_physics();
            b.step_physics();
        }
        assert_eq!(a.object_pose_raw(), b.object_pose_raw());
        assert_eq!(a.link_poses(), b.link_poses());
        assert_eq!(b.take_recording().len(), 30);
    }

    #[test]
    fn geometry_matches_the_model() {
        let s = sim();
        let g = s.hand_geometry();
        assert!(g.len() > 20, "{}", g.len());
        let fingers = s.hand_tactile_fingers();
        assert_eq!(fingers.len(), g.len());
        for f in 0..5u8 {
            assert!(fingers.contains(&Some(f)), "finger {f}");
        }
        // The built-in hand: cylinder phalanges, box palm, and sphere tips simulated as
        // 0.2 mm capsules (see `HandSim::new`).
        for kind in ["cylinder", "capsule", "box"] {
            assert!(
                g.iter()
                    .any(|x| serde_json::to_value(x).unwrap()["kind"] == kind),
                "{kind}"
            );
        }
        // The default box: one box piece with the spec's half extents.
        let o = s.object_geometry();
        let half = s.object().shape.half_extents();
        match &o[..] {
            [PlacedShape {
                shape: ShapeGeometry::Box { half: h },
                ..
            }] => {
                for k in 0..3 {
                    assert!((h[k] as f64 - half[k]).abs() < 1e-6);
                }
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn shapes_flatten_and_fall_back_to_boxes() {
        use rapier3d::prelude::{SharedShape, Vector};
        let compound = SharedShape::compound(vec![
            (
                Pose::from_translation(Vector::new(0.1, 0.0, 0.0)),
                SharedShape::ball(0.02),
            ),
            (Pose::IDENTITY, SharedShape::cuboid(0.01, 0.02, 0.03)),
        ]);
        let mut out = Vec::new();
        shape_geometry(
            compound.as_ref(),
            Pose::from_translation(Vector::new(0.0, 0.0, 1.0)),
            &mut out,
        );
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].shape, ShapeGeometry::Sphere { radius: 0.02 });
        assert_eq!(out[0].pose, [0.1, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        // A cone (no drawing of its own) becomes its bounding box.
        let mut out = Vec::new();
        shape_geometry(
            SharedShape::cone(0.05, 0.02).as_ref(),
            Pose::IDENTITY,
            &mut out,
        );
        assert_eq!(
            out[0].shape,
            ShapeGeometry::Box {
                half: [0.02, 0.05, 0.02]
            }
        );
        // A convex hull becomes a closed mesh.
        let pts = [
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.0, 1.0, 0.0),
            Vector::new(0.0, 0.0, 1.0),
        ];
        let hull = SharedShape::convex_hull(&pts).unwrap();
        let mut out = Vec::new();
        shape_geometry(hull.as_ref(), Pose::IDENTITY, &mut out);
        match &out[0].shape {
            ShapeGeometry::Mesh {
                vertices,
                triangles,
            } => {
                assert_eq!(vertices.len(), 4);
                assert_eq!(triangles.len(), 4);
            }
            other => panic!("{other:?}"),
        }
    }
}
