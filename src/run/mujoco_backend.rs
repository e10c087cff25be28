//! [`MujocoHandArm`]: the hand, the table and one object simulated in MuJoCo (feature
//! `mujoco`), behind the same [`HandArm`] interface and raw-sensor model as the Rapier
//! backend ([`super::sim_backend::SimHandArm`]): a second, independent engine in which the
//! policies were never trained, for a sim-to-sim check before the real robot.
//!
//! The scene is [`super::mjcf::scene_xml`] with the engine settings of
//! `configs/mujoco.toml` ([`MujocoSettings`]); the same hand (URDF links, masses, joint
//! limits, PD gains and effort limits, J1 = J2), table, object (convex parts, mass,
//! inertia, friction) and lift (height, smoothstep ramp, hold) as the Rapier simulator.
//!
//! # Signals
//! - Fingertip force `F_k`: the sum of the normal forces of MuJoCo's contacts between the
//!   distal phalanx of finger `k` and the object (`mj_contactForce`), then the raw tactile
//!   model of [`super::raw_model`].
//! - Actuator efforts: MuJoCo's actuator forces (the clamped PD law), coupled J1 and J2
//!   summed into J0 ([`crate::robot::joints::actuator_sums`]), then the raw tendon model.
//! - Joint angles: `qpos` of the 24 hand joints, plus the raw model's noise.
//!
//! # Arm, lift and judgement
//! The forearm hangs from a mount (a mocap body) by three slide joints, each a position
//! motor with the Rapier lift's gains and force limit (`[motors] lift` of the sim config).
//! [`ArmMotion::Joints`] resets the world with the mount where the arm's forward kinematics
//! puts the flange (palm down only, raised in 5 mm steps while the hand overlaps the
//! object, as the Rapier backend does). [`ArmMotion::Lift`] drives the mount's vertical
//! motor along the smoothstep ramp, holds, and judges as Rapier does: held when the
//! object's lowest point is at least `lift.success_height` above the table and it touches
//! the hand. The lift does not stop early when the object has dropped (Rapier's
//! `stop_when_dropped` only saves time).
//!
//! # Physics failures
//! As in Rapier ([`crate::sim::PhysicsFailure`]): a non-finite state, MuJoCo's own
//! warning of a bad acceleration (after which it resets the state), the object faster than
//! `failure.max_speed`, farther than `failure.max_object_travel` from its start, or a
//! contact of the object deeper than `failure.max_penetration`. The step that sees one
//! ends the episode: every later command is refused with [`HwError::Disconnected`].

use super::mjcf::{self, MujocoSettings};
use super::raw_model::RawModel;
use super::simulated::SimulatedArm;
use super::simulated::{guarded_placement, top_down_placement, SimBackendConfig, GUARD_STEP_M};
use crate::hardware::{check_duration, ArmMotion, HandArm, HwError, RawSensors};
use crate::perception::camera::{camera_cloud_at, CameraConfig};
use crate::perception::pointcloud::CloudError;
use crate::robot::joints::{actuator_sums, couple_and_clamp, HAND_JOINTS};
use crate::robot::joints::{N_JOINTS, N_TACTILE};
use crate::robot::{Posture, Robot};
use crate::sim::placement::hand_root_pose;
use crate::sim::world::finger_grip;
use crate::sim::{LiftOutcome, ObjectShape, ObjectSpec, SimConfig};
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rapier3d::parry::bounding_volume::BoundingVolume;

/// Ids into MuJoCo's arrays.
struct Ids {
    /// Per hand joint (paper order): its `qpos` and `qvel` addresses and its actuator.
    qpos: [usize; N_JOINTS],
    dof: [usize; N_JOINTS],
    act: [usize; N_JOINTS],
    /// The three lift joints' actuators.
    lift_act: [usize; 3],
    /// The object's free joint: `qpos` and `qvel` addresses, and its body.
    obj_qpos: usize,
    obj_dof: usize,
    /// Per geom: the finger (0..5, FF..TH) whose distal phalanx it belongs to.
    distal: Vec<Option<usize>>,
    /// Per geom: whether it is the hand's, whether it is the object's.
    hand: Vec<bool>,
    object: Vec<bool>,
}

/// The MuJoCo hand-arm (see the module docs).
pub struct MujocoHandArm {
    data: MjData<Box<MjModel>>,
    ids: Ids,
    /// MuJoCo's time step (s).
    dt: f64,
    robot: Robot,
    object: ObjectSpec,
    sim_cfg: SimConfig,
    cfg: SimBackendConfig,
    raw: RawModel,
    targets: [f64; N_JOINTS],
    /// The mount's pose at the last placement.
    mount: Isometry3<f64>,
    lift_target: f64,
    clock_base: f64,
    extra_force: [f64; N_TACTILE],
    lift: Option<LiftOutcome>,
    failure: Option<String>,
    /// The deepest object contact since the hand was last placed (m) and the geom the
    /// object touched there.
    deepest: Option<(f64, usize)>,
    object_start: Vector3<f64>,
    kept_object: Option<Isometry3<f64>>,
    guard_raise: f64,
    stops: Vec<f64>,
}

fn cmd_err(field: &str, detail: String) -> HwError {
    HwError::InvalidCommand {
        field: field.into(),
        detail,
    }
}

impl MujocoHandArm {
    /// The hand (`robot`'s) with `object` at rest on the table at `cfg.object_xy`,
    /// `cfg.object_yaw`, the hand open, its grasp point `cfg.home_clearance` above the
    /// object's top; MuJoCo with `settings`.
    pub fn new(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        cfg: SimBackendConfig,
        settings: &MujocoSettings,
    ) -> Result<MujocoHandArm, HwError> {
        cfg.validate()?;
        let raw = RawModel::new(cfg.raw.clone())?;
        sim_cfg
            .validate()
            .map_err(|e| cmd_err("sim config", e.to_string()))?;
        let xml = mjcf::scene_xml(
            robot,
            &Isometry3::identity(),
            Some(&object),
            &sim_cfg,
            settings,
        )
        .map_err(|e| cmd_err("mujoco scene", e.to_string()))?;
        let model = MjModel::from_xml_string(&xml)
            .map_err(|e| cmd_err("mujoco scene", format!("MuJoCo refused the scene: {e}")))?;
        let ids = ids(robot, &model)?;
        let data = MjData::new(Box::new(model));
        let top = 2.0 * object.rest_height();
        let mut arm = MujocoHandArm {
            data,
            ids,
            dt: settings.timestep,
            robot: robot.clone(),
            object,
            sim_cfg,
            raw,
            targets: Posture::Open.angles(),
            mount: Isometry3::identity(),
            lift_target: 0.0,
            clock_base: cfg.raw.clock_start_s,
            extra_force: [0.0; N_TACTILE],
            lift: None,
            failure: None,
            deepest: None,
            object_start: Vector3::zeros(),
            kept_object: None,
            guard_raise: 0.0,
            stops: Vec::new(),
            cfg,
        };
        let [x, y] = arm.cfg.object_xy;
        let start = Posture::Open.angles();
        arm.place(
            &start,
            &Point3::new(x, y, top + arm.cfg.home_clearance),
            0.0,
        )?;
        Ok(arm)
    }

    /// The simulated object.
    pub fn object(&self) -> &ObjectSpec {
        &self.object
    }

    /// The backend configuration.
    pub fn config(&self) -> &SimBackendConfig {
        &self.cfg
    }

    /// How far the last placement was raised to clear the object (m).
    pub fn guard_raise(&self) -> f64 {
        self.guard_raise
    }

    /// Backend times at which [`HandArm::stop`] was called.
    pub fn stop_times(&self) -> &[f64] {
        &self.stops
    }

    /// The physics failure that ended the episode, if any.
    pub fn failure(&self) -> Option<&str> {
        self.failure.as_deref()
    }

    /// The object's body pose in the world.
    pub fn object_pose(&self) -> Isometry3<f64> {
        let q = self.data.qpos();
        let a = self.ids.obj_qpos;
        Isometry3::from_parts(
            Translation3::new(q[a], q[a + 1], q[a + 2]),
            UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[a + 3],
                q[a + 4],
                q[a + 5],
                q[a + 6],
            )),
        )
    }

    /// The object's world bounding box (lowest and highest corners, m): the union of its
    /// convex parts' boxes at its pose (as [`crate::sim::HandSim::object_aabb`]).
    pub fn object_aabb(&self) -> (Point3<f64>, Point3<f64>) {
        let pose = pose_f32(&self.object_pose());
        let builder = self.object.shape.collider();
        let aabb = match (&self.object.shape, builder.shape.as_compound()) {
            (ObjectShape::Library { .. }, Some(compound)) => compound
                .shapes()
                .iter()
                .map(|(part_pose, part)| part.compute_aabb(&(pose * builder.position * *part_pose)))
                .reduce(|a, b| a.merged(&b)),
            _ => None,
        }
        .unwrap_or_else(|| builder.shape.compute_aabb(&(pose * builder.position)));
        let p = |v: rapier3d::math::Vector| Point3::new(v.x as f64, v.y as f64, v.z as f64);
        (p(aabb.mins), p(aabb.maxs))
    }

    /// The object's contacts now: each one's index, its signed distance (m, negative when
    /// penetrating) and the geom the object touches there.
    fn object_contacts(&self) -> impl Iterator<Item = (usize, f64, usize)> + '_ {
        self.data.contact().iter().enumerate().filter_map(|(i, c)| {
            let (g1, g2) = (
                usize::try_from(c.geom[0]).ok()?,
                usize::try_from(c.geom[1]).ok()?,
            );
            let other = if self.ids.object[g1] {
                g2
            } else if self.ids.object[g2] {
                g1
            } else {
                return None;
            };
            Some((i, c.dist, other))
        })
    }

    /// Per finger, the normal force (N) of the object on its distal phalanx; and the total
    /// normal force between the object and the hand.
    pub fn contact_forces(&self) -> ([f64; N_TACTILE], f64) {
        let mut tip = [0.0; N_TACTILE];
        let mut hand = 0.0;
        for (i, _, hand_geom) in self.object_contacts() {
            if !self.ids.hand[hand_geom] {
                continue;
            }
            let f = self.data.contact_force(i)[0].max(0.0);
            hand += f;
            if let Some(k) = self.ids.distal[hand_geom] {
                tip[k] += f;
            }
        }
        (tip, hand)
    }

    fn joint_state(&self) -> ([f64; N_JOINTS], [f64; N_JOINTS]) {
        let (q, v) = (self.data.qpos(), self.data.qvel());
        (
            std::array::from_fn(|n| q[self.ids.qpos[n]]),
            std::array::from_fn(|n| v[self.ids.dof[n]]),
        )
    }

    /// One reading of the raw signals with `extra` newtons added to the fingertip forces.
    fn reading(&mut self) -> RawSensors {
        let (q, _) = self.joint_state();
        let (tip, _) = self.contact_forces();
        let tip: [f64; N_TACTILE] = std::array::from_fn(|k| tip[k] + self.extra_force[k]);
        let effort = actuator_sums(&self.joint_efforts());
        let t = self.now();
        self.raw.reading(t, &q, &tip, &effort)
    }

    /// Targets as Rapier's motors take them ([`couple_and_clamp`]).
    fn clamp_targets(&self, t: &[f64; N_JOINTS]) -> [f64; N_JOINTS] {
        couple_and_clamp(t, &self.robot.hand_limits())
    }

    fn apply_controls(&mut self) {
        let ctrl_lift = self.mount.rotation.inverse() * Vector3::new(0.0, 0.0, self.lift_target);
        let (act, lift) = (self.ids.act, self.ids.lift_act);
        let targets = self.targets;
        let ctrl = self.data.ctrl_mut();
        for n in 0..N_JOINTS {
            ctrl[act[n]] = targets[n];
        }
        for k in 0..3 {
            ctrl[lift[k]] = ctrl_lift[k];
        }
    }

    /// Resets the world with the hand in posture `start` (clamped), its grasp point at
    /// `grasp_point` and yaw `hand_yaw`, the object at rest (or where it was kept), raising
    /// the hand in [`GUARD_STEP_M`] steps while it overlaps the object.
    fn place(
        &mut self,
        start: &[f64; N_JOINTS],
        grasp_point: &Point3<f64>,
        hand_yaw: f64,
    ) -> Result<(), HwError> {
        let start = self.clamp_targets(start);
        self.clock_base += self.data.time();
        let mut gp = *grasp_point;
        let raised = guarded_placement(|raise| {
            if raise {
                gp.z += GUARD_STEP_M;
            }
            let root = hand_root_pose(&self.robot, &gp, hand_yaw, &start)
                .map_err(|e| cmd_err("arm joints", e.to_string()))?;
            self.reset_world(&root, &start);
            Ok(self.hand_overlaps_object())
        })?;
        self.guard_raise = raised;
        self.lift = None;
        Ok(())
    }

    fn reset_world(&mut self, root: &Isometry3<f64>, start: &[f64; N_JOINTS]) {
        self.data.reset();
        self.failure = None;
        self.deepest = None;
        self.mount = *root;
        let t = root.translation.vector;
        let r = root.rotation.quaternion();
        self.data.mocap_pos_mut()[0] = [t.x, t.y, t.z];
        self.data.mocap_quat_mut()[0] = [r.w, r.i, r.j, r.k];
        let obj = self.kept_object.unwrap_or_else(|| {
            Isometry3::from_parts(
                Translation3::new(
                    self.cfg.object_xy[0],
                    self.cfg.object_xy[1],
                    self.object.rest_height(),
                ),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.cfg.object_yaw),
            )
        });
        self.object_start = obj.translation.vector;
        let (ids_q, a) = (self.ids.qpos, self.ids.obj_qpos);
        let oq = obj.rotation.quaternion();
        let ot = obj.translation.vector;
        let q = self.data.qpos_mut();
        for n in 0..N_JOINTS {
            q[ids_q[n]] = start[n];
        }
        q[a..a + 7].copy_from_slice(&[ot.x, ot.y, ot.z, oq.w, oq.i, oq.j, oq.k]);
        self.targets = *start;
        self.lift_target = 0.0;
        self.apply_controls();
        self.data.forward();
    }

    fn hand_overlaps_object(&self) -> bool {
        self.object_contacts()
            .any(|(_, dist, other)| dist < 0.0 && self.ids.hand[other])
    }

    /// One physics step and the failure checks; false once the physics has failed.
    fn step(&mut self) -> bool {
        if self.failure.is_some() {
            return false;
        }
        self.data.step();
        let deepest = self.deepest_now();
        if let Some((d, g)) = deepest {
            if self.deepest.is_none_or(|(best, _)| d > best) {
                self.deepest = Some((d, g));
            }
        }
        self.failure = self.check_failure(deepest.map_or(0.0, |(d, _)| d));
        self.failure.is_none()
    }

    /// The deepest penetration of the object now (m) and the geom it touches there; `None`
    /// without a penetrating contact.
    fn deepest_now(&self) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for (_, dist, other) in self.object_contacts() {
            if dist < 0.0 && best.is_none_or(|(d, _)| -dist > d) {
                best = Some((-dist, other));
            }
        }
        best
    }

    /// The physics failure of the state now, if any; `deepest` is the deepest object
    /// contact now (m, [`Self::deepest_now`]).
    fn check_failure(&self, deepest: f64) -> Option<String> {
        let bad_acc = self.data.warning()[MjtWarning::mjWARN_BADQACC as usize].number;
        if bad_acc > 0 {
            return Some(format!(
                "MuJoCo reported a bad acceleration (warning mjWARN_BADQACC) at {:.3} s",
                self.data.time()
            ));
        }
        if self
            .data
            .qpos()
            .iter()
            .chain(self.data.qvel())
            .any(|v| !v.is_finite())
        {
            return Some("the state is not finite".into());
        }
        let f = &self.sim_cfg.failure;
        let v = self.data.qvel();
        let d = self.ids.obj_dof;
        let speed = Vector3::new(v[d], v[d + 1], v[d + 2]).norm();
        if speed > f.max_speed {
            return Some(format!("the object moves at {speed:.2} m/s"));
        }
        let travel = (self.object_pose().translation.vector - self.object_start).norm();
        if travel > f.max_object_travel {
            return Some(format!("the object travelled {travel:.3} m"));
        }
        if deepest > f.max_penetration {
            return Some(format!(
                "an object contact is {:.1} mm deep",
                deepest * 1000.0
            ));
        }
        None
    }

    fn physics_err(&self) -> HwError {
        HwError::Disconnected(format!(
            "the simulated physics (MuJoCo) failed: {}",
            self.failure.as_deref().unwrap_or("unknown")
        ))
    }

    /// The 24 joints' actuator forces (N m): the clamped PD law.
    fn joint_efforts(&self) -> [f64; N_JOINTS] {
        let force = self.data.actuator_force();
        std::array::from_fn(|n| force[self.ids.act[n]])
    }

    /// Raises the mount by `lift.height` along the smoothstep ramp, holds, and judges as
    /// [`crate::sim::HandSim::lift_and_judge`] does (without its early stop).
    fn lift_and_judge(&mut self) -> Result<LiftOutcome, HwError> {
        let l = self.sim_cfg.lift;
        let ramp = (l.ramp_time / self.dt).round().max(1.0) as usize;
        let hold = (l.hold_time / self.dt).round() as usize;
        let start = self.object_pose().rotation;
        let (mut grip_sum, mut grip_steps) = (0.0, 0usize);
        for k in 0..ramp + hold {
            let s = ((k + 1) as f64 / ramp as f64).min(1.0);
            self.lift_target = l.height * s * s * (3.0 - 2.0 * s);
            self.apply_controls();
            if !self.step() {
                return Err(self.physics_err());
            }
            grip_sum += finger_grip(&self.joint_efforts());
            grip_steps += 1;
        }
        let lowest = self.object_aabb().0.z;
        let in_contact = self.contact_forces().1 > 0.0;
        Ok(LiftOutcome {
            success: lowest >= l.success_height && in_contact,
            object_lowest_z: lowest,
            in_contact,
            object_turn: start.angle_to(&self.object_pose().rotation),
            grip_effort: grip_sum / grip_steps.max(1) as f64,
            failure: None,
        })
    }
}

fn pose_f32(p: &Isometry3<f64>) -> rapier3d::math::Pose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    rapier3d::math::Pose::from_parts(
        rapier3d::math::Vector::new(t.x as f32, t.y as f32, t.z as f32),
        rapier3d::math::Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32)
            .normalize(),
    )
}

/// Looks up every id the backend needs by name.
fn ids(robot: &Robot, m: &MjModel) -> Result<Ids, HwError> {
    let missing = |what: String| cmd_err("mujoco scene", format!("no {what} in the scene"));
    let joint = |name: &str| {
        m.name_to_id(MjtObjBase::mjOBJ_JOINT, name)
            .ok_or_else(|| missing(format!("joint {name}")))
    };
    let actuator = |name: &str| {
        m.name_to_id(MjtObjBase::mjOBJ_ACTUATOR, name)
            .ok_or_else(|| missing(format!("actuator {name}")))
    };
    let (qadr, dadr) = (m.jnt_qposadr(), m.jnt_dofadr());
    let mut qpos = [0; N_JOINTS];
    let mut dof = [0; N_JOINTS];
    let mut act = [0; N_JOINTS];
    for n in 0..N_JOINTS {
        let name = &robot.joints[robot.hand.joints[n]].name;
        let j = joint(name)?;
        qpos[n] = qadr[j] as usize;
        dof[n] = dadr[j] as usize;
        act[n] = actuator(&mjcf::actuator_name(name))?;
        debug_assert!(crate::robot::joints::canonical_name(name) == HAND_JOINTS[n]);
    }
    let mut lift_act = [0; 3];
    for (a, name) in lift_act.iter_mut().zip(mjcf::LIFT_JOINTS) {
        *a = actuator(&mjcf::actuator_name(name))?;
    }
    let free = joint("object_free")?;
    let obj_body = m
        .name_to_id(MjtObjBase::mjOBJ_BODY, mjcf::OBJECT_BODY)
        .ok_or_else(|| missing("object body".into()))?;
    let body_of_link = |l: usize| m.name_to_id(MjtObjBase::mjOBJ_BODY, &robot.links[l].name);
    let distal_bodies: [Option<usize>; N_TACTILE] =
        std::array::from_fn(|f| body_of_link(robot.hand.distal[f]));
    let hand_bodies: Vec<usize> = robot
        .links
        .iter()
        .enumerate()
        .filter_map(|(l, _)| body_of_link(l))
        .collect();
    let ngeom = m.ngeom() as usize;
    let gbody = m.geom_bodyid();
    let mut distal = vec![None; ngeom];
    let mut hand = vec![false; ngeom];
    let mut object = vec![false; ngeom];
    for g in 0..ngeom {
        let b = gbody[g] as usize;
        hand[g] = hand_bodies.contains(&b);
        object[g] = b == obj_body;
        distal[g] = distal_bodies.iter().position(|d| *d == Some(b));
    }
    // The fingertips' order: FF, MF, RF, LF, TH (robot.hand.distal follows it).
    Ok(Ids {
        qpos,
        dof,
        act,
        lift_act,
        obj_qpos: qadr[free] as usize,
        obj_dof: dadr[free] as usize,
        distal,
        hand,
        object,
    })
}

impl SimulatedArm for MujocoHandArm {
    const NAME: &'static str = "mujoco";

    /// The backend with the engine settings in use ([`MujocoSettings::in_use`]:
    /// `configs/mujoco.toml` unless `--mujoco-settings` chose others).
    fn build(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        cfg: SimBackendConfig,
    ) -> Result<Self, HwError> {
        MujocoHandArm::new(robot, object, sim_cfg, cfg, &MujocoSettings::in_use())
    }

    /// The point cloud the simulated depth cameras see of the object where it lies now
    /// (the Rapier backend's cameras, on MuJoCo's object pose).
    fn camera_cloud(&self, cam: &CameraConfig, seed: u64) -> Result<Vec<Point3<f64>>, CloudError> {
        camera_cloud_at(&self.object, &pose_f32(&self.object_pose()), cam, seed)
    }

    /// One reading while fingertip `finger` (0..5) is pressed with `force_n` newtons (a
    /// known force added to its contact force in the raw model), as the Rapier backend.
    fn read_pressed(&mut self, finger: usize, force_n: f64) -> Result<RawSensors, HwError> {
        super::raw_model::check_press(finger, force_n)?;
        self.extra_force[finger] = force_n;
        let r = self.read();
        self.extra_force = [0.0; N_TACTILE];
        r
    }

    /// Prepares a second attempt after a failed one, as the Rapier backend does: opens the
    /// hand where it is and runs the physics (at least 0.25 s, at most 2 s) until the
    /// object is at rest clear of the hand and on the table; from then on, arm moves keep
    /// the object where it lies.
    fn settle_for_retry(&mut self) -> Result<(), HwError> {
        use crate::sim::settle::{ON_TABLE_M, REST_SPEED, REST_SPIN, SETTLE_MAX_S, SETTLE_MIN_S};
        let dt = self.dt;
        let (min, max) = (
            (SETTLE_MIN_S / dt).round() as usize,
            (SETTLE_MAX_S / dt).round() as usize,
        );
        self.targets = self.clamp_targets(&Posture::Open.angles());
        self.apply_controls();
        let mut settled = false;
        for k in 0..max {
            if !self.step() {
                return Err(self.physics_err());
            }
            if k + 1 >= min {
                let v = self.data.qvel();
                let d = self.ids.obj_dof;
                let lin = Vector3::new(v[d], v[d + 1], v[d + 2]).norm();
                let ang = Vector3::new(v[d + 3], v[d + 4], v[d + 5]).norm();
                if lin < REST_SPEED && ang < REST_SPIN && self.contact_forces().1 == 0.0 {
                    settled = true;
                    break;
                }
            }
        }
        if !settled {
            return Err(cmd_err(
                "retry",
                "the object did not come to rest clear of the hand within 2 s".into(),
            ));
        }
        if self.object_aabb().0.z.abs() > ON_TABLE_M {
            return Err(cmd_err("retry", "the object left the table".into()));
        }
        self.kept_object = Some(self.object_pose());
        Ok(())
    }

    fn physics_failure(&self) -> Option<String> {
        self.failure.clone()
    }

    fn lift_report(&self) -> Option<LiftOutcome> {
        self.lift.clone()
    }

    /// The depth and what the object touched: a hand link's name, or `table`.
    fn deepest_contact(&self) -> Option<(f64, String)> {
        let (d, g) = self.deepest?;
        let with = if self.ids.hand[g] {
            let m = self.data.model();
            let body = m.geom_bodyid()[g] as usize;
            m.id_to_name(MjtObjBase::mjOBJ_BODY, body)
                .unwrap_or("hand")
                .to_string()
        } else {
            "table".to_string()
        };
        Some((d, with))
    }
}

impl HandArm for MujocoHandArm {
    fn read(&mut self) -> Result<RawSensors, HwError> {
        Ok(self.reading())
    }

    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), HwError> {
        if let Some(k) = targets.iter().position(|v| !v.is_finite()) {
            return Err(cmd_err(
                &format!("targets[{k}] ({})", HAND_JOINTS[k]),
                format!("{} is not finite", targets[k]),
            ));
        }
        if self.failure.is_some() {
            return Err(self.physics_err());
        }
        self.targets = self.clamp_targets(targets);
        self.apply_controls();
        Ok(())
    }

    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError> {
        motion.validate()?;
        match *motion {
            ArmMotion::Joints(q) => {
                let start = self.targets;
                let (gp, yaw) = top_down_placement(&self.robot, &self.cfg.arm_base, &start, &q)?;
                self.place(&start, &gp, yaw)
            }
            ArmMotion::Lift { height_m, .. } => {
                let h = self.sim_cfg.lift.height;
                if (height_m - h).abs() > 1e-6 {
                    return Err(cmd_err(
                        "lift height_m",
                        format!(
                            "the simulator lifts by its configured lift.height {h} m, not {height_m} m"
                        ),
                    ));
                }
                let out = self.lift_and_judge()?;
                self.lift = Some(out);
                Ok(())
            }
        }
    }

    fn stop(&mut self) -> Result<(), HwError> {
        self.stops.push(self.now());
        let (q, _) = self.joint_state();
        self.targets = self.clamp_targets(&q);
        self.apply_controls();
        Ok(())
    }

    fn now(&self) -> f64 {
        self.clock_base + self.data.time()
    }

    fn wait(&mut self, seconds: f64) -> Result<(), HwError> {
        check_duration(seconds)?;
        let dt = self.dt;
        let end = self.data.time() + seconds;
        while self.data.time() + 0.5 * dt <= end {
            if !self.step() {
                return Err(self.physics_err());
            }
        }
        Ok(())
    }

    fn lift_outcome(&self) -> Option<bool> {
        self.lift.as_ref().map(|l| l.success)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Side;

    fn arm(object: ObjectSpec) -> MujocoHandArm {
        let robot = Robot::builtin(Side::Left);
        MujocoHandArm::new(
            &robot,
            object,
            SimConfig::default(),
            SimBackendConfig::default(),
            &MujocoSettings::builtin(),
        )
        .unwrap()
    }

    #[test]
    fn the_box_rests_on_the_table_and_the_clock_is_simulated_time() {
        let mut a = arm(ObjectSpec::default_box());
        assert_eq!(a.now(), 0.0);
        a.wait(1.0).unwrap();
        assert!((a.now() - 1.0).abs() < 1e-9, "{}", a.now());
        let p = a.object_pose();
        // 5 x 5 x 8 cm box: centre 4 cm up, within 1 mm of where it was put.
        assert!((p.translation.z - 0.04).abs() < 1e-3, "{p}");
        assert!(
            p.translation.x.abs() < 1e-3 && p.translation.y.abs() < 1e-3,
            "{p}"
        );
        assert!(a.failure().is_none());
        // No fingertip touches it: the raw tactile readings sit at their offsets.
        let r = a.read().unwrap();
        let off = crate::run::sim_backend::RawModelConfig::default().tactile_offset;
        for (k, (v, o)) in r.tactile_raw.iter().zip(off).enumerate() {
            assert!((v - o).abs() < 1.8, "{k}: {v}");
        }
    }

    #[test]
    fn a_finger_tracks_its_target_and_coupled_joints_share_j0() {
        let mut a = arm(ObjectSpec::default_box());
        let mut t = a.targets;
        let ffj3 = crate::sim::hand_index("FFJ3");
        let (ffj2, ffj1) = (
            crate::sim::hand_index("FFJ2"),
            crate::sim::hand_index("FFJ1"),
        );
        t[ffj3] = 0.95;
        t[ffj2] = 0.8;
        t[ffj1] = 0.0;
        a.command_hand(&t).unwrap();
        a.wait(0.5).unwrap();
        let (q, _) = a.joint_state();
        assert!((q[ffj3] - 0.95).abs() < 0.05, "FFJ3 {}", q[ffj3]);
        // J0 = 0.8 split as 0.4 + 0.4.
        assert!(
            (q[ffj2] - 0.4).abs() < 0.05 && (q[ffj1] - 0.4).abs() < 0.05,
            "{} {}",
            q[ffj2],
            q[ffj1]
        );
    }

    #[test]
    fn the_lift_raises_the_hand_and_judges_by_height_and_contact() {
        use crate::robot::grasp_map::{root_pose_for, TwoFingerGrasp};
        let mut a = arm(ObjectSpec::default_box());
        let robot = Robot::builtin(Side::Left);
        let q_hand = a.targets;
        // Grasp point 3 cm below the box's top, thumb-to-little-finger along x.
        let g = TwoFingerGrasp::top_down(Point3::new(0.0, 0.0, 0.05), 0.0);
        let root = root_pose_for(&robot, &q_hand, &g).unwrap();
        let base = a.config().arm_base.pose();
        let q =
            crate::robot::ur10e::ik(&(base.inverse() * root), &crate::robot::ur10e::HOME).unwrap();
        a.move_arm(&ArmMotion::Joints(q)).unwrap();
        let closed = crate::sim::script::power_grasp();
        let start = a.targets;
        for i in 1..=10 {
            let s = i as f64 / 10.0;
            let t: [f64; 24] = std::array::from_fn(|k| start[k] + s * (closed[k] - start[k]));
            a.command_hand(&t).unwrap();
            a.wait(0.2).unwrap();
        }
        let (tip, hand) = a.contact_forces();
        assert!(hand > 0.5, "hand force {hand}, tips {tip:?}");
        let forearm = |a: &MujocoHandArm| {
            let m = a.data.model();
            let id = m
                .name_to_id(MjtObjBase::mjOBJ_BODY, &robot.links[robot.root].name)
                .unwrap();
            a.data.xpos()[id][2]
        };
        let z0 = forearm(&a);
        a.move_arm(&ArmMotion::Lift {
            height_m: 0.15,
            duration_s: 1.1,
        })
        .unwrap();
        // The mount's motor raised the hand by the lift height (within its sag).
        assert!(
            (forearm(&a) - z0 - 0.15).abs() < 5e-3,
            "{}",
            forearm(&a) - z0
        );
        // The verdict is the lowest point's height and the contact with the hand.
        let l = a.lift.clone().unwrap();
        let (lo, _) = a.object_aabb();
        assert_eq!(l.object_lowest_z, lo.z);
        assert_eq!(l.in_contact, a.contact_forces().1 > 0.0);
        assert_eq!(l.success, lo.z >= 0.10 && l.in_contact);
        assert_eq!(a.lift_outcome(), Some(l.success));
    }

    /// The library object `name` rests 1 s on the table: it neither sinks nor jumps (1 mm)
    /// nor tips, and the physics holds.
    fn rests_in_place(name: &str) {
        use crate::objects::sets::{build, resolve_specs};
        use crate::objects::BuildContext;
        let dir = tempfile::tempdir().unwrap();
        let spec = resolve_specs(name).unwrap().remove(0);
        let o = build(&spec, &BuildContext::with_cache_dir(dir.path())).unwrap();
        let mut a = arm(ObjectSpec::from_object(&o).unwrap());
        let (lo0, hi0) = a.object_aabb();
        assert!(lo0.z.abs() < 1e-6, "{name}: {lo0}");
        a.wait(1.0).unwrap();
        let (lo, hi) = a.object_aabb();
        assert!(
            (lo.z - lo0.z).abs() < 1e-3 && (hi.z - hi0.z).abs() < 1e-3,
            "{name}: {lo} {hi}"
        );
        assert!(a.failure().is_none(), "{name}");
    }

    #[test]
    fn a_library_mesh_object_rests_where_rapier_puts_it() {
        // The mug: convex mesh parts, placed where Rapier puts them.
        rests_in_place("mug");
    }

    #[test]
    fn objects_with_cylinder_parts_build_and_rest() {
        // proc-1000-15 (validation): a convex part that is a cylinder, which parry stands
        // along y and MuJoCo along z.
        rests_in_place("proc-1000-15");
    }

    #[test]
    fn joint_limits_hold_within_the_safety_tolerance() {
        // The hand palm down and open: LFJ5 sits at its lower limit (0) under gravity.
        let mut a = arm(ObjectSpec::default_box());
        a.wait(1.0).unwrap();
        let (q, _) = a.joint_state();
        let limits = Robot::builtin(Side::Left).hand_limits();
        for (k, (lo, hi)) in limits.iter().enumerate() {
            assert!(
                q[k] > lo - 0.01 && q[k] < hi + 0.01,
                "{} at {} outside [{lo}, {hi}]",
                HAND_JOINTS[k],
                q[k]
            );
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_readings() {
        let run = || {
            let mut a = arm(ObjectSpec::default_box());
            let mut t = a.targets;
            t[crate::sim::hand_index("FFJ3")] = 1.2;
            a.command_hand(&t).unwrap();
            a.wait(0.4).unwrap();
            (a.read().unwrap(), a.object_pose())
        };
        let (r1, p1) = run();
        let (r2, p2) = run();
        assert_eq!(r1, r2);
        assert_eq!(p1, p2);
    }
}
