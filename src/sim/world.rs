//! [`HandSim`]: the Shadow hand on a Cartesian lift, a table and one object in Rapier.
//!
//! # Model
//! - World: z up, gravity `(0, 0, cfg.gravity)`; the table is a fixed cuboid whose top is
//!   the plane z = 0.
//! - The hand is ONE multibody. Its root is a fixed anchor body at the world origin; a
//!   motorised prismatic joint along world z (the "lift") carries the forearm. The lift
//!   joint's frames hold the flange pose, so placing the hand changes two joint frames, not
//!   the root. This stands in for the UR10e: a stiff position-controlled Cartesian lift
//!   (the arm's 6 joints are not simulated; `robot::ur10e` gives their IK).
//! - Every hand link joined by a movable URDF joint is a multibody link with a revolute
//!   joint (frames from the URDF `origin`, axis from `axis`, limits from lower/upper).
//!   Links joined by fixed joints (the fingertip frames) are merged into their parent body.
//!   Masses and inertias come from the URDF `inertial`; colliders carry zero mass
//!   (explicit zero mass properties).
//! - Motors: `MotorModel::ForceBased` position motors on every hand joint, gains per group
//!   from [`SimConfig`], max force = the URDF effort limit. Target angles are clamped to the
//!   joint limits.
//! - Coupling: for FF, MF, RF, LF the pair J1/J2 is tied RIGIDLY by
//!   `Multibody::add_dof_coupling` (J1 = J2), and both motors target J0/2, where
//!   J0 = target(J1) + target(J2). The coupled actuator's reported effort is the sum of
//!   the J1 and J2 efforts.
//! - Self-collisions between hand links are disabled by collision groups: hand colliders
//!   collide with the table and the object only; the object collides with everything.
//! - Friction: hand 1.0, table 0.8, object from its spec; combine rule MIN everywhere.
//! - The object: one dynamic body whose origin is the centre of the object's bounding box
//!   (see [`super::object`]), with the mass properties of its [`ObjectSpec`] set on the
//!   body and one collider of density 0 (a compound of convex parts for library objects).
//!
//! # Reset
//! The world is built once as a template (bodies, colliders, joints are `Clone`); a reset
//! clones it, gives it a fresh pipeline, broad phase, narrow phase and island manager,
//! writes the start posture into the joint coordinates and places hand and object.

use super::config::{DriveModel, LimitRows, SimConfig};
use super::contact::HullContactDispatcher;
use super::object::{ObjectError, ObjectSpec};
use super::placement::{hand_root_pose, PlacementError};
use super::sensors::{near_limit, pd_effort, spring_rest, Sensors};
use crate::robot::joints::HAND_JOINTS;
use crate::robot::Robot;
use crate::util::levels::torque_level;
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

mod health;
mod scene;
mod state;

pub use scene::Scene;

#[path = "build.rs"]
mod build;
#[path = "record.rs"]
pub mod record;

/// Error of the simulator's inputs (never of the physics: see [`PhysicsFailure`]).
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The config is out of range.
    #[error(transparent)]
    Config(#[from] super::config::SimConfigError),
    /// The object description is invalid.
    #[error(transparent)]
    Object(#[from] ObjectError),
    /// The hand cannot be placed.
    #[error(transparent)]
    Placement(#[from] PlacementError),
    /// The robot model has something the simulator cannot build.
    #[error("robot {robot}: {message}")]
    Robot {
        /// The robot's source file.
        robot: String,
        /// What is unsupported.
        message: String,
    },
    /// A joint target is NaN or infinite.
    #[error("joint target {joint} (index {index}) is not finite: {value}")]
    NonFiniteTarget {
        /// Joint name (paper order).
        joint: &'static str,
        /// Index in the 24-vector.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A scene number is NaN or infinite.
    #[error("scene: {what} is not finite")]
    NonFiniteScene {
        /// Which input.
        what: &'static str,
    },
}

/// Why the physics was declared broken; the episode ends, nothing panics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PhysicsFailure {
    /// A position or velocity became NaN or infinite (or rapier quarantined a body).
    NonFinite,
    /// A body moved faster than the bound.
    TooFast {
        /// Speed (m/s).
        speed: f64,
    },
    /// The object left the scene.
    ObjectLost {
        /// Distance from its start (m).
        distance: f64,
    },
    /// A contact with the object penetrated too deep.
    DeepPenetration {
        /// Penetration depth (m).
        depth: f64,
        /// What the object touched there: a hand link's name, or `table`.
        with: String,
        /// The object's convex part (index in its decomposition), for compound objects.
        part: Option<usize>,
    },
    /// The rapier step panicked (caught).
    Panic,
    /// The simulator refused the episode's scene (the episode never ran).
    RefusedScene {
        /// Why, as the simulator's error says.
        reason: String,
    },
}

impl PhysicsFailure {
    /// The failure's kind as one word (`deep_penetration`, `too_fast`, ...), as its JSON
    /// `kind` field says.
    pub fn kind(&self) -> &'static str {
        match self {
            PhysicsFailure::NonFinite => "non_finite",
            PhysicsFailure::TooFast { .. } => "too_fast",
            PhysicsFailure::ObjectLost { .. } => "object_lost",
            PhysicsFailure::DeepPenetration { .. } => "deep_penetration",
            PhysicsFailure::Panic => "panic",
            PhysicsFailure::RefusedScene { .. } => "refused_scene",
        }
    }
}

impl std::fmt::Display for PhysicsFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PhysicsFailure::NonFinite => write!(f, "non-finite state"),
            PhysicsFailure::TooFast { speed } => write!(f, "a body at {speed:.1} m/s"),
            PhysicsFailure::ObjectLost { distance } => {
                write!(f, "object {distance:.2} m from its start")
            }
            PhysicsFailure::DeepPenetration { depth, with, part } => {
                write!(f, "{:.1} mm deep contact with {with}", depth * 1e3)?;
                if let Some(p) = part {
                    write!(f, " (object part {p})")?;
                }
                Ok(())
            }
            PhysicsFailure::Panic => write!(f, "the physics step panicked"),
            PhysicsFailure::RefusedScene { reason } => write!(f, "scene refused: {reason}"),
        }
    }
}

/// A physics failure and the physics step (since the reset) at which it was detected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureReport {
    /// What broke (serialised flat: `kind` and its fields).
    #[serde(flatten)]
    pub failure: PhysicsFailure,
    /// Physics step since the reset.
    pub step: u64,
}

/// A contact of the object with the hand or the table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectContact {
    /// Penetration depth (m; positive inside).
    pub depth: f64,
    /// What the object touched: a hand link's name, or `table`.
    pub with: String,
    /// The object's convex part (index in its decomposition), for compound objects.
    pub part: Option<usize>,
    /// Physics step since the reset at which it was seen.
    pub step: u64,
}

/// Result of the lift that ends an episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LiftOutcome {
    /// The object is held: lowest point high enough and in contact with the hand.
    pub success: bool,
    /// The object's lowest point above the table top at the end (m).
    pub object_lowest_z: f64,
    /// Whether the object touches the hand at the end.
    pub in_contact: bool,
    /// How far the object turned during the lift (rad, 0 to pi): the angle of the
    /// rotation from its orientation when the lift began to its orientation at the end.
    /// A grasp that holds the object keeps it small; a large turn is the object tipping,
    /// pivoting about the fingers or swinging in the grasp.
    pub object_turn: f64,
    /// The grip the fingers held through the lift: the sum over the 22 finger joints of
    /// the absolute PD effort (N m), averaged over the lift's physics steps.
    pub grip_effort: f64,
    /// Set when the physics broke during the episode.
    pub failure: Option<PhysicsFailure>,
}

/// The state of the whole rapier world that a reset restores.
#[derive(Clone)]
struct Sets {
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
}

/// One simulated hand joint.
#[derive(Debug, Clone, Copy)]
struct HandJoint {
    link: usize,
    /// Whether the joint has limits (revolute; a continuous joint has none).
    limited: bool,
    kp: f64,
    kd: f64,
    effort: f64,
    lower: f64,
    upper: f64,
}

/// A hand body and the URDF links merged into it, with their poses in the body frame.
type BodyLinks = (RigidBodyHandle, Vec<(usize, Isometry3<f64>)>);

const HAND_GROUP: Group = Group::GROUP_1;
const TABLE_GROUP: Group = Group::GROUP_2;
const OBJECT_GROUP: Group = Group::GROUP_3;
/// The object's convex hull, its collider against the table (`contacts.table_hull`).
const OBJECT_HULL_GROUP: Group = Group::GROUP_4;
/// Half length (m) of the capsule that stands in for a URDF sphere (see `HandSim::new`).
const SPHERE_AS_CAPSULE_HALF_LENGTH: f32 = 1e-4;
/// Travel of the lift joint (m): its limits, far from anything an episode reaches.
const LIFT_LIMITS: [f64; 2] = [-0.5, 1.0];
/// Height (m) by which the whole hand must clear the object's top for a lift to count as
/// decided (see `HandSim::dropped`).
const DECIDED_CLEARANCE: f64 = 0.01;
/// Mass given to a body whose links have no inertial (kg).
const MIN_LINK_MASS: f64 = 1e-3;

fn pose_f32(p: &Isometry3<f64>) -> Pose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    Pose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
    )
}

/// A rapier vector in f64.
fn vec_f64(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// A rapier pose in f64 (the inverse of [`pose_f32`]).
fn pose_f64(p: &Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        nalgebra::Translation3::from(vec_f64(p.translation)),
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            p.rotation.w as f64,
            p.rotation.x as f64,
            p.rotation.y as f64,
            p.rotation.z as f64,
        )),
    )
}

/// A narrow phase with the contact check of [`HullContactDispatcher`] when
/// `contacts.check_normals` is on and its table contacts of the object's hull when
/// `contacts.table_hull` is, parry's contacts as they are otherwise.
fn narrow_phase(cfg: &SimConfig, sets: &Sets, table: ColliderHandle) -> NarrowPhase {
    let c = &cfg.contacts;
    if c.check_normals || c.table_hull {
        let table = c
            .table_hull
            .then(|| sets.colliders.get(table).map(|t| t.shape()))
            .flatten()
            .map(|t| (t, c.table_hull_stiffness as f32));
        NarrowPhase::with_query_dispatcher(HullContactDispatcher::new(c.check_normals, table))
    } else {
        NarrowPhase::new()
    }
}

/// The multibody whose root link is `root` (the hand's), mutably.
fn hand_multibody_mut(
    set: &mut MultibodyJointSet,
    root: RigidBodyHandle,
) -> Option<&mut Multibody> {
    let link = *set.rigid_body_link(root)?;
    set.get_multibody_mut(link.multibody)
}

/// Rotation taking the x axis to `axis` (unit).
fn x_to(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::x(), axis).unwrap_or_else(|| {
        // axis = -x: turn half a revolution about z.
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
    })
}

/// What [`HandSim::critic_geometry`] returns, in the world frame (m, m/s, rad/s).
#[derive(Debug, Clone, PartialEq)]
pub struct CriticGeometry {
    /// The palm body's pose.
    pub palm: Isometry3<f64>,
    /// The object body's pose.
    pub object: Isometry3<f64>,
    /// The object's linear velocity.
    pub object_linvel: Vector3<f64>,
    /// The object's angular velocity.
    pub object_angvel: Vector3<f64>,
    /// For FF, MF, RF, LF, TH distal and the palm: (collider centre, nearest object
    /// surface point).
    pub nearest: [(Point3<f64>, Point3<f64>); 6],
}

/// The hand, a table and one object, simulated in Rapier. `Send`: many can be stepped in
/// parallel with rayon.
pub struct HandSim {
    cfg: SimConfig,
    template: Sets,
    sets: Sets,
    pipeline: PhysicsPipeline,
    islands: IslandManager,
    broad_phase: DefaultBroadPhase,
    narrow_phase: NarrowPhase,
    ccd: CCDSolver,
    soft: SoftBodySet,
    params: IntegrationParameters,
    robot: Robot,
    mb_root: RigidBodyHandle,
    lift_link: usize,
    joints: [HandJoint; 24],
    hand_bodies: Vec<RigidBodyHandle>,
    hand_colliders: Vec<ColliderHandle>,
    distal_colliders: [Vec<ColliderHandle>; 5],
    object: ObjectSpec,
    object_body: RigidBodyHandle,
    object_collider: ColliderHandle,
    /// The object's convex hull, which alone meets the table (`contacts.table_hull`);
    /// invalid otherwise.
    object_hull: ColliderHandle,
    object_start: Vector3<f64>,
    table: ColliderHandle,
    targets: [f64; 24],
    lift_target: f64,
    physics_steps: u64,
    /// The physics failure that ended the episode, with its step.
    failure: Option<FailureReport>,
    /// The deepest contact of the object since the reset.
    deepest: Option<ObjectContact>,
    /// Each hand collider's link name (for failure reports).
    collider_links: Vec<(ColliderHandle, String)>,
    recorder: Option<record::FrameRecorder>,
}

impl HandSim {
    /// Builds the world for `robot` (its Shadow hand), `object` and `cfg`, and resets it to
    /// the object on the table with the open hand 3 cm above its centre.
    pub fn new(robot: &Robot, object: ObjectSpec, cfg: SimConfig) -> Result<HandSim, SimError> {
        cfg.validate()?;
        object.validate()?;
        let mut sets = Sets {
            bodies: RigidBodySet::new(),
            colliders: ColliderSet::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
        };
        // The order of insertion fixes every handle: table, bodies, colliders, joints.
        let table = build::table(&mut sets, &cfg);
        let mb_root = sets.bodies.insert(RigidBodyBuilder::fixed());
        let bodies = build::hand_bodies(robot, &mut sets)?;
        let colliders = build::hand_colliders(robot, &cfg, &mut sets, &bodies)?;
        build::attach_lift(robot, &cfg, &mut sets, mb_root, bodies.root)?;
        let handles = build::revolute_joints(robot, &cfg, &mut sets, &bodies)?;
        let joints = build::joint_table(robot, &sets, &handles)?;
        let lift_link = build::couple_and_damp(robot, &cfg, &mut sets, bodies.root, &joints)?;
        let rb_root = bodies.root;
        let hand_bodies = bodies.body_links.iter().map(|(b, _)| *b).collect();
        let build::HandColliders {
            all: hand_colliders,
            links: collider_links,
            distal: distal_colliders,
        } = colliders;
        let params = build::integration_parameters(&cfg);
        let narrow_phase = narrow_phase(&cfg, &sets, table);
        let mut sim = HandSim {
            cfg,
            template: sets.clone(),
            sets,
            pipeline: PhysicsPipeline::new(),
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::default(),
            narrow_phase,
            ccd: CCDSolver::new(),
            soft: SoftBodySet::new(),
            params,
            robot: robot.clone(),
            mb_root: rb_root,
            lift_link,
            joints,
            hand_bodies,
            hand_colliders,
            distal_colliders,
            object: object.clone(),
            object_body: RigidBodyHandle::invalid(),
            object_collider: ColliderHandle::invalid(),
            object_hull: ColliderHandle::invalid(),
            object_start: Vector3::zeros(),
            table,
            targets: [0.0; 24],
            lift_target: 0.0,
            physics_steps: 0,
            failure: None,
            deepest: None,
            collider_links,
            recorder: None,
        };
        sim.insert_object(object.clone());
        let start = crate::robot::Posture::Open.angles();
        sim.reset(&Scene::above(&object, start, 0.03, 0.0))?;
        Ok(sim)
    }

    fn insert_object(&mut self, object: ObjectSpec) {
        let t = &mut self.template;
        if self.object_body != RigidBodyHandle::invalid() {
            let mut islands = IslandManager::new();
            t.bodies.remove(
                self.object_body,
                &mut islands,
                &mut t.colliders,
                &mut t.impulse_joints,
                &mut t.multibody_joints,
                &mut SoftBodySet::new(),
                true,
            );
        }
        // Mass properties set on the body; the collider has density 0.
        let body = t.bodies.insert(
            RigidBodyBuilder::dynamic()
                .can_sleep(false)
                .angular_damping(self.cfg.object_angular_damping as f32)
                .additional_mass_properties(object.mass_properties())
                .translation(Vector::new(0.0, 0.0, object.rest_height() as f32)),
        );
        // With `contacts.table_hull` a library object meets the table with its convex
        // hull, a second collider, and the hand with its parts.
        let hull = object
            .shape
            .table_hull()
            .filter(|_| self.cfg.contacts.table_hull);
        let meets = if hull.is_some() {
            Group::ALL.difference(TABLE_GROUP)
        } else {
            Group::ALL
        };
        // Zero mass given explicitly, not as density 0: with a density rapier recomputes
        // the compound's mass properties (tetrahedra of every convex part) whenever the
        // body's mass is updated, i.e. after every reset.
        let massless = |b: ColliderBuilder, membership: Group, filter: Group| {
            b.mass_properties(MassProperties::default())
                .friction(object.friction as f32)
                .friction_combine_rule(CoefficientCombineRule::Min)
                .collision_groups(InteractionGroups::new(
                    membership,
                    filter,
                    InteractionTestMode::And,
                ))
        };
        let collider = t.colliders.insert_with_parent(
            massless(object.shape.collider(), OBJECT_GROUP, meets),
            body,
            &mut t.bodies,
        );
        self.object_hull = match hull {
            Some(h) => t.colliders.insert_with_parent(
                massless(
                    ColliderBuilder::new(h.clone()),
                    OBJECT_HULL_GROUP,
                    TABLE_GROUP,
                ),
                body,
                &mut t.bodies,
            ),
            None => ColliderHandle::invalid(),
        };
        self.object = object;
        self.object_body = body;
        self.object_collider = collider;
    }

    /// Replaces the object (validated); takes effect at the next [`HandSim::reset`].
    pub fn set_object(&mut self, object: ObjectSpec) -> Result<(), SimError> {
        object.validate()?;
        self.insert_object(object);
        Ok(())
    }

    /// The config in use.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// The robot model in use.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The object in use.
    pub fn object(&self) -> &ObjectSpec {
        &self.object
    }

    /// Restores the template world and places hand and object as `scene` says: joints at the
    /// start posture (clamped to limits; coupled J1 = J2 = their mean), targets = start,
    /// object resting on the table, lift at 0.
    pub fn reset(&mut self, scene: &Scene) -> Result<(), SimError> {
        self.reset_object_at(scene, None)
    }

    /// [`HandSim::reset`] with the object at `pose` instead of resting upright at the
    /// scene's `object_xy` and `object_yaw`: where an earlier attempt left it at rest (a
    /// retry after a failed lift; the scene's object fields are not used). The object
    /// starts still, as it lay.
    pub fn reset_with_object_pose(
        &mut self,
        scene: &Scene,
        pose: &Isometry3<f64>,
    ) -> Result<(), SimError> {
        let finite = pose.translation.vector.iter().all(|v| v.is_finite())
            && pose.rotation.coords.iter().all(|v| v.is_finite());
        if !finite {
            return Err(SimError::NonFiniteScene {
                what: "object pose",
            });
        }
        self.reset_object_at(scene, Some(pose))
    }

    fn reset_object_at(
        &mut self,
        scene: &Scene,
        object_pose: Option<&Isometry3<f64>>,
    ) -> Result<(), SimError> {
        scene.check()?;
        let start = self.clamp_targets(&scene.start);
        let gp = Point3::from(scene.grasp_point);
        let root_pose = hand_root_pose(&self.robot, &gp, scene.hand_yaw, &start)?;
        self.sets = self.template.clone();
        self.pipeline = PhysicsPipeline::new();
        self.islands = IslandManager::new();
        self.broad_phase = DefaultBroadPhase::default();
        self.narrow_phase = narrow_phase(&self.cfg, &self.sets, self.table);
        self.ccd = CCDSolver::new();
        self.soft = SoftBodySet::new();
        self.physics_steps = 0;
        self.failure = None;
        self.deepest = None;
        // Lift frames: frame1 at the flange position with x along world z; the forearm at
        // `root_pose` when the lift coordinate is 0.
        let up = x_to(&Vector3::z());
        let f1 = Isometry3::from_parts(root_pose.translation, up);
        let f2 = root_pose.inverse() * f1;
        let Some(mb) = hand_multibody_mut(&mut self.sets.multibody_joints, self.mb_root) else {
            return Err(self.lost());
        };
        if let Some(l) = mb.link_mut(self.lift_link) {
            l.joint.data.set_local_frame1(pose_f32(&f1));
            l.joint.data.set_local_frame2(pose_f32(&f2));
        }
        let mut disp = vec![0.0f32; mb.ndofs()];
        for (n, hj) in self.joints.iter().enumerate() {
            if let Some(l) = mb.link(hj.link) {
                disp[l.assembly_id()] = start[n] as f32 - l.joint().coords()[3];
            }
        }
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&self.sets.bodies, false);
        mb.update_rigid_bodies(&mut self.sets.bodies, true);
        // Object.
        let obj_pose = object_pose.copied().unwrap_or_else(|| {
            let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), scene.object_yaw);
            Isometry3::from_parts(
                Vector3::new(
                    scene.object_xy[0],
                    scene.object_xy[1],
                    self.object.rest_height(),
                )
                .into(),
                rot,
            )
        });
        self.object_start = obj_pose.translation.vector;
        if let Some(rb) = self.sets.bodies.get_mut(self.object_body) {
            rb.set_position(pose_f32(&obj_pose), true);
        }
        self.targets = start;
        self.lift_target = 0.0;
        self.apply_targets();
        Ok(())
    }

    fn lost(&self) -> SimError {
        build::robot_err(&self.robot, "the hand multibody was lost".into())
    }

    /// Clamps to limits and applies the J1 = J2 = J0/2 coupling.
    fn clamp_targets(&self, t: &[f64; 24]) -> [f64; 24] {
        let limits = self.joints.map(|hj| (hj.lower, hj.upper));
        crate::robot::joints::couple_and_clamp(t, &limits)
    }

    /// Sets the 24 joint targets (paper order; rad). Coupled joints follow J0 = J1 + J2
    /// (each gets J0/2); every target is clamped to its joint's limits. A NaN or infinite
    /// target is rejected and nothing changes.
    pub fn set_targets(&mut self, targets: &[f64; 24]) -> Result<(), SimError> {
        if let Some((index, value)) = targets
            .iter()
            .copied()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(SimError::NonFiniteTarget {
                joint: HAND_JOINTS[index],
                index,
                value,
            });
        }
        self.targets = self.clamp_targets(targets);
        self.apply_targets();
        Ok(())
    }

    /// The current joint targets (after clamping and coupling).
    pub fn targets(&self) -> [f64; 24] {
        self.targets
    }

    /// Writes the targets into the motor rows (`drive = "motor_row"`); with implicit
    /// drives they take effect in [`HandSim::step_physics`] (see `update_drives`).
    fn apply_targets(&mut self) {
        if self.cfg.drive != DriveModel::MotorRow {
            return;
        }
        let Some(mb) = hand_multibody_mut(&mut self.sets.multibody_joints, self.mb_root) else {
            return;
        };
        for (n, hj) in self.joints.iter().enumerate() {
            if let Some(l) = mb.link_mut(hj.link) {
                l.joint.data.set_motor_position(
                    JointAxis::AngX,
                    self.targets[n] as f32,
                    hj.kp as f32,
                    hj.kd as f32,
                );
            }
        }
        if let Some(l) = mb.link_mut(self.lift_link) {
            l.joint.data.set_motor_position(
                JointAxis::LinX,
                self.lift_target as f32,
                self.cfg.motors.lift.kp as f32,
                self.cfg.motors.lift.kd as f32,
            );
        }
    }

    /// The physics failure that ended the episode, if any.
    pub fn failure(&self) -> Option<&PhysicsFailure> {
        self.failure.as_ref().map(|f| &f.failure)
    }

    /// The physics step (since the reset) at which [`HandSim::failure`] was detected.
    pub fn failure_step(&self) -> Option<u64> {
        self.failure.as_ref().map(|f| f.step)
    }

    /// [`HandSim::failure`] with its step.
    pub fn failure_report(&self) -> Option<FailureReport> {
        self.failure.clone()
    }

    /// The deepest contact of the object (with the hand or the table) seen since the
    /// reset, penetrations below the failure threshold included; `None` before any
    /// penetrating contact.
    pub fn deepest_contact(&self) -> Option<&ObjectContact> {
        self.deepest.as_ref()
    }

    /// Ends the episode with `failure` (e.g. a scene the simulator refused), as a
    /// detected physics failure does: every later step does nothing.
    pub fn fail(&mut self, failure: PhysicsFailure) {
        if self.failure.is_none() {
            self.failure = Some(FailureReport {
                failure,
                step: self.physics_steps,
            });
        }
    }

    /// Physics steps since the last reset.
    pub fn physics_steps(&self) -> u64 {
        self.physics_steps
    }

    /// Simulated seconds since the last reset.
    pub fn time(&self) -> f64 {
        self.physics_steps as f64 * self.cfg.dt
    }

    /// Runs one physics step; returns false (and records the failure) when the physics
    /// broke. Does nothing once a failure is recorded.
    pub fn step_physics(&mut self) -> bool {
        if self.failure.is_some() {
            return false;
        }
        self.update_drives();
        let gravity = Vector::new(0.0, 0.0, self.cfg.gravity as f32);
        let stepped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            self.pipeline.step(
                gravity,
                &self.params,
                &mut self.islands,
                &mut self.broad_phase,
                &mut self.narrow_phase,
                &mut self.sets.bodies,
                &mut self.sets.colliders,
                &mut self.sets.impulse_joints,
                &mut self.sets.multibody_joints,
                &mut self.soft,
                &mut self.ccd,
                &(),
                &(),
            );
        }));
        self.physics_steps += 1;
        let failure = if stepped.is_err() {
            Some(PhysicsFailure::Panic)
        } else {
            self.check_physics()
        };
        self.failure = failure.map(|failure| FailureReport {
            failure,
            step: self.physics_steps,
        });
        self.record_step();
        self.failure.is_none()
    }

    /// Before a physics step: moves each implicit spring's rest point so that it applies
    /// the clamped PD effort of [`pd_effort`] at the current state (`drive = "spring"`),
    /// and turns each joint limit's solver row on only near its bound (`limit_rows =
    /// "near"`).
    fn update_drives(&mut self) {
        let spring = self.cfg.drive == DriveModel::Spring;
        let near = self.cfg.limit_rows == LimitRows::Near;
        if !spring && !near {
            return;
        }
        let (dt, margin) = (self.cfg.dt, self.cfg.limit_margin);
        let Some(mb) = hand_multibody_mut(&mut self.sets.multibody_joints, self.mb_root) else {
            return;
        };
        let lift = self.cfg.motors.lift;
        let lift_joint = HandJoint {
            link: self.lift_link,
            limited: true,
            kp: lift.kp,
            kd: lift.kd,
            effort: self.cfg.motors.lift_max_force,
            lower: LIFT_LIMITS[0],
            upper: LIFT_LIMITS[1],
        };
        let drives = self
            .joints
            .iter()
            .zip(self.targets)
            .map(|(hj, t)| (hj, t, JointAxesMask::ANG_X, 3))
            .chain(std::iter::once((
                &lift_joint,
                self.lift_target,
                JointAxesMask::LIN_X,
                0,
            )));
        for (hj, target, axis, coord) in drives {
            let Some(l) = mb.link(hj.link) else {
                continue;
            };
            let q = l.joint().coords()[coord] as f64;
            let qd = mb.joint_velocity(l)[0] as f64;
            let Some(l) = mb.link_mut(hj.link) else {
                continue;
            };
            if spring {
                let rest = spring_rest(hj.kp, hj.kd, target, q, qd, hj.effort);
                l.joint.set_spring(coord, hj.kp as f32, rest as f32);
            }
            if near && hj.limited {
                let active = near_limit(q, qd, hj.lower, hj.upper, margin, dt);
                l.joint.data.limit_axes.set(axis, active);
            }
        }
    }

    /// Runs one control period (`control_period / dt` physics steps) with the current
    /// targets; returns false when the physics broke (see [`HandSim::failure`]).
    pub fn step_control(&mut self) -> bool {
        for _ in 0..self.cfg.steps_per_control() {
            if !self.step_physics() {
                return false;
            }
        }
        true
    }

    /// Raises the hand by `lift.height` over `lift.ramp_time` with a smooth (cubic) profile,
    /// finger targets held, holds `lift.hold_time`, and judges: success when the object's
    /// lowest point is at least `lift.success_height` above the table AND it touches the
    /// hand. With `lift.stop_when_dropped` the lift ends as soon as the whole hand is above
    /// the object (a failure either way).
    pub fn lift_and_judge(&mut self) -> LiftOutcome {
        let l = self.cfg.lift;
        let ramp = (l.ramp_time / self.cfg.dt).round().max(1.0) as usize;
        let hold = (l.hold_time / self.cfg.dt).round() as usize;
        let (mut grip_sum, mut grip_steps) = (0.0, 0usize);
        let start = self.object_pose().map(|p| p.rotation);
        for k in 0..ramp + hold {
            if self.failure.is_some() {
                break;
            }
            let s = ((k + 1) as f64 / ramp as f64).min(1.0);
            self.lift_target = l.height * s * s * (3.0 - 2.0 * s);
            self.apply_targets();
            self.step_physics();
            grip_sum += finger_grip(&self.joint_efforts());
            grip_steps += 1;
            if l.stop_when_dropped && self.dropped() {
                break;
            }
        }
        let lowest = self.object_lowest_z();
        let in_contact = self.hand_object_force() > 0.0;
        let failure = self.failure().cloned();
        let object_turn = match (start, self.object_pose()) {
            (Some(a), Some(b)) => a.angle_to(&b.rotation),
            _ => 0.0,
        };
        LiftOutcome {
            success: failure.is_none() && lowest >= l.success_height && in_contact,
            object_lowest_z: lowest,
            in_contact,
            object_turn,
            grip_effort: grip_sum / grip_steps.max(1) as f64,
            failure,
        }
    }
}

/// The grip of a hand posture's efforts (24 hand joints, paper order: the two wrist
/// joints first): the sum of the 22 finger joints' absolute efforts (N m).
pub fn finger_grip(effort: &[f64; 24]) -> f64 {
    effort[2..].iter().map(|e| e.abs()).sum()
}

#[cfg(test)]
mod tests;
