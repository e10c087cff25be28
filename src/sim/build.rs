//! The steps of [`super::HandSim::new`]: the table, the hand's bodies, their masses and
//! colliders, the lift, the revolute joints, the joint table, the J1 = J2 coupling and the
//! implicit drives' damping, and the integration parameters. Each inserts into the rapier
//! sets in a fixed order, so the handles (and every result) are the same build to build.

use super::{
    pose_f32, x_to, BodyLinks, HandJoint, Sets, SimError, HAND_GROUP, LIFT_LIMITS, MIN_LINK_MASS,
    OBJECT_GROUP, OBJECT_HULL_GROUP, SPHERE_AS_CAPSULE_HALF_LENGTH, TABLE_GROUP,
};
use crate::robot::joints::{COUPLED_FINGERS, HAND_JOINTS};
use crate::robot::model::{Geometry, JointKind, Link};
use crate::robot::Robot;
use crate::sim::config::{CoriolisModel, DriveModel, Gains, SimConfig};
use nalgebra::{Isometry3, Vector3};
use rapier3d::prelude::*;

/// An error of the robot's model, naming its file.
pub(super) fn robot_err(robot: &Robot, message: String) -> SimError {
    SimError::Robot {
        robot: robot.source.display().to_string(),
        message,
    }
}

/// The table: its top at z = 0.
pub(super) fn table(sets: &mut Sets, cfg: &SimConfig) -> ColliderHandle {
    let table_body = sets
        .bodies
        .insert(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, -0.05)));
    sets.colliders.insert_with_parent(
        ColliderBuilder::cuboid(1.0, 1.0, 0.05)
            .friction(cfg.friction.table as f32)
            .friction_combine_rule(CoefficientCombineRule::Min)
            .collision_groups(InteractionGroups::new(
                TABLE_GROUP,
                HAND_GROUP | OBJECT_GROUP | OBJECT_HULL_GROUP,
                InteractionTestMode::And,
            )),
        table_body,
        &mut sets.bodies,
    )
}

/// The hand's rigid bodies: one per movable link, fixed links merged into their parent's.
pub(super) struct HandBodies {
    /// The forearm's body (the multibody's root link, on the lift).
    pub root: RigidBodyHandle,
    /// Per URDF link, its body and its pose in that body's frame.
    pub link_body: Vec<Option<(RigidBodyHandle, Isometry3<f64>)>>,
    /// Per body, the links merged into it.
    pub body_links: Vec<BodyLinks>,
    /// The movable joints still to insert: (joint index, child link).
    pub pending: Vec<(usize, usize)>,
}

/// Creates the hand's bodies (masses need all merged links first, joints come later).
pub(super) fn hand_bodies(robot: &Robot, sets: &mut Sets) -> Result<HandBodies, SimError> {
    let mut link_body: Vec<Option<(RigidBodyHandle, Isometry3<f64>)>> =
        vec![None; robot.links.len()];
    let mut body_links: Vec<BodyLinks> = Vec::new();
    let root = robot.root;
    let mut pending: Vec<(usize, usize)> = Vec::new();
    let new_body = |sets: &mut Sets| {
        sets.bodies
            .insert(RigidBodyBuilder::dynamic().can_sleep(false))
    };
    let rb_root = new_body(sets);
    link_body[root] = Some((rb_root, Isometry3::identity()));
    body_links.push((rb_root, vec![(root, Isometry3::identity())]));
    for (k, j) in robot.joints.iter().enumerate() {
        let Some((pb, poff)) = link_body[j.parent] else {
            return Err(robot_err(
                robot,
                format!("joint '{}' has an unplaced parent", j.name),
            ));
        };
        match j.kind {
            JointKind::Fixed => {
                let off = poff * j.origin;
                link_body[j.child] = Some((pb, off));
                if let Some(e) = body_links.iter_mut().find(|(b, _)| *b == pb) {
                    e.1.push((j.child, off));
                }
            }
            JointKind::Revolute | JointKind::Continuous => {
                let b = new_body(sets);
                link_body[j.child] = Some((b, Isometry3::identity()));
                body_links.push((b, vec![(j.child, Isometry3::identity())]));
                pending.push((k, j.child));
            }
            JointKind::Prismatic => {
                return Err(robot_err(
                    robot,
                    format!(
                        "joint '{}': prismatic hand joints are not supported",
                        j.name
                    ),
                ))
            }
        }
    }
    Ok(HandBodies {
        root: rb_root,
        link_body,
        body_links,
        pending,
    })
}

/// The hand's colliders.
pub(super) struct HandColliders {
    /// Every hand collider.
    pub all: Vec<ColliderHandle>,
    /// Each collider's link name (for failure reports).
    pub links: Vec<(ColliderHandle, String)>,
    /// Per finger (TH, FF, MF, RF, LF), the colliders of its distal body.
    pub distal: [Vec<ColliderHandle>; 5],
}

/// The mass properties of a body from its merged links' inertials (a small sphere's when
/// they have none).
fn body_mass(robot: &Robot, links: &[(usize, Isometry3<f64>)]) -> MassProperties {
    let mut mp = MassProperties::default();
    let mut mass = 0.0;
    for (l, off) in links {
        if let Some(i) = &robot.links[*l].inertial {
            let m3 = i.inertia.map(|v| v as f32);
            let inertia = rapier3d::math::Matrix::from_cols_array(&[
                m3[(0, 0)],
                m3[(1, 0)],
                m3[(2, 0)],
                m3[(0, 1)],
                m3[(1, 1)],
                m3[(2, 1)],
                m3[(0, 2)],
                m3[(1, 2)],
                m3[(2, 2)],
            ]);
            let local = MassProperties::with_inertia_matrix(Vector::ZERO, i.mass as f32, inertia);
            mp += local.transform_by(&pose_f32(&(off * i.origin)));
            mass += i.mass;
        }
    }
    if mass <= 0.0 {
        let r = 0.01f32;
        let m = MIN_LINK_MASS as f32;
        mp = MassProperties::new(Vector::ZERO, m, Vector::splat(0.4 * m * r * r));
    }
    mp
}

/// The rapier shape of a link's collision geometry and its pose in the geometry's frame.
fn collision_shape(
    robot: &Robot,
    link: &Link,
    geometry: &Geometry,
) -> Result<(SharedShape, Isometry3<f64>), SimError> {
    Ok(match geometry {
        Geometry::Cuboid { half } => (
            SharedShape::cuboid(half.x as f32, half.y as f32, half.z as f32),
            Isometry3::identity(),
        ),
        Geometry::Cylinder { radius, length } => (
            SharedShape::cylinder((length / 2.0) as f32, *radius as f32),
            Isometry3::rotation(Vector3::x() * std::f64::consts::FRAC_PI_2),
        ),
        Geometry::Capsule { radius, length } => (
            SharedShape::capsule_z((length / 2.0) as f32, *radius as f32),
            Isometry3::identity(),
        ),
        // A sphere is simulated as a capsule 0.2 mm long (the same surface within 0.1 mm).
        // parry's ball-vs-convex-polyhedron contact query sometimes returns a bogus
        // penetration of about 2 cm while the ball is 3 mm away (traced: a fingertip at the
        // 738-vertex egg hull went from +3.0 mm to -22.8 mm in one step with 0.6 mm of
        // motion); the general convex path used for capsules does not. Baseline 2, 38
        // episodes: physics failures 11 -> 1 (unseen) and 3 -> 2 (train).
        Geometry::Sphere { radius } => (
            SharedShape::capsule_z(SPHERE_AS_CAPSULE_HALF_LENGTH, *radius as f32),
            Isometry3::identity(),
        ),
        Geometry::Mesh { path, .. } => {
            return Err(robot_err(
                robot,
                format!(
                    "link '{}': mesh collision '{}' is not supported by the simulator (use \
                     primitive collision geometry)",
                    link.name,
                    path.display()
                ),
            ))
        }
    })
}

/// Sets each hand body's mass and inserts its links' colliders, body by body.
pub(super) fn hand_colliders(
    robot: &Robot,
    cfg: &SimConfig,
    sets: &mut Sets,
    bodies: &HandBodies,
) -> Result<HandColliders, SimError> {
    let mut out = HandColliders {
        all: Vec::new(),
        links: Vec::new(),
        distal: Default::default(),
    };
    let groups = InteractionGroups::new(
        HAND_GROUP,
        TABLE_GROUP | OBJECT_GROUP,
        InteractionTestMode::And,
    );
    for (b, links) in &bodies.body_links {
        let mp = body_mass(robot, links);
        if let Some(rb) = sets.bodies.get_mut(*b) {
            rb.set_additional_mass_properties(mp, false);
        }
        for (l, off) in links {
            let link = &robot.links[*l];
            for c in &link.collisions {
                let pose = off * c.origin;
                let (shape, extra) = collision_shape(robot, link, &c.geometry)?;
                let h = sets.colliders.insert_with_parent(
                    ColliderBuilder::new(shape)
                        .position(pose_f32(&(pose * extra)))
                        .mass_properties(MassProperties::default())
                        .friction(cfg.friction.hand as f32)
                        .friction_combine_rule(CoefficientCombineRule::Min)
                        .collision_groups(groups),
                    *b,
                    &mut sets.bodies,
                );
                out.all.push(h);
                out.links.push((h, link.name.clone()));
                for f in 0..5 {
                    if bodies.link_body[robot.hand.distal[f]].map(|x| x.0) == Some(*b) {
                        out.distal[f].push(h);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Attaches the forearm's body to the fixed multibody root by the lift joint (its frames
/// are set at reset).
pub(super) fn attach_lift(
    robot: &Robot,
    cfg: &SimConfig,
    sets: &mut Sets,
    mb_root: RigidBodyHandle,
    rb_root: RigidBodyHandle,
) -> Result<(), SimError> {
    let mut lift = GenericJointBuilder::new(JointAxesMask::LOCKED_PRISMATIC_AXES).limits(
        JointAxis::LinX,
        [LIFT_LIMITS[0] as f32, LIFT_LIMITS[1] as f32],
    );
    if cfg.drive == DriveModel::MotorRow {
        lift = lift
            .motor_model(JointAxis::LinX, MotorModel::ForceBased)
            .motor_max_force(JointAxis::LinX, cfg.motors.lift_max_force as f32)
            .motor_position(
                JointAxis::LinX,
                0.0,
                cfg.motors.lift.kp as f32,
                cfg.motors.lift.kd as f32,
            );
    }
    sets.multibody_joints
        .insert(mb_root, rb_root, lift.build(), true)
        .ok_or_else(|| robot_err(robot, "cannot attach the forearm to the lift".into()))?;
    Ok(())
}

/// A movable joint's multibody handle and drive gains.
pub(super) type JointHandle = Option<(MultibodyJointHandle, Gains)>;

/// Inserts the revolute (and continuous) joints; per URDF joint, its handle and gains.
pub(super) fn revolute_joints(
    robot: &Robot,
    cfg: &SimConfig,
    sets: &mut Sets,
    bodies: &HandBodies,
) -> Result<Vec<JointHandle>, SimError> {
    let err = |m: String| robot_err(robot, m);
    let motor_rows = cfg.drive == DriveModel::MotorRow;
    let mut joint_handles = vec![None; robot.joints.len()];
    for &(k, child) in &bodies.pending {
        let j = &robot.joints[k];
        let (pb, poff) = bodies.link_body[j.parent].ok_or_else(|| err("unplaced link".into()))?;
        let (cb, _) = bodies.link_body[child].ok_or_else(|| err("unplaced link".into()))?;
        let a = x_to(&j.axis);
        let f1 = poff * j.origin * Isometry3::from_parts(Default::default(), a);
        let f2 = Isometry3::from_parts(Default::default(), a);
        let gains = cfg.motors.for_joint(&j.name);
        let mut b = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
            .local_frame1(pose_f32(&f1))
            .local_frame2(pose_f32(&f2));
        if motor_rows {
            b = b
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_max_force(JointAxis::AngX, j.effort as f32)
                .motor_position(JointAxis::AngX, 0.0, gains.kp as f32, gains.kd as f32);
        }
        if j.kind == JointKind::Revolute {
            b = b.limits(JointAxis::AngX, [j.lower as f32, j.upper as f32]);
        }
        let h = sets
            .multibody_joints
            .insert(pb, cb, b.build(), true)
            .ok_or_else(|| err(format!("joint '{}' closes a loop", j.name)))?;
        joint_handles[k] = Some((h, gains));
    }
    Ok(joint_handles)
}

/// The 24 hand joints in the canonical order: multibody link, limits, gains, effort.
pub(super) fn joint_table(
    robot: &Robot,
    sets: &Sets,
    handles: &[JointHandle],
) -> Result<[HandJoint; 24], SimError> {
    let err = |m: String| robot_err(robot, m);
    let mut joints = [HandJoint {
        link: 0,
        limited: false,
        kp: 0.0,
        kd: 0.0,
        effort: 0.0,
        lower: 0.0,
        upper: 0.0,
    }; 24];
    for (n, &ji) in robot.hand.joints.iter().enumerate() {
        let (h, gains) = handles[ji]
            .ok_or_else(|| err(format!("hand joint {} is not movable", HAND_JOINTS[n])))?;
        let (_, link) = sets
            .multibody_joints
            .get(h)
            .ok_or_else(|| err("lost a joint".into()))?;
        let jj = &robot.joints[ji];
        joints[n] = HandJoint {
            link,
            limited: jj.kind == JointKind::Revolute,
            kp: gains.kp,
            kd: gains.kd,
            effort: jj.effort,
            lower: jj.lower,
            upper: jj.upper,
        };
    }
    Ok(joints)
}

/// Couples J1 = J2 rigidly on the coupled fingers, gives the implicit drives the PD law's
/// damping on each driven DoF (the spring is set before every step, see `update_drives`)
/// and chooses the Coriolis model; returns the lift joint's multibody link.
pub(super) fn couple_and_damp(
    robot: &Robot,
    cfg: &SimConfig,
    sets: &mut Sets,
    rb_root: RigidBodyHandle,
    joints: &[HandJoint; 24],
) -> Result<usize, SimError> {
    let err = |m: &str| robot_err(robot, m.into());
    let lift_link = sets
        .multibody_joints
        .rigid_body_link(rb_root)
        .map(|l| l.id)
        .ok_or_else(|| err("lost the lift joint"))?;
    let mb_index = sets
        .multibody_joints
        .rigid_body_link(rb_root)
        .map(|l| l.multibody)
        .ok_or_else(|| err("lost the multibody"))?;
    let mb = sets
        .multibody_joints
        .get_multibody_mut(mb_index)
        .ok_or_else(|| err("lost the multibody"))?;
    for f in COUPLED_FINGERS {
        let j2 = crate::sim::hand_index(&format!("{f}J2"));
        let j1 = crate::sim::hand_index(&format!("{f}J1"));
        mb.add_dof_coupling(MultibodyDofCoupling {
            link1: joints[j2].link,
            dof1: 0,
            axis1: 3,
            link2: joints[j1].link,
            dof2: 0,
            axis2: 3,
            coeff: 1.0,
            offset: 0.0,
        });
    }
    if cfg.drive != DriveModel::MotorRow {
        let mut dofs: Vec<(usize, f64)> = joints
            .iter()
            .filter_map(|hj| mb.link(hj.link).map(|l| (l.assembly_id(), hj.kd)))
            .collect();
        if let Some(l) = mb.link(lift_link) {
            dofs.push((l.assembly_id(), cfg.motors.lift.kd));
        }
        let damping = mb.damping_mut();
        for (dof, kd) in dofs {
            damping[dof] = kd as f32;
        }
    }
    mb.set_implicit_coriolis(cfg.coriolis == CoriolisModel::Implicit);
    Ok(lift_link)
}

/// rapier's integration parameters from the simulator config.
pub(super) fn integration_parameters(cfg: &SimConfig) -> IntegrationParameters {
    let mut params = IntegrationParameters {
        dt: cfg.dt as f32,
        ..Default::default()
    };
    params.num_solver_iterations = cfg.substeps;
    params.num_internal_pgs_iterations = cfg.pgs_iterations;
    params.max_ccd_substeps = cfg.ccd_substeps;
    params.contact_clustering = cfg.contact_clustering;
    params.normalized_prediction_distance = cfg.prediction_distance as f32;
    let c = cfg.contacts;
    params.contact_recycling = c.recycle_distance > 0.0;
    params.normalized_contact_recycle_distance = c.recycle_distance as f32;
    params.contact_softness =
        SpringCoefficients::new(c.natural_frequency as f32, c.damping_ratio as f32);
    params.static_contact_softness = SpringCoefficients::new(
        c.static_natural_frequency as f32,
        c.static_damping_ratio as f32,
    );
    params
}
