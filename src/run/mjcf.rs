//! The simulated scene in MuJoCo's MJCF: the Shadow hand on its mount, the table and one
//! object, as the Rapier simulator builds them ([`crate::sim::HandSim`]), with the engine
//! settings of `configs/mujoco.toml` ([`MujocoSettings`]). The MuJoCo backend (feature
//! `mujoco`) loads this text; `grasp robot mjcf` writes it for MuJoCo's own viewer.
//!
//! # What maps to what
//! - Every URDF link is a body, posed by its joint's origin; a revolute joint is a hinge
//!   about the URDF axis with the URDF limits; a fixed joint welds its child (a body
//!   without a joint). The root link (the forearm) is a mocap body: the mount that stands
//!   in for the UR10e flange, placed and lifted kinematically. Links keep their URDF mass,
//!   centre of mass and inertia; a moving link without an inertial gets 1 g (as in Rapier).
//!   Collision geometry: URDF boxes, cylinders, spheres and capsules as MuJoCo primitives
//!   (no meshes, as in Rapier).
//! - Each of the 24 hand joints has a position actuator with the simulator's PD gains
//!   (`[motors]` of the sim config: kp, and kd as the actuator's `kv`) and its force clamped
//!   to the URDF effort: the law `clamp(kp (target - q) - kd qdot, -effort, effort)` of
//!   [`crate::sim::sensors::pd_effort`]. J1 = J2 of FF, MF, RF and LF is an equality.
//! - The object is a free body with its mass, centre of mass and inertia; its collision
//!   geometry is its convex parts (MuJoCo meshes, of which MuJoCo collides the convex hull,
//!   which a convex part already is). Rapier's support feet (thin pieces inside the hull
//!   that work around parry's manifolds) are left out. The table top is at z = 0.
//! - Friction combines with the MIN rule, as in Rapier: the hand meets the object with the
//!   object's coefficient (its geoms have the higher `priority`; the hand's is 1.0) and the
//!   table with the table's (0.8); the object meets the table through explicit `<pair>`s
//!   with `min(object, table)`. The hand does not collide with itself.

use crate::robot::model::{Geometry, JointKind};
use crate::robot::Robot;
use crate::sim::{ObjectShape, ObjectSpec, SimConfig};
use nalgebra::{Isometry3, Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// The built-in engine settings (`configs/mujoco.toml`, embedded).
pub const DEFAULT_MUJOCO_TOML: &str = include_str!("../../configs/mujoco.toml");

/// Name of the object's body in the scene.
pub const OBJECT_BODY: &str = "object";
/// Name of the table's geom.
pub const TABLE_GEOM: &str = "table";
/// Name of the mocap body the forearm hangs from: the UR10e flange's stand-in.
pub const MOUNT_BODY: &str = "mount";
/// The slide joints that hang the forearm from its mount, along x, y, z of the mount frame:
/// each a position motor with the Rapier lift's gains (the lift moves the mount frame's
/// image of world z).
pub const LIFT_JOINTS: [&str; 3] = ["lift_x", "lift_y", "lift_z"];
/// Mass given to a moving link without an inertial (kg), as in Rapier.
const MIN_LINK_MASS: f64 = 1e-3;

/// Error of the MJCF writer or of the settings file.
#[derive(Debug, thiserror::Error)]
pub enum MjcfError {
    /// The settings file could not be read or parsed.
    #[error(transparent)]
    Load(#[from] crate::util::config::ConfigError),
    /// A setting is out of range.
    #[error("mujoco settings: field '{field}': {detail}")]
    Setting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        detail: String,
    },
    /// The robot or object cannot be written as MJCF.
    #[error("mjcf: {0}")]
    Model(String),
}

/// The settings chosen for this process ([`MujocoSettings::use_for_process`]).
static IN_USE: std::sync::OnceLock<MujocoSettings> = std::sync::OnceLock::new();

/// MuJoCo's engine settings (see `configs/mujoco.toml` for each value's reason).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MujocoSettings {
    /// Physics step (s).
    pub timestep: f64,
    /// `Euler`, `RK4`, `implicit` or `implicitfast`.
    pub integrator: String,
    /// `pyramidal` or `elliptic`.
    pub cone: String,
    /// `PGS`, `CG` or `Newton`.
    pub solver: String,
    /// Solver iterations.
    pub iterations: u32,
    /// Line-search iterations.
    pub ls_iterations: u32,
    /// Solver tolerance.
    pub tolerance: f64,
    /// Frictional to normal impedance ratio.
    pub impratio: f64,
    /// Contact dimensionality (1, 3, 4 or 6).
    pub condim: u32,
    /// Contact solref (time constant s, damping ratio).
    pub solref: [f64; 2],
    /// Contact solimp (dmin, dmax, width m, midpoint, power).
    pub solimp: [f64; 5],
    /// Contact margin (m).
    pub margin: f64,
    /// The joint limits' solref (time constant s, damping ratio); MuJoCo's default is the
    /// contacts' (0.02, 1).
    #[serde(default = "default_solref")]
    pub joint_limit_solref: [f64; 2],
}

/// MuJoCo's default solref, (0.02 s, 1).
fn default_solref() -> [f64; 2] {
    [0.02, 1.0]
}

impl MujocoSettings {
    /// The built-in settings (`configs/mujoco.toml`).
    pub fn builtin() -> MujocoSettings {
        let s: MujocoSettings =
            crate::util::config::parse_toml(Path::new("configs/mujoco.toml"), DEFAULT_MUJOCO_TOML)
                .unwrap_or_else(|e| unreachable!("the embedded configs/mujoco.toml parses: {e}"));
        s
    }

    /// The settings the MuJoCo backend builds its scenes with: those given to
    /// [`MujocoSettings::use_for_process`], else the built-in ones.
    pub fn in_use() -> MujocoSettings {
        IN_USE
            .get()
            .cloned()
            .unwrap_or_else(MujocoSettings::builtin)
    }

    /// Makes `self` the settings of every MuJoCo scene this process builds (`grasp run
    /// --mujoco-settings`); an error once another set was chosen.
    pub fn use_for_process(self) -> Result<(), MjcfError> {
        self.validate()?;
        IN_USE.set(self).map_err(|_| MjcfError::Setting {
            field: "settings",
            detail: "the MuJoCo settings of this process were already chosen".into(),
        })
    }

    /// Loads and checks a settings file.
    pub fn load(path: &Path) -> Result<MujocoSettings, MjcfError> {
        let s: MujocoSettings = crate::util::config::load_toml(path)?;
        s.validate()?;
        Ok(s)
    }

    /// Checks every value's range; the error names the field.
    pub fn validate(&self) -> Result<(), MjcfError> {
        let bad = |field, detail: String| Err(MjcfError::Setting { field, detail });
        if !(self.timestep.is_finite() && (1e-5..=0.01).contains(&self.timestep)) {
            return bad(
                "timestep",
                format!("{} is not in [1e-5, 0.01] s", self.timestep),
            );
        }
        let one_of = |field, v: &str, allowed: &[&str]| {
            if allowed.contains(&v) {
                Ok(())
            } else {
                bad(field, format!("`{v}` is not one of {}", allowed.join(", ")))
            }
        };
        one_of(
            "integrator",
            &self.integrator,
            &["Euler", "RK4", "implicit", "implicitfast"],
        )?;
        one_of("cone", &self.cone, &["pyramidal", "elliptic"])?;
        one_of("solver", &self.solver, &["PGS", "CG", "Newton"])?;
        if !(1..=10_000).contains(&self.iterations) {
            return bad(
                "iterations",
                format!("{} is not in 1..=10000", self.iterations),
            );
        }
        if !(1..=10_000).contains(&self.ls_iterations) {
            return bad(
                "ls_iterations",
                format!("{} is not in 1..=10000", self.ls_iterations),
            );
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad("tolerance", format!("{} must be >= 0", self.tolerance));
        }
        if !(self.impratio.is_finite() && self.impratio >= 1.0) {
            return bad("impratio", format!("{} must be >= 1", self.impratio));
        }
        if ![1, 3, 4, 6].contains(&self.condim) {
            return bad("condim", format!("{} is not 1, 3, 4 or 6", self.condim));
        }
        if !(self.solref[0].is_finite() && self.solref[0] >= 2.0 * self.timestep) {
            return bad(
                "solref",
                format!(
                    "time constant {} must be at least two time steps ({} s)",
                    self.solref[0],
                    2.0 * self.timestep
                ),
            );
        }
        if !(self.solref[1].is_finite() && self.solref[1] > 0.0) {
            return bad(
                "solref",
                format!("damping ratio {} must be > 0", self.solref[1]),
            );
        }
        let [d0, d1, w, mid, p] = self.solimp;
        let ok = [d0, d1, w, mid, p].iter().all(|v| v.is_finite())
            && (0.0..1.0).contains(&d0)
            && (0.0..1.0).contains(&d1)
            && w >= 0.0
            && (0.0..=1.0).contains(&mid)
            && p >= 1.0;
        if !ok {
            return bad(
                "solimp",
                format!(
                    "{:?}: dmin, dmax in [0, 1), width >= 0, midpoint in [0, 1], power >= 1",
                    self.solimp
                ),
            );
        }
        if !(self.margin.is_finite() && (0.0..=0.05).contains(&self.margin)) {
            return bad("margin", format!("{} is not in [0, 0.05] m", self.margin));
        }
        Ok(())
    }
}

/// Numbers as MJCF writes them: enough digits to round-trip an f64.
fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:e}")
    }
}

fn nums(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ")
}

/// `pos="x y z" quat="w x y z"` of a pose.
fn pose_attrs(p: &Isometry3<f64>) -> String {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    format!(
        "pos=\"{}\" quat=\"{}\"",
        nums(&[t.x, t.y, t.z]),
        nums(&[q.w, q.i, q.j, q.k])
    )
}

/// `<inertial>` of a mass with inertia matrix `i` about the centre of mass, given in the
/// frame `frame` (which also places the centre of mass); MJCF takes the full matrix in the
/// body's axes (it allows no orientation beside it), so it is turned into them.
fn inertial(frame: &Isometry3<f64>, mass: f64, i: &Matrix3<f64>) -> String {
    let r = frame.rotation.to_rotation_matrix();
    let ib = r.matrix() * i * r.matrix().transpose();
    let t = frame.translation.vector;
    format!(
        "<inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{}\"/>",
        nums(&[t.x, t.y, t.z]),
        num(mass),
        nums(&[
            ib[(0, 0)],
            ib[(1, 1)],
            ib[(2, 2)],
            ib[(0, 1)],
            ib[(0, 2)],
            ib[(1, 2)]
        ])
    )
}

/// A hand geom's type and size attributes (MuJoCo primitives are along z, as URDF's).
fn hand_geom(link: &str, g: &Geometry) -> Result<String, MjcfError> {
    Ok(match g {
        Geometry::Cuboid { half } => format!("type=\"box\" size=\"{}\"", nums(&[half.x, half.y, half.z])),
        Geometry::Cylinder { radius, length } => {
            format!("type=\"cylinder\" size=\"{}\"", nums(&[*radius, length / 2.0]))
        }
        Geometry::Capsule { radius, length } => {
            format!("type=\"capsule\" size=\"{}\"", nums(&[*radius, length / 2.0]))
        }
        Geometry::Sphere { radius } => format!("type=\"sphere\" size=\"{}\"", num(*radius)),
        Geometry::Mesh { path, .. } => {
            return Err(MjcfError::Model(format!(
                "link '{link}': mesh collision '{}' is not supported (primitives only, as in the Rapier simulator)",
                path.display()
            )))
        }
    })
}

/// The name of a hand geom: its link's name and its index among the link's collisions.
pub fn hand_geom_name(link: &str, k: usize) -> String {
    format!("{link}_c{k}")
}

/// The name of the object's geom `k`.
pub fn object_geom_name(k: usize) -> String {
    format!("object_g{k}")
}

/// The name of joint `joint`'s position actuator.
pub fn actuator_name(joint: &str) -> String {
    format!("act_{joint}")
}

/// Writes the scene: the hand (`robot`) on its mount at `mount` (the pose of the root
/// link), the table and, when given, `object` resting at the origin (the backend moves
/// both). `sim` gives the gains, frictions and gravity, `s` the engine settings.
pub fn scene_xml(
    robot: &Robot,
    mount: &Isometry3<f64>,
    object: Option<&ObjectSpec>,
    sim: &SimConfig,
    s: &MujocoSettings,
) -> Result<String, MjcfError> {
    s.validate()?;
    let mut assets = String::new();
    let mut x = String::new();
    let _ = writeln!(x, "<mujoco model=\"grasp_{}\">", robot.name);
    let _ = writeln!(
        x,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\" autolimits=\"true\"/>"
    );
    let _ = writeln!(
        x,
        "  <option timestep=\"{}\" integrator=\"{}\" cone=\"{}\" solver=\"{}\" iterations=\"{}\" ls_iterations=\"{}\" tolerance=\"{}\" impratio=\"{}\" gravity=\"0 0 {}\"/>",
        num(s.timestep),
        s.integrator,
        s.cone,
        s.solver,
        s.iterations,
        s.ls_iterations,
        num(s.tolerance),
        num(s.impratio),
        num(sim.gravity)
    );
    let contact = format!(
        "condim=\"{}\" solref=\"{}\" solimp=\"{}\" margin=\"{}\"",
        s.condim,
        nums(&s.solref),
        nums(&s.solimp),
        num(s.margin)
    );
    let _ = writeln!(
        x,
        "  <default><geom {contact}/><joint solreflimit=\"{}\"/></default>",
        nums(&s.joint_limit_solref)
    );
    let mut world = String::new();
    // The table: its top at z = 0, as in Rapier.
    let _ = writeln!(
        world,
        "    <geom name=\"{TABLE_GEOM}\" type=\"box\" pos=\"0 0 -0.05\" size=\"1 1 0.05\" contype=\"0\" conaffinity=\"1\" priority=\"1\" friction=\"{} 0.005 0.0001\"/>",
        num(sim.friction.table)
    );
    hand_bodies(robot, mount, sim, &mut world)?;
    let mut pairs = String::new();
    if let Some(o) = object {
        object_body(o, sim, &contact, &mut world, &mut assets, &mut pairs)?;
    }
    if !assets.is_empty() {
        let _ = writeln!(x, "  <asset>\n{assets}  </asset>");
    }
    let _ = writeln!(x, "  <worldbody>\n{world}  </worldbody>");
    if !pairs.is_empty() {
        let _ = writeln!(x, "  <contact>\n{pairs}  </contact>");
    }
    // J1 = J2 of the coupled fingers.
    let mut eq = String::new();
    for f in crate::robot::joints::COUPLED_FINGERS {
        let name = |j: &str| {
            robot
                .joints
                .iter()
                .find(|jj| crate::robot::joints::canonical_name(&jj.name) == format!("{f}J{j}"))
                .map(|jj| jj.name.clone())
                .ok_or_else(|| MjcfError::Model(format!("the robot has no joint {f}J{j}")))
        };
        let _ = writeln!(
            eq,
            "    <joint joint1=\"{}\" joint2=\"{}\" polycoef=\"0 1 0 0 0\"/>",
            name("1")?,
            name("2")?
        );
    }
    let _ = writeln!(x, "  <equality>\n{eq}  </equality>");
    let mut act = String::new();
    for &ji in &robot.hand.joints {
        let j = &robot.joints[ji];
        let g = sim.motors.for_joint(&j.name);
        let _ = writeln!(
            act,
            "    <position name=\"{}\" joint=\"{}\" kp=\"{}\" kv=\"{}\" forcerange=\"{}\"/>",
            actuator_name(&j.name),
            j.name,
            num(g.kp),
            num(g.kd),
            nums(&[-j.effort, j.effort])
        );
    }
    let m = &sim.motors;
    for name in LIFT_JOINTS {
        let _ = writeln!(
            act,
            "    <position name=\"{}\" joint=\"{name}\" kp=\"{}\" kv=\"{}\" forcerange=\"{}\"/>",
            actuator_name(name),
            num(m.lift.kp),
            num(m.lift.kd),
            nums(&[-m.lift_max_force, m.lift_max_force])
        );
    }
    let _ = writeln!(x, "  <actuator>\n{act}  </actuator>");
    x.push_str("</mujoco>\n");
    Ok(x)
}

/// The hand's bodies, from the root link (a mocap body) down.
fn hand_bodies(
    robot: &Robot,
    mount: &Isometry3<f64>,
    sim: &SimConfig,
    out: &mut String,
) -> Result<(), MjcfError> {
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (k, j) in robot.joints.iter().enumerate() {
        if j.kind == JointKind::Prismatic {
            return Err(MjcfError::Model(format!(
                "joint '{}': prismatic hand joints are not supported",
                j.name
            )));
        }
        children[j.parent].push(k);
    }
    let root = &robot.links[robot.root];
    let _ = writeln!(
        out,
        "    <body name=\"{MOUNT_BODY}\" mocap=\"true\" {}>",
        pose_attrs(mount)
    );
    let _ = writeln!(out, "      <body name=\"{}\">", root.name);
    for (name, axis) in LIFT_JOINTS.iter().zip(["1 0 0", "0 1 0", "0 0 1"]) {
        let _ = writeln!(
            out,
            "        <joint name=\"{name}\" type=\"slide\" axis=\"{axis}\"/>"
        );
    }
    link_contents(robot, robot.root, true, sim, out, 4)?;
    for &k in &children[robot.root] {
        joint_body(robot, k, &children, sim, out, 4)?;
    }
    out.push_str("      </body>\n    </body>\n");
    Ok(())
}

fn joint_body(
    robot: &Robot,
    k: usize,
    children: &[Vec<usize>],
    sim: &SimConfig,
    out: &mut String,
    depth: usize,
) -> Result<(), MjcfError> {
    let j = &robot.joints[k];
    let pad = "  ".repeat(depth + 1);
    let link = &robot.links[j.child];
    let _ = writeln!(
        out,
        "{pad}<body name=\"{}\" {}>",
        link.name,
        pose_attrs(&j.origin)
    );
    let moving = j.is_movable();
    if moving {
        let axis = j.axis.normalize();
        let range = if j.kind == JointKind::Revolute {
            format!(" range=\"{}\"", nums(&[j.lower, j.upper]))
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "{pad}  <joint name=\"{}\" type=\"hinge\" axis=\"{}\"{range}/>",
            j.name,
            nums(&[axis.x, axis.y, axis.z])
        );
    }
    link_contents(robot, j.child, moving, sim, out, depth + 1)?;
    for &c in &children[j.child] {
        joint_body(robot, c, children, sim, out, depth + 1)?;
    }
    let _ = writeln!(out, "{pad}</body>");
    Ok(())
}

/// A link's inertial and collision geoms.
fn link_contents(
    robot: &Robot,
    l: usize,
    moving: bool,
    sim: &SimConfig,
    out: &mut String,
    depth: usize,
) -> Result<(), MjcfError> {
    let pad = "  ".repeat(depth + 1);
    let link = &robot.links[l];
    match &link.inertial {
        Some(i) => {
            let _ = writeln!(out, "{pad}{}", inertial(&i.origin, i.mass, &i.inertia));
        }
        None if moving => {
            // A 1 cm sphere of 1 g, as Rapier gives a body without inertials.
            let r = 0.01;
            let iv = 0.4 * MIN_LINK_MASS * r * r;
            let _ = writeln!(
                out,
                "{pad}{}",
                inertial(
                    &Isometry3::identity(),
                    MIN_LINK_MASS,
                    &Matrix3::from_diagonal_element(iv)
                )
            );
        }
        None => {}
    }
    for (k, c) in link.collisions.iter().enumerate() {
        let _ = writeln!(
            out,
            "{pad}<geom name=\"{}\" {} {} contype=\"1\" conaffinity=\"0\" friction=\"{} 0.005 0.0001\"/>",
            hand_geom_name(&link.name, k),
            hand_geom(&link.name, &c.geometry)?,
            pose_attrs(&c.origin),
            num(sim.friction.hand)
        );
    }
    Ok(())
}

/// The object's free body, its mesh assets and its pairs with the table.
fn object_body(
    o: &ObjectSpec,
    sim: &SimConfig,
    contact: &str,
    world: &mut String,
    assets: &mut String,
    pairs: &mut String,
) -> Result<(), MjcfError> {
    o.validate()
        .map_err(|e| MjcfError::Model(format!("object '{}': {e}", o.name)))?;
    let (frame, inertia) = object_inertia(o);
    let _ = writeln!(
        world,
        "    <body name=\"{OBJECT_BODY}\" pos=\"0 0 {}\">\n      <freejoint name=\"object_free\"/>\n      {}",
        num(o.rest_height()),
        inertial(&frame, o.mass, &inertia)
    );
    let geom_attrs = format!(
        "contype=\"0\" conaffinity=\"1\" priority=\"1\" friction=\"{} 0.005 0.0001\"",
        num(o.friction)
    );
    let mut names = Vec::new();
    match &o.shape {
        ObjectShape::Box { half } => {
            let _ = writeln!(
                world,
                "      <geom name=\"{}\" type=\"box\" size=\"{}\" {geom_attrs}/>",
                object_geom_name(0),
                nums(half)
            );
            names.push(object_geom_name(0));
        }
        ObjectShape::Cylinder {
            radius,
            half_height,
        } => {
            let _ = writeln!(
                world,
                "      <geom name=\"{}\" type=\"cylinder\" size=\"{}\" {geom_attrs}/>",
                object_geom_name(0),
                nums(&[*radius, *half_height])
            );
            names.push(object_geom_name(0));
        }
        ObjectShape::Library {
            parts,
            support_feet,
            ..
        } => {
            let all = parts.parts();
            let hulls = all.len().saturating_sub(*support_feet);
            for (k, (pose, shape)) in all[..hulls].iter().enumerate() {
                let name = object_geom_name(k);
                // parry's cylinders stand along y, MuJoCo's along z.
                let along_y = matches!(
                    shape.as_typed_shape(),
                    rapier3d::parry::shape::TypedShape::Cylinder(_)
                );
                let pose = if along_y {
                    *pose
                        * rapier3d::prelude::Pose::rotation(rapier3d::math::Vector::new(
                            -std::f32::consts::FRAC_PI_2,
                            0.0,
                            0.0,
                        ))
                } else {
                    *pose
                };
                let t = pose.translation;
                let r = pose.rotation;
                let attrs = format!(
                    "pos=\"{}\" quat=\"{}\"",
                    nums(&[t.x as f64, t.y as f64, t.z as f64]),
                    nums(&[r.w as f64, r.x as f64, r.y as f64, r.z as f64])
                );
                let kind = part_geom(o, k, shape, &name, assets)?;
                let _ = writeln!(
                    world,
                    "      <geom name=\"{name}\" {kind} {attrs} {geom_attrs}/>"
                );
                names.push(name);
            }
        }
    }
    world.push_str("    </body>\n");
    let mu = o.friction.min(sim.friction.table);
    for n in names {
        let _ = writeln!(
            pairs,
            "    <pair geom1=\"{n}\" geom2=\"{TABLE_GEOM}\" friction=\"{} {} 0.005 0.0001 0.0001\" {}/>",
            num(mu),
            num(mu),
            contact
        );
    }
    Ok(())
}

/// The object's centre of mass (as a frame in the body) and its inertia about it (kg m^2):
/// a uniform solid for the primitives, the library's values for library objects, at
/// [`ObjectSpec::mass`] (as [`ObjectSpec::mass_properties`] gives Rapier, in f64).
pub fn object_inertia(o: &ObjectSpec) -> (Isometry3<f64>, Matrix3<f64>) {
    let m = o.mass;
    match &o.shape {
        ObjectShape::Box { half: [x, y, z] } => (
            Isometry3::identity(),
            Matrix3::from_diagonal(&Vector3::new(
                m / 3.0 * (y * y + z * z),
                m / 3.0 * (x * x + z * z),
                m / 3.0 * (x * x + y * y),
            )),
        ),
        ObjectShape::Cylinder {
            radius,
            half_height,
        } => {
            let side = m * (3.0 * radius * radius + 4.0 * half_height * half_height) / 12.0;
            (
                Isometry3::identity(),
                Matrix3::from_diagonal(&Vector3::new(side, side, 0.5 * m * radius * radius)),
            )
        }
        ObjectShape::Library {
            com, unit_inertia, ..
        } => (
            Isometry3::translation(com[0], com[1], com[2]),
            Matrix3::from_fn(|r, c| unit_inertia[r][c] * m),
        ),
    }
}

/// One convex part's geom type (and mesh asset).
fn part_geom(
    o: &ObjectSpec,
    k: usize,
    shape: &rapier3d::prelude::SharedShape,
    name: &str,
    assets: &mut String,
) -> Result<String, MjcfError> {
    use rapier3d::parry::shape::TypedShape;
    Ok(match shape.as_typed_shape() {
        TypedShape::ConvexPolyhedron(p) => {
            let v: Vec<f64> = p
                .points()
                .iter()
                .flat_map(|q| [q.x as f64, q.y as f64, q.z as f64])
                .collect();
            let _ = writeln!(assets, "    <mesh name=\"{name}\" vertex=\"{}\"/>", nums(&v));
            format!("type=\"mesh\" mesh=\"{name}\"")
        }
        TypedShape::Cuboid(c) => {
            let h = c.half_extents;
            format!("type=\"box\" size=\"{}\"", nums(&[h.x as f64, h.y as f64, h.z as f64]))
        }
        TypedShape::Ball(b) => format!("type=\"sphere\" size=\"{}\"", num(b.radius as f64)),
        TypedShape::Cylinder(c) => format!(
            "type=\"cylinder\" size=\"{}\"",
            nums(&[c.radius as f64, c.half_height as f64])
        ),
        TypedShape::Capsule(c) => {
            let (a, b) = (c.segment.a, c.segment.b);
            format!(
                "type=\"capsule\" size=\"{}\" fromto=\"{}\"",
                num(c.radius as f64),
                nums(&[a.x, a.y, a.z, b.x, b.y, b.z].map(|v| v as f64))
            )
        }
        _ => {
            return Err(MjcfError::Model(format!(
                "object '{}': part {k} has a shape MuJoCo is not given (convex polyhedra, boxes, balls, capsules and cylinders are)",
                o.name
            )))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Side;

    #[test]
    fn builtin_settings_are_valid_and_errors_name_the_field() {
        let s = MujocoSettings::builtin();
        s.validate().unwrap();
        assert_eq!(s.timestep, 0.002);
        assert_eq!(s.integrator, "implicitfast");
        let mut b = s.clone();
        b.integrator = "verlet".into();
        assert!(b.validate().unwrap_err().to_string().contains("integrator"));
        let mut b = s.clone();
        b.solref[0] = 0.003;
        assert!(b.validate().unwrap_err().to_string().contains("solref"));
        let mut b = s;
        b.timestep = f64::NAN;
        assert!(b.validate().unwrap_err().to_string().contains("timestep"));
    }

    #[test]
    fn scene_holds_every_hand_joint_actuator_coupling_and_the_object() {
        let robot = Robot::builtin(Side::Left);
        let xml = scene_xml(
            &robot,
            &Isometry3::identity(),
            Some(&ObjectSpec::default_box()),
            &SimConfig::default(),
            &MujocoSettings::builtin(),
        )
        .unwrap();
        for &ji in &robot.hand.joints {
            let n = &robot.joints[ji].name;
            assert!(
                xml.contains(&format!("<joint name=\"{n}\" type=\"hinge\"")),
                "{n}"
            );
            assert!(xml.contains(&format!("name=\"{}\" joint=\"{n}\"", actuator_name(n))));
        }
        assert_eq!(xml.matches("polycoef=\"0 1 0 0 0\"").count(), 4);
        // kp 2 and kd 0.02 of the fingers, effort 2 N m.
        assert!(xml.contains("kp=\"2e0\" kv=\"2e-2\" forcerange=\"-2e0 2e0\""));
        assert!(xml.contains("<body name=\"object\" pos=\"0 0 4e-2\">"));
        // One pair of the box with the table, at min(0.8, 0.8).
        assert_eq!(xml.matches("<pair ").count(), 1);
        assert!(xml.contains("mocap=\"true\""));
    }
}
