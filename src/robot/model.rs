//! The [`Robot`] model: links, joints and collision geometry loaded from a URDF through
//! `urdf-rs`, validated, with the Shadow hand's joint table located by name.
//!
//! The loader reads the project's own URDFs and third-party Shadow hand URDFs as published
//! by its maker (flattened xacro output with `rh_`/`lh_` prefixes, `package://` mesh URIs,
//! transmissions and gazebo tags, fixed tip joints). Meshes that cannot be found fall back
//! to a primitive approximation with a warning, or fail when loading is strict.

use super::joints::{
    canonical_name, Side, FINGERTIP_LINKS, FINGER_JOINTS, HAND_JOINTS, KEY_CLOSING_JOINTS,
};
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Error while loading or validating a robot description.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The file could not be read.
    #[error("cannot read URDF {path}: {source}")]
    Io {
        /// The URDF file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The XML is malformed or does not follow the URDF schema.
    #[error("malformed URDF {path}: {message}")]
    Malformed {
        /// The URDF file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// An element is inconsistent (names the element).
    #[error("invalid URDF {path}: {element}: {message}")]
    Invalid {
        /// The URDF file.
        path: PathBuf,
        /// The offending element, e.g. `joint 'rh_FFJ3'`.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// A joint or link the hand model needs is missing.
    #[error("URDF {path} is not a Shadow hand: missing {what}")]
    MissingHandPart {
        /// The URDF file.
        path: PathBuf,
        /// What is missing, e.g. `joint FFJ3`.
        what: String,
    },
    /// A mesh file was not found while loading strictly.
    #[error("URDF {path}: link '{link}': mesh '{uri}' not found (searched {searched})")]
    MeshNotFound {
        /// The URDF file.
        path: PathBuf,
        /// The link whose geometry refers to the mesh.
        link: String,
        /// The URI as written.
        uri: String,
        /// Where the loader looked.
        searched: String,
    },
}

/// Kind of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Rotation about the axis, with limits.
    Revolute,
    /// Rotation about the axis, without limits.
    Continuous,
    /// Translation along the axis.
    Prismatic,
    /// No motion.
    Fixed,
}

/// Collision geometry of a link, in the link frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// A box with half extents.
    Cuboid {
        /// Half extents (m).
        half: Vector3<f64>,
    },
    /// A cylinder along z.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Full length (m).
        length: f64,
    },
    /// A capsule along z (urdf-rs extension).
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part (m).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A mesh file that was found on disk.
    Mesh {
        /// Resolved path.
        path: PathBuf,
        /// Per-axis scale.
        scale: Vector3<f64>,
    },
}

/// One collision element of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    /// Pose of the geometry in the link frame.
    pub origin: Isometry3<f64>,
    /// The geometry.
    pub geometry: Geometry,
}

/// Mass properties of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Inertial {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass and inertia frame, in the link frame.
    pub origin: Isometry3<f64>,
    /// Inertia tensor (kg m^2) about the centre of mass, in the inertia frame.
    pub inertia: Matrix3<f64>,
}

/// A link of the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Name as written in the URDF (with prefix).
    pub name: String,
    /// Mass properties, if given (links without inertial are massless frames).
    pub inertial: Option<Inertial>,
    /// Collision elements.
    pub collisions: Vec<Collision>,
}

/// A joint of the robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Name as written in the URDF (with prefix).
    pub name: String,
    /// Kind of motion.
    pub kind: JointKind,
    /// Parent link index.
    pub parent: usize,
    /// Child link index.
    pub child: usize,
    /// Pose of the joint frame in the parent link frame.
    pub origin: Isometry3<f64>,
    /// Unit axis in the joint frame.
    pub axis: Vector3<f64>,
    /// Lower position limit (rad or m); `-inf` when unlimited.
    pub lower: f64,
    /// Upper position limit; `+inf` when unlimited.
    pub upper: f64,
    /// Effort limit (N m or N).
    pub effort: f64,
    /// Velocity limit (rad/s or m/s).
    pub velocity: f64,
}

impl Joint {
    /// Whether the joint moves.
    pub fn is_movable(&self) -> bool {
        self.kind != JointKind::Fixed
    }

    /// The joint's motion for position `q`.
    pub fn motion(&self, q: f64) -> Isometry3<f64> {
        match self.kind {
            JointKind::Revolute | JointKind::Continuous => Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_scaled_axis(self.axis * q),
            ),
            JointKind::Prismatic => {
                Isometry3::translation(self.axis.x * q, self.axis.y * q, self.axis.z * q)
            }
            JointKind::Fixed => Isometry3::identity(),
        }
    }
}

/// Where the Shadow hand's parts are inside a [`Robot`].
#[derive(Debug, Clone, PartialEq)]
pub struct HandTable {
    /// Which hand (from the joint prefix; a robot without prefix is taken as right).
    pub side: Side,
    /// Joint indices of [`HAND_JOINTS`] (paper order: WRJ2, WRJ1, FF J4..J1, ...).
    pub joints: [usize; 24],
    /// Link indices of the five fingertip frames, in [`FINGERTIP_LINKS`] order.
    pub tips: [usize; 5],
    /// Link index of the distal phalanx carrying each fingertip sensor.
    pub distal: [usize; 5],
    /// Link index of the palm.
    pub palm: usize,
    /// Link index of the forearm (the hand's root).
    pub forearm: usize,
}

impl HandTable {
    /// Joint indices of the 22 finger joints ([`FINGER_JOINTS`] order).
    pub fn finger_joints(&self) -> &[usize] {
        &self.joints[2..]
    }

    /// Indices into the 22-joint finger vector of the key closing joints of eq. 5.
    pub fn key_closing(&self) -> [usize; 5] {
        KEY_CLOSING_JOINTS.map(|k| {
            FINGER_JOINTS
                .iter()
                .position(|j| *j == k)
                .unwrap_or_default()
        })
    }
}

/// A validated robot: a kinematic tree of links and joints.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// The robot's name.
    pub name: String,
    /// Where it was loaded from (for messages).
    pub source: PathBuf,
    /// Links; index 0 is not necessarily the root.
    pub links: Vec<Link>,
    /// Joints in topological order (every joint's parent link is reached before it).
    pub joints: Vec<Joint>,
    /// Index of the root link.
    pub root: usize,
    /// The Shadow hand inside this robot.
    pub hand: HandTable,
}

/// How to treat mesh files that cannot be found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MeshPolicy {
    /// Replace the mesh by a primitive approximation and log a warning.
    #[default]
    Fallback,
    /// Fail with [`RobotError::MeshNotFound`].
    Strict,
}

const LEFT_URDF: &str = include_str!("../../assets/robots/shadow_hand_left.urdf");
const RIGHT_URDF: &str = include_str!("../../assets/robots/shadow_hand_right.urdf");
const UR10E_URDF: &str = include_str!("../../assets/robots/ur10e.urdf");

impl Robot {
    /// The project's shipped hand model (`assets/robots/shadow_hand_{side}.urdf`).
    pub fn builtin(side: Side) -> Robot {
        let (text, file) = match side {
            Side::Left => (LEFT_URDF, "assets/robots/shadow_hand_left.urdf"),
            Side::Right => (RIGHT_URDF, "assets/robots/shadow_hand_right.urdf"),
        };
        // The shipped files are generated and tested; failing here is a build defect.
        Self::from_str(text, Path::new(file), MeshPolicy::Strict)
            .unwrap_or_else(|e| panic!("shipped robot model is invalid: {e}"))
    }

    /// The shipped UR10e with the left hand on its flange (`assets/robots/ur10e.urdf`).
    pub fn builtin_arm() -> Robot {
        Self::from_str(
            UR10E_URDF,
            Path::new("assets/robots/ur10e.urdf"),
            MeshPolicy::Strict,
        )
        .unwrap_or_else(|e| panic!("shipped robot model is invalid: {e}"))
    }

    /// Loads and validates a URDF file.
    pub fn load(path: &Path, policy: MeshPolicy) -> Result<Robot, RobotError> {
        let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
            .map_err(|source| RobotError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_str(&text, path, policy)
    }

    /// Parses and validates URDF text; `path` names the source in errors and is the base
    /// for relative mesh paths.
    pub fn from_str(text: &str, path: &Path, policy: MeshPolicy) -> Result<Robot, RobotError> {
        let malformed = |message: String| RobotError::Malformed {
            path: path.to_path_buf(),
            message,
        };
        if !text.contains("<robot") {
            return Err(malformed("no <robot> element".into()));
        }
        // urdf-rs may panic on some malformed inputs deep in its XML layer; contain it.
        let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text))
            .map_err(|_| malformed("the XML parser failed on this input".into()))?
            .map_err(|e| malformed(e.to_string()))?;
        build(parsed, path, policy)
    }

    /// Index of the link named `name` (exact URDF name).
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Index of the link whose unprefixed, lower-case name is `base` (e.g. `ffdistal`).
    pub fn hand_link(&self, base: &str) -> Option<usize> {
        self.links
            .iter()
            .position(|l| canonical_name(&l.name).eq_ignore_ascii_case(base))
    }

    /// Index of the joint named `name` (exact URDF name).
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Lower and upper limits of the 24 hand joints, paper order.
    pub fn hand_limits(&self) -> [(f64, f64); 24] {
        self.hand
            .joints
            .map(|j| (self.joints[j].lower, self.joints[j].upper))
    }

    /// Lower and upper limits of the 22 finger joints, synergy order.
    pub fn finger_limits(&self) -> [(f64, f64); 22] {
        let h = self.hand_limits();
        std::array::from_fn(|k| h[k + 2])
    }

    /// Effort limits of the 24 hand joints, paper order.
    pub fn hand_efforts(&self) -> [f64; 24] {
        self.hand.joints.map(|j| self.joints[j].effort)
    }

    /// A zero vector of joint positions, one entry per joint (fixed joints ignored).
    pub fn zero_q(&self) -> Vec<f64> {
        vec![0.0; self.joints.len()]
    }

    /// Writes the 24 hand joint angles (paper order) into a full joint vector.
    pub fn set_hand_q(&self, q: &mut [f64], hand: &[f64; 24]) {
        for (k, &j) in self.hand.joints.iter().enumerate() {
            q[j] = hand[k];
        }
    }
}

fn pose_of(p: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = p.xyz.0;
    let [r, pi, yaw] = p.rpy.0;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(r, pi, yaw),
    )
}

fn finite_pose(p: &urdf_rs::Pose) -> bool {
    p.xyz.0.iter().chain(p.rpy.0.iter()).all(|v| v.is_finite())
}

/// Resolves a mesh URI: `package://pkg/rest` is searched under the URDF's folder and its
/// ancestors (as `pkg/rest` and `rest`) and under `ROS_PACKAGE_PATH`; `file://` and plain
/// paths are taken relative to the URDF's folder.
fn resolve_mesh(uri: &str, urdf: &Path) -> (Option<PathBuf>, Vec<PathBuf>) {
    let base = urdf.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut candidates = Vec::new();
    if let Some(rest) = uri.strip_prefix("package://") {
        let tail = rest.split_once('/').map_or(rest, |(_, t)| t);
        let mut dir = Some(base.as_path());
        while let Some(d) = dir {
            candidates.push(d.join(rest));
            candidates.push(d.join(tail));
            dir = d.parent();
        }
        if let Ok(rpp) = std::env::var("ROS_PACKAGE_PATH") {
            for p in rpp.split(':').filter(|p| !p.is_empty()) {
                candidates.push(Path::new(p).join(rest));
            }
        }
    } else {
        let plain = uri.strip_prefix("file://").unwrap_or(uri);
        let p = Path::new(plain);
        candidates.push(if p.is_absolute() {
            p.to_path_buf()
        } else {
            base.join(p)
        });
    }
    let found = candidates.iter().find(|c| c.is_file()).cloned();
    (found, candidates)
}

/// A primitive stand-in for a link whose mesh is missing: a 7 mm cylinder from the link
/// origin to its first child joint, or a 1 cm sphere for a leaf link.
fn fallback_geometry(child_offset: Option<Vector3<f64>>) -> Collision {
    match child_offset {
        Some(v) if v.norm() > 1e-4 => {
            let len = v.norm();
            let rot = UnitQuaternion::rotation_between(&Vector3::z(), &v).unwrap_or_else(|| {
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
            });
            Collision {
                origin: Isometry3::from_parts(Translation3::from(v / 2.0), rot),
                geometry: Geometry::Cylinder {
                    radius: 0.007,
                    length: len,
                },
            }
        }
        _ => Collision {
            origin: Isometry3::identity(),
            geometry: Geometry::Sphere { radius: 0.01 },
        },
    }
}

/// An invalid element of the URDF at `path`.
fn invalid(path: &Path, element: String, message: String) -> RobotError {
    RobotError::Invalid {
        path: path.to_path_buf(),
        element,
        message,
    }
}

fn build(u: urdf_rs::Robot, path: &Path, policy: MeshPolicy) -> Result<Robot, RobotError> {
    let index = link_index(&u, path)?;
    let (joints, parent_of) = parse_joints(&u, &index, path)?;
    let (root, joints) = tree_order(&u, joints, &parent_of, path)?;
    let links = parse_links(&u, &joints, path, policy)?;
    let hand = hand_table(&links, &joints, path)?;
    Ok(Robot {
        name: u.name,
        source: path.to_path_buf(),
        links,
        joints,
        root,
        hand,
    })
}

/// Each link's index by name (every name once, at least one link).
fn link_index<'a>(
    u: &'a urdf_rs::Robot,
    path: &Path,
) -> Result<HashMap<&'a str, usize>, RobotError> {
    let invalid = |element: String, message: String| invalid(path, element, message);
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (k, l) in u.links.iter().enumerate() {
        if index.insert(l.name.as_str(), k).is_some() {
            return Err(invalid(
                format!("link '{}'", l.name),
                "defined more than once".into(),
            ));
        }
    }
    if u.links.is_empty() {
        return Err(invalid("robot".into(), "has no links".into()));
    }
    Ok(index)
}

/// The joints in file order, checked, and each link's parent joint.
type ParsedJoints = (Vec<Joint>, Vec<Option<usize>>);

/// Reads and checks every joint: known links, one parent per link, finite poses, axes
/// and limits.
fn parse_joints(
    u: &urdf_rs::Robot,
    index: &HashMap<&str, usize>,
    path: &Path,
) -> Result<ParsedJoints, RobotError> {
    let invalid = |element: String, message: String| invalid(path, element, message);
    let mut joints = Vec::with_capacity(u.joints.len());
    let mut seen_joint: HashMap<&str, ()> = HashMap::new();
    let mut parent_of: Vec<Option<usize>> = vec![None; u.links.len()];
    for j in &u.joints {
        let el = format!("joint '{}'", j.name);
        if seen_joint.insert(j.name.as_str(), ()).is_some() {
            return Err(invalid(el, "defined more than once".into()));
        }
        let parent = *index.get(j.parent.link.as_str()).ok_or_else(|| {
            invalid(
                el.clone(),
                format!("unknown parent link '{}'", j.parent.link),
            )
        })?;
        let child = *index
            .get(j.child.link.as_str())
            .ok_or_else(|| invalid(el.clone(), format!("unknown child link '{}'", j.child.link)))?;
        if parent_of[child].is_some() {
            return Err(invalid(
                el,
                format!("link '{}' has two parent joints", j.child.link),
            ));
        }
        if !finite_pose(&j.origin) {
            return Err(invalid(el, "origin has a non-finite number".into()));
        }
        let kind = match j.joint_type {
            urdf_rs::JointType::Revolute => JointKind::Revolute,
            urdf_rs::JointType::Continuous => JointKind::Continuous,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            urdf_rs::JointType::Fixed => JointKind::Fixed,
            ref other => {
                return Err(invalid(el, format!("unsupported joint type {other:?}")));
            }
        };
        let a = Vector3::from(j.axis.xyz.0);
        if kind != JointKind::Fixed && (!a.iter().all(|v| v.is_finite()) || a.norm() < 1e-9) {
            return Err(invalid(el, "axis is zero or not finite".into()));
        }
        let axis = if kind == JointKind::Fixed {
            Vector3::z()
        } else {
            a.normalize()
        };
        let (mut lower, mut upper) = (j.limit.lower, j.limit.upper);
        let lim = [lower, upper, j.limit.effort, j.limit.velocity];
        if lim.iter().any(|v| v.is_nan()) {
            return Err(invalid(el, "limit has a non-finite number".into()));
        }
        match kind {
            JointKind::Continuous => {
                lower = f64::NEG_INFINITY;
                upper = f64::INFINITY;
            }
            JointKind::Revolute | JointKind::Prismatic => {
                if !(lower.is_finite() && upper.is_finite()) {
                    return Err(invalid(el, "limit has a non-finite number".into()));
                }
                if lower > upper {
                    return Err(invalid(
                        el,
                        format!("lower limit {lower} is above upper limit {upper}"),
                    ));
                }
            }
            JointKind::Fixed => {}
        }
        if j.limit.effort < 0.0 || j.limit.velocity < 0.0 {
            return Err(invalid(el, "negative effort or velocity limit".into()));
        }
        parent_of[child] = Some(joints.len());
        joints.push(Joint {
            name: j.name.clone(),
            kind,
            parent,
            child,
            origin: pose_of(&j.origin),
            axis,
            lower,
            upper,
            effort: j.limit.effort,
            velocity: j.limit.velocity,
        });
    }
    Ok((joints, parent_of))
}

/// The tree's root link and the joints in breadth-first order from it (links never
/// reached are in a cycle).
fn tree_order(
    u: &urdf_rs::Robot,
    joints: Vec<Joint>,
    parent_of: &[Option<usize>],
    path: &Path,
) -> Result<(usize, Vec<Joint>), RobotError> {
    let invalid = |element: String, message: String| invalid(path, element, message);
    let roots: Vec<usize> = (0..u.links.len())
        .filter(|&k| parent_of[k].is_none())
        .collect();
    if roots.len() != 1 {
        let names: Vec<&str> = roots.iter().map(|&k| u.links[k].name.as_str()).collect();
        return Err(invalid(
            "robot".into(),
            format!(
                "the links must form one tree, found {} roots: {}",
                roots.len(),
                names.join(", ")
            ),
        ));
    }
    let root = roots[0];
    // Topological order: breadth-first from the root. Links never reached are in a cycle.
    let mut order = Vec::with_capacity(joints.len());
    let mut frontier = vec![root];
    while let Some(l) = frontier.pop() {
        for (k, j) in joints.iter().enumerate() {
            if j.parent == l {
                order.push(k);
                frontier.push(j.child);
            }
        }
    }
    if order.len() != joints.len() {
        return Err(invalid("robot".into(), "the joints contain a cycle".into()));
    }
    Ok((root, order.iter().map(|&k| joints[k].clone()).collect()))
}

/// A link's inertial: `None` for a massless link; finite, non-negative values otherwise.
fn inertial_of(l: &urdf_rs::Link, el: &str, path: &Path) -> Result<Option<Inertial>, RobotError> {
    let invalid = |element: &str, message: String| invalid(path, element.to_string(), message);
    let i = &l.inertial;
    let m = i.mass.value;
    let t = [
        i.inertia.ixx,
        i.inertia.ixy,
        i.inertia.ixz,
        i.inertia.iyy,
        i.inertia.iyz,
        i.inertia.izz,
    ];
    if !m.is_finite() || t.iter().any(|v| !v.is_finite()) || !finite_pose(&i.origin) {
        return Err(invalid(el, "inertial has a non-finite number".into()));
    }
    if m < 0.0 {
        return Err(invalid(el, format!("negative mass {m}")));
    }
    Ok((m > 0.0).then(|| Inertial {
        mass: m,
        origin: pose_of(&i.origin),
        inertia: Matrix3::new(t[0], t[1], t[2], t[1], t[3], t[4], t[2], t[4], t[5]),
    }))
}

/// Reads every link: its inertial and its collision geometry (a mesh not found is an
/// error with `MeshPolicy::Strict`, else a primitive stand-in).
fn parse_links(
    u: &urdf_rs::Robot,
    joints: &[Joint],
    path: &Path,
    policy: MeshPolicy,
) -> Result<Vec<Link>, RobotError> {
    let invalid = |element: String, message: String| invalid(path, element, message);
    let first_child_offset = |l: usize| {
        joints
            .iter()
            .find(|j| j.parent == l)
            .map(|j| j.origin.translation.vector)
    };
    let mut links = Vec::with_capacity(u.links.len());
    for (k, l) in u.links.iter().enumerate() {
        let el = format!("link '{}'", l.name);
        let inertial = inertial_of(l, &el, path)?;
        let mut collisions = Vec::new();
        for c in &l.collision {
            if !finite_pose(&c.origin) {
                return Err(invalid(
                    el,
                    "collision origin has a non-finite number".into(),
                ));
            }
            let positive = |v: f64, what: &str| {
                if v.is_finite() && v > 0.0 {
                    Ok(v)
                } else {
                    Err(invalid(
                        el.clone(),
                        format!("{what} must be positive, got {v}"),
                    ))
                }
            };
            let geometry = match &c.geometry {
                urdf_rs::Geometry::Box { size } => Geometry::Cuboid {
                    half: Vector3::new(
                        positive(size[0], "box size")?,
                        positive(size[1], "box size")?,
                        positive(size[2], "box size")?,
                    ) / 2.0,
                },
                urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
                    radius: positive(*radius, "cylinder radius")?,
                    length: positive(*length, "cylinder length")?,
                },
                urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
                    radius: positive(*radius, "capsule radius")?,
                    length: positive(*length, "capsule length")?,
                },
                urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere {
                    radius: positive(*radius, "sphere radius")?,
                },
                urdf_rs::Geometry::Mesh { filename, scale } => {
                    let scale = scale.map_or(Vector3::new(1.0, 1.0, 1.0), |s| Vector3::from(s.0));
                    if scale.iter().any(|v| !v.is_finite() || *v == 0.0) {
                        return Err(invalid(el, "mesh scale must be finite and non-zero".into()));
                    }
                    match resolve_mesh(filename, path) {
                        (Some(p), _) => Geometry::Mesh { path: p, scale },
                        (None, searched) => {
                            if policy == MeshPolicy::Strict {
                                return Err(RobotError::MeshNotFound {
                                    path: path.to_path_buf(),
                                    link: l.name.clone(),
                                    uri: filename.clone(),
                                    searched: searched
                                        .iter()
                                        .take(4)
                                        .map(|p| p.display().to_string())
                                        .collect::<Vec<_>>()
                                        .join(", "),
                                });
                            }
                            tracing::warn!(
                                "{}: link '{}': mesh '{}' not found, using a primitive approximation",
                                path.display(),
                                l.name,
                                filename
                            );
                            let fb = fallback_geometry(first_child_offset(k));
                            collisions.push(fb);
                            continue;
                        }
                    }
                }
            };
            collisions.push(Collision {
                origin: pose_of(&c.origin),
                geometry,
            });
        }
        links.push(Link {
            name: l.name.clone(),
            inertial,
            collisions,
        });
    }
    Ok(links)
}

fn hand_table(links: &[Link], joints: &[Joint], path: &Path) -> Result<HandTable, RobotError> {
    let missing = |what: String| RobotError::MissingHandPart {
        path: path.to_path_buf(),
        what,
    };
    let mut side: Option<Side> = None;
    let mut hj = [0usize; 24];
    for (k, name) in HAND_JOINTS.iter().enumerate() {
        let found = joints
            .iter()
            .position(|j| j.is_movable() && canonical_name(&j.name) == *name)
            .ok_or_else(|| missing(format!("joint {name}")))?;
        hj[k] = found;
        let lower = joints[found].name.to_ascii_lowercase();
        let s = if lower.starts_with("lh_") {
            Side::Left
        } else {
            Side::Right
        };
        if *side.get_or_insert(s) != s {
            return Err(RobotError::Invalid {
                path: path.to_path_buf(),
                element: format!("joint '{}'", joints[found].name),
                message: "mixes left- and right-hand prefixes".into(),
            });
        }
    }
    let link = |base: &str| {
        links
            .iter()
            .position(|l| canonical_name(&l.name).eq_ignore_ascii_case(base))
            .ok_or_else(|| missing(format!("link {base}")))
    };
    let tips = [
        link(FINGERTIP_LINKS[0])?,
        link(FINGERTIP_LINKS[1])?,
        link(FINGERTIP_LINKS[2])?,
        link(FINGERTIP_LINKS[3])?,
        link(FINGERTIP_LINKS[4])?,
    ];
    let distal = [
        link("ffdistal")?,
        link("mfdistal")?,
        link("rfdistal")?,
        link("lfdistal")?,
        link("thdistal")?,
    ];
    Ok(HandTable {
        side: side.unwrap_or(Side::Right),
        joints: hj,
        tips,
        distal,
        palm: link("palm")?,
        forearm: link("forearm")?,
    })
}
