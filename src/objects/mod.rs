//! The object library: primitives, meshes, procedural shapes and object sets.
//!
//! The paper trains on 61 objects (YCB, ShapeNet, EGAD and primitive shapes) and tests on
//! unseen ones. Those files cannot be shipped, so this module generates a comparable
//! library deterministically ([`procedural`] shapes from [`shape_kit`]'s constructions,
//! the [`builtin`] sets, [`build`] and the [`sets`] resolver) and reads any user's OBJ/STL
//! meshes ([`mesh`]) or TOML manifests ([`spec`]).
//!
//! # Object frame
//!
//! Every [`Object`] is expressed in its own frame: **z up, the origin at the bottom centre
//! of the bounding box** (x and y centred, `z = 0` on the lowest vertex). An object placed
//! with the identity pose therefore rests on a table whose surface is the plane `z = 0`.
//! The centre of mass [`Object::com`] is given in that frame.
//!
//! # Collision geometry
//!
//! The simulator gets convex pieces only ([`Object::collider_desc`],
//! [`Object::to_shared_shape`]):
//!
//! - primitives (box, cylinder, sphere, capsule) keep their exact shape ([`Primitive`],
//!   axis along z, centred at [`Object::primitive_center`]), plus one hull of their
//!   tessellation;
//! - convex meshes use one hull;
//! - generated objects built from convex parts (mugs, hammers, bananas...) use those parts;
//! - other non-convex meshes are decomposed with VHACD ([`decomp`]), cached on disk.
//!
//! Mass and inertia come from the visual mesh (or the exact primitive), not from the
//! hulls, whose union slightly overestimates the volume.
//!
//! Every hull keeps at most [`MAX_HULL_POINTS`] vertices ([`convex_hull_mesh`]): a dense
//! scan (a sphere of 180k triangles has a hull of 86k vertices) is thinned by vertex
//! clustering first, because the contact queries scan a hull's vertices and parry's
//! convex polyhedron failed (index out of bounds) on such hulls.

pub mod build;
pub mod builtin;
pub mod decomp;
pub mod mesh;
pub mod procedural;
pub mod random_shapes;
pub mod rest;
pub mod sets;
pub mod shape_kit;
pub mod spec;
pub mod stream;

pub use decomp::{CacheStatus, DecompParams};
pub use mesh::{Aabb, MassProps, TriMesh};
pub use sets::{load_objects, resolve_specs, BuildContext};
pub use spec::{ObjectKind, ObjectSpec, ShapeSpec};

use parry3d::math::{Pose, Vector};
use parry3d::shape::SharedShape;

/// Errors of the object library. Every variant names the file or object concerned.
#[derive(Debug, thiserror::Error)]
pub enum ObjectError {
    /// A file could not be read. (The I/O error is part of the message, not a separate
    /// `source`, so `{:#}` chains do not print it twice.)
    #[error("cannot read {path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        error: std::io::Error,
    },
    /// A file could not be written.
    #[error("{0}")]
    Write(crate::util::fsx::WriteError),
    /// A manifest could not be read or parsed.
    #[error("{0}")]
    Config(crate::util::config::ConfigError),
    /// The mesh file extension is neither `.obj` nor `.stl`.
    #[error("unsupported mesh format {path}: expected a .obj or .stl file")]
    UnsupportedFormat {
        /// The file.
        path: String,
    },
    /// The OBJ/STL parser rejected the file.
    #[error("cannot parse mesh {path}: {message}")]
    MeshParse {
        /// The file.
        path: String,
        /// What the parser reported.
        message: String,
    },
    /// The mesh has no triangles.
    #[error("mesh {path} is empty (no triangles)")]
    EmptyMesh {
        /// The file or object.
        path: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error(
        "mesh {path}: vertex {} (counted from 1) has a NaN or infinite coordinate",
        index + 1
    )]
    NonFiniteVertex {
        /// The file or object.
        path: String,
        /// 0-based vertex index.
        index: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "mesh {path}: triangle {} uses vertex {}, but there are only {vertex_count} vertices \
         (both counted from 1)",
        triangle + 1,
        index + 1
    )]
    IndexOutOfRange {
        /// The file or object.
        path: String,
        /// 0-based triangle index.
        triangle: usize,
        /// The offending vertex index.
        index: usize,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("mesh {path}: triangle {triangle} is degenerate (repeats a vertex)")]
    DegenerateTriangle {
        /// The file or object.
        path: String,
        /// 0-based triangle index.
        triangle: usize,
    },
    /// The mesh has holes (edges used by one triangle only).
    #[error("mesh {path} is not watertight: {boundary_edges} boundary edge(s), e.g. between vertices {a} and {b}")]
    NotWatertight {
        /// The file or object.
        path: String,
        /// Number of directed edges without a matching opposite edge.
        boundary_edges: usize,
        /// One end of an open edge (0-based).
        a: u32,
        /// The other end.
        b: u32,
    },
    /// An edge is shared by more than two triangles or its triangles disagree on the
    /// orientation.
    #[error("mesh {path} is non-manifold or inconsistently oriented: edge {a}-{b} is used by {count} triangles, not 2 with opposite directions")]
    NonManifold {
        /// The file or object.
        path: String,
        /// One end of the edge (0-based).
        a: u32,
        /// The other end.
        b: u32,
        /// How many triangles use it.
        count: u32,
    },
    /// The enclosed volume is (numerically) zero.
    #[error("mesh {path} is degenerate: enclosed volume {volume:e} m^3")]
    ZeroVolume {
        /// The file or object.
        path: String,
        /// The absolute volume found.
        volume: f64,
    },
    /// The bounding box is larger than 1 m.
    #[error(
        "mesh {path} is too large: {} m across (limit 1 m); is it in millimetres? set \
         `scale = 0.001`",
        crate::util::num::short(*extent_m)
    )]
    TooLarge {
        /// The file or object.
        path: String,
        /// Largest bounding-box extent in metres.
        extent_m: f64,
    },
    /// The bounding box is smaller than 5 mm.
    #[error(
        "mesh {path} is too small: {} m across (minimum 0.005 m); check `scale`",
        crate::util::num::short(*extent_m)
    )]
    TooSmall {
        /// The file or object.
        path: String,
        /// Largest bounding-box extent in metres.
        extent_m: f64,
    },
    /// A field of an object spec has an invalid value.
    #[error("object {object} in {source_name}: field `{field}`: {message}")]
    InvalidSpec {
        /// Manifest file or "built-in".
        source_name: String,
        /// The object name.
        object: String,
        /// The offending field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A comma-separated name list holds the name of a whole set.
    #[error(
        "`{name}` is an object set, not an object name: a comma-separated list holds \
         object names only (stream objects as proc-<seed>-<index>); pass --objects {name} \
         alone"
    )]
    SetInList {
        /// The set named.
        name: String,
    },
    /// The `--objects` argument names nothing known.
    #[error("unknown object or set `{name}`: {hint}")]
    Unknown {
        /// What was asked for.
        name: String,
        /// The known sets and close names.
        hint: String,
    },
    /// Two objects in one set share a name.
    #[error("duplicate object name `{name}` in {source_name}{detail}")]
    DuplicateName {
        /// The repeated name.
        name: String,
        /// Where the set came from.
        source_name: String,
        /// The colliding files (": a b.obj and a_b.obj both give it"), or empty.
        detail: String,
    },
    /// A set resolved to no objects (an empty folder or manifest).
    #[error("{source_name} contains no objects")]
    EmptySet {
        /// The folder or manifest.
        source_name: String,
    },
    /// Convex decomposition failed.
    #[error("convex decomposition of {name} failed: {message}")]
    Decomposition {
        /// The object.
        name: String,
        /// What went wrong.
        message: String,
    },
}

impl From<crate::util::fsx::WriteError> for ObjectError {
    fn from(e: crate::util::fsx::WriteError) -> Self {
        ObjectError::Write(e)
    }
}

impl From<crate::util::config::ConfigError> for ObjectError {
    fn from(e: crate::util::config::ConfigError) -> Self {
        ObjectError::Config(e)
    }
}

/// A convex piece of an object's collision geometry: the vertices of a convex polyhedron
/// in the object frame (metres).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ConvexHull {
    /// The hull's vertices (every point is a vertex of the hull).
    pub points: Vec<[f64; 3]>,
}

impl ConvexHull {
    /// The convex hull of `points`, keeping only its vertices; `None` when the points are
    /// fewer than four, not finite, or flat.
    pub fn from_points(points: &[[f64; 3]]) -> Option<ConvexHull> {
        let mesh = convex_hull_mesh(points)?;
        Some(ConvexHull {
            points: mesh.vertices,
        })
    }

    /// The hull as a closed, outward-oriented triangle mesh.
    pub fn mesh(&self) -> Option<TriMesh> {
        convex_hull_mesh(&self.points)
    }
}

/// Most vertices a hull keeps. The shipped objects' hulls have at most 770 vertices
/// (capsule_pill) and their meshes at most 2,562, so nothing shipped is thinned; a dense
/// user mesh is ([`thin_points`]).
pub const MAX_HULL_POINTS: usize = 1024;

/// Input points beyond which the hull is computed from a clustered subset (of at most
/// this many points), then capped to [`MAX_HULL_POINTS`].
const MAX_HULL_INPUT: usize = 4 * MAX_HULL_POINTS;

/// The convex hull of `points` as an outward-oriented closed mesh (parry3d's quickhull in
/// f32) with at most [`MAX_HULL_POINTS`] vertices; `None` for degenerate input. More
/// than 4 x [`MAX_HULL_POINTS`] input points are thinned first, and a hull with more vertices
/// than the cap is recomputed from its thinned vertices ([`thin_points`]).
pub fn convex_hull_mesh(points: &[[f64; 3]]) -> Option<TriMesh> {
    if points.len() < 4 || points.iter().any(|p| p.iter().any(|x| !x.is_finite())) {
        return None;
    }
    let mut m = if points.len() > MAX_HULL_INPUT {
        exact_hull(&thin_points(points, MAX_HULL_INPUT))?
    } else {
        exact_hull(points)?
    };
    if m.vertices.len() > MAX_HULL_POINTS {
        // The thinned points are at most the cap, so is their hull.
        m = exact_hull(&thin_points(&m.vertices, MAX_HULL_POINTS))?;
    }
    Some(m)
}

/// At most `max` of `points` (`max >= 8`), by vertex clustering: the bounding box is cut
/// into the finest grid of equal cubes that leaves at most `max` cubes occupied, and each
/// occupied cube keeps its point farthest from the box centre (the first on a tie), so the
/// hull of the result lies inside the hull of `points`, off by at most a cube's diagonal.
/// Deterministic, in the order of `points`.
pub fn thin_points(points: &[[f64; 3]], max: usize) -> Vec<[f64; 3]> {
    let Some(bb) = Aabb::of_points(points) else {
        return Vec::new();
    };
    if points.len() <= max {
        return points.to_vec();
    }
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (bb.min[k] + bb.max[k]));
    let extent = bb.max_extent().max(f64::MIN_POSITIVE);
    let cluster = |cells: u32| {
        let size = extent / cells as f64;
        let mut best: std::collections::HashMap<[i64; 3], (f64, usize)> =
            std::collections::HashMap::new();
        for (i, p) in points.iter().enumerate() {
            let key: [i64; 3] = std::array::from_fn(|k| ((p[k] - bb.min[k]) / size).floor() as i64);
            let d: f64 = (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum();
            let e = best.entry(key).or_insert((d, i));
            if d > e.0 {
                *e = (d, i);
            }
        }
        let mut keep: Vec<usize> = best.into_values().map(|(_, i)| i).collect();
        keep.sort_unstable();
        keep
    };
    // The finest grid (cubes per longest side) whose occupied cubes fit in `max`.
    let (mut lo, mut hi) = (1u32, 4096u32);
    let mut keep = cluster(lo);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        let k = cluster(mid);
        if k.len() <= max {
            lo = mid;
            keep = k;
        } else {
            hi = mid - 1;
        }
    }
    keep.into_iter().map(|i| points[i]).collect()
}

/// The hull of `points` without a vertex cap.
fn exact_hull(points: &[[f64; 3]]) -> Option<TriMesh> {
    if points.len() < 4 {
        return None;
    }
    let pts: Vec<Vector> = points
        .iter()
        .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
        .collect();
    let (v, t) = std::panic::catch_unwind(|| parry3d::transformation::try_convex_hull(&pts))
        .ok()?
        .ok()?;
    if v.len() < 4 || t.len() < 4 {
        return None;
    }
    let mut m = TriMesh::new(
        v.iter()
            .map(|p| [p.x as f64, p.y as f64, p.z as f64])
            .collect(),
        t,
    );
    m.orient_outward();
    let scale = m.aabb()?.max_extent();
    if m.signed_volume() <= 1e-9 * scale.powi(3) {
        return None;
    }
    Some(m)
}

/// An exact primitive shape, centred on [`Object::primitive_center`], its axis along z.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Primitive {
    /// A box with the given half extents (x, y, z).
    Box {
        /// Half extents in metres.
        half_extents: [f64; 3],
    },
    /// A cylinder along z.
    Cylinder {
        /// Radius in metres.
        radius: f64,
        /// Half of the height in metres.
        half_height: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius in metres.
        radius: f64,
    },
    /// A capsule along z: a segment of length `2 half_height` swept by a sphere.
    Capsule {
        /// Radius in metres.
        radius: f64,
        /// Half of the segment length (the total height is `2 (half_height + radius)`).
        half_height: f64,
    },
}

impl Primitive {
    /// Half of the total height along z (the primitive's centre lies this far above the
    /// table).
    pub fn half_height_total(&self) -> f64 {
        match *self {
            Primitive::Box { half_extents } => half_extents[2],
            Primitive::Cylinder { half_height, .. } => half_height,
            Primitive::Sphere { radius } => radius,
            Primitive::Capsule {
                radius,
                half_height,
            } => half_height + radius,
        }
    }

    /// The exact volume in m^3.
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Primitive::Box { half_extents: h } => 8.0 * h[0] * h[1] * h[2],
            Primitive::Cylinder {
                radius,
                half_height,
            } => PI * radius * radius * 2.0 * half_height,
            Primitive::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
            Primitive::Capsule {
                radius,
                half_height,
            } => PI * radius * radius * 2.0 * half_height + 4.0 / 3.0 * PI * radius.powi(3),
        }
    }

    /// The principal moments of inertia (about x, y, z through the centre) of the solid
    /// with total mass `mass_kg`, in kg m^2.
    pub fn principal_inertia(&self, mass_kg: f64) -> [f64; 3] {
        use std::f64::consts::PI;
        let m = mass_kg;
        match *self {
            Primitive::Box { half_extents: h } => {
                // m (b^2 + c^2) / 12 with full extents b = 2 h.
                let (x2, y2, z2) = (h[0] * h[0], h[1] * h[1], h[2] * h[2]);
                [
                    m * (y2 + z2) / 3.0,
                    m * (x2 + z2) / 3.0,
                    m * (x2 + y2) / 3.0,
                ]
            }
            Primitive::Cylinder {
                radius: r,
                half_height: hh,
            } => {
                let ixx = m * (3.0 * r * r + 4.0 * hh * hh) / 12.0;
                [ixx, ixx, m * r * r / 2.0]
            }
            Primitive::Sphere { radius: r } => {
                let i = 0.4 * m * r * r;
                [i, i, i]
            }
            Primitive::Capsule {
                radius: r,
                half_height: hh,
            } => {
                // Cylinder of mass mc plus two hemispheres (total ms), whose centres of mass
                // sit 3r/8 beyond the segment ends; a hemisphere's transverse moment about
                // its own centre of mass is 83/320 m r^2.
                let vc = PI * r * r * 2.0 * hh;
                let vs = 4.0 / 3.0 * PI * r.powi(3);
                let mc = m * vc / (vc + vs);
                let ms = m - mc;
                let izz = mc * r * r / 2.0 + ms * 0.4 * r * r;
                let d = hh + 3.0 * r / 8.0;
                let ixx =
                    mc * (4.0 * hh * hh / 12.0 + r * r / 4.0) + ms * (83.0 / 320.0 * r * r + d * d);
                [ixx, ixx, izz]
            }
        }
    }

    /// The parry3d shape, centred at the origin with its axis along z.
    pub fn to_shared_shape(&self) -> (Pose, SharedShape) {
        match *self {
            Primitive::Box { half_extents: h } => (
                Pose::IDENTITY,
                SharedShape::cuboid(h[0] as f32, h[1] as f32, h[2] as f32),
            ),
            Primitive::Cylinder {
                radius,
                half_height,
            } => (
                // parry's cylinder axis is y; turn it onto z (+90 degrees about x).
                Pose::rotation(Vector::new(std::f32::consts::FRAC_PI_2, 0.0, 0.0)),
                SharedShape::cylinder(half_height as f32, radius as f32),
            ),
            Primitive::Sphere { radius } => (Pose::IDENTITY, SharedShape::ball(radius as f32)),
            Primitive::Capsule {
                radius,
                half_height,
            } => (
                Pose::IDENTITY,
                SharedShape::capsule_z(half_height as f32, radius as f32),
            ),
        }
    }
}

/// A ready-to-simulate object, in the object frame described in the module docs.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Object {
    /// Unique, readable name (`bottle_tall`, `egad_c3_d2`, a file stem...).
    pub name: String,
    /// Category label.
    pub kind: ObjectKind,
    /// Total mass in kg.
    pub mass_kg: f64,
    /// Coulomb friction coefficient (0..=1).
    pub friction: f64,
    /// Volume of the solid in m^3.
    pub volume_m3: f64,
    /// Centre of mass in the object frame (metres).
    pub com: [f64; 3],
    /// Inertia tensor about the centre of mass, object-frame axes (kg m^2).
    pub inertia: [[f64; 3]; 3],
    /// Bounding box of the visual mesh in the object frame (`min.z == 0`).
    pub bbox: Aabb,
    /// Convex collision pieces in the object frame (at least one).
    pub hulls: Vec<ConvexHull>,
    /// The exact primitive, for primitive objects.
    pub primitive: Option<Primitive>,
    /// Where the hulls came from.
    pub hull_source: HullSource,
    /// The visual mesh in the object frame (one or more closed components).
    #[serde(skip)]
    pub mesh: TriMesh,
}

/// How an object's convex pieces were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HullSource {
    /// The exact primitive (plus its tessellated hull).
    Primitive,
    /// The mesh is convex: one hull.
    Convex,
    /// The generator built the object from convex parts.
    Parts,
    /// VHACD decomposition, with the cache status.
    Vhacd(CacheStatus),
}

/// What the simulator needs to build the object's rigid body and colliders, in the object
/// frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ColliderDesc {
    /// Convex hull point lists (use these when `primitive` is `None`).
    pub hulls: Vec<Vec<[f64; 3]>>,
    /// The exact primitive and its centre, when the object is one.
    pub primitive: Option<(Primitive, [f64; 3])>,
    /// Total mass in kg (set it on the body; do not derive it from the hulls' volume).
    pub mass_kg: f64,
    /// Centre of mass.
    pub com: [f64; 3],
    /// Inertia about the centre of mass (kg m^2).
    pub inertia: [[f64; 3]; 3],
    /// Friction coefficient.
    pub friction: f64,
}

impl Object {
    /// The centre of the primitive in the object frame: `(0, 0, half total height)`.
    pub fn primitive_center(&self) -> Option<[f64; 3]> {
        self.primitive.map(|p| [0.0, 0.0, p.half_height_total()])
    }

    /// The bounding-box extents (x, y, z) in metres.
    pub fn size(&self) -> [f64; 3] {
        self.bbox.extents()
    }

    /// Everything the simulator needs to build the collider (see [`ColliderDesc`]).
    pub fn collider_desc(&self) -> ColliderDesc {
        ColliderDesc {
            hulls: self.hulls.iter().map(|h| h.points.clone()).collect(),
            primitive: self.primitive.zip(self.primitive_center()),
            mass_kg: self.mass_kg,
            com: self.com,
            inertia: self.inertia,
            friction: self.friction,
        }
    }

    /// The collision pieces as parry3d shapes with their poses in the object frame: the
    /// exact primitive, or one convex polyhedron per hull.
    pub fn collider_parts(&self) -> Result<Vec<(Pose, SharedShape)>, ObjectError> {
        if let (Some(p), Some(c)) = (self.primitive, self.primitive_center()) {
            let (pose, shape) = p.to_shared_shape();
            let t = Pose::translation(c[0] as f32, c[1] as f32, c[2] as f32);
            return Ok(vec![(t * pose, shape)]);
        }
        let mut parts = Vec::with_capacity(self.hulls.len());
        for h in &self.hulls {
            let pts: Vec<Vector> = h
                .points
                .iter()
                .map(|p| Vector::new(p[0] as f32, p[1] as f32, p[2] as f32))
                .collect();
            if let Some(s) = SharedShape::convex_hull(&pts) {
                parts.push((Pose::IDENTITY, s));
            }
        }
        if parts.is_empty() {
            return Err(ObjectError::Decomposition {
                name: self.name.clone(),
                message: "no hull forms a valid convex polyhedron".into(),
            });
        }
        Ok(parts)
    }

    /// One parry3d shape for the whole object: a compound of [`Object::collider_parts`]
    /// (a compound even for a single piece, so the object frame is preserved).
    pub fn to_shared_shape(&self) -> Result<SharedShape, ObjectError> {
        Ok(SharedShape::compound(self.collider_parts()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn primitive_volumes_and_inertia() {
        let b = Primitive::Box {
            half_extents: [0.5, 1.0, 1.5],
        };
        assert_relative_eq!(b.volume(), 6.0);
        // 1 x 2 x 3 box, mass 12: Ixx = 12 (4 + 9) / 12 = 13.
        assert_relative_eq!(b.principal_inertia(12.0)[0], 13.0, epsilon = 1e-12);
        let s = Primitive::Sphere { radius: 2.0 };
        assert_relative_eq!(s.principal_inertia(5.0)[1], 0.4 * 5.0 * 4.0);
        // A capsule with a zero-length segment is a sphere.
        let c = Primitive::Capsule {
            radius: 2.0,
            half_height: 0.0,
        };
        assert_relative_eq!(c.volume(), s.volume(), epsilon = 1e-12);
        for k in 0..3 {
            assert_relative_eq!(c.principal_inertia(5.0)[k], 8.0, epsilon = 1e-12);
        }
        let cy = Primitive::Cylinder {
            radius: 1.0,
            half_height: 1.0,
        };
        // m (3 r^2 + h^2) / 12 with h = 2: (3 + 4) / 12.
        assert_relative_eq!(cy.principal_inertia(1.0)[0], 7.0 / 12.0, epsilon = 1e-12);
        assert_relative_eq!(cy.principal_inertia(1.0)[2], 0.5, epsilon = 1e-12);
    }

    #[test]
    fn cylinder_shape_is_turned_onto_z() {
        let cy = Primitive::Cylinder {
            radius: 0.02,
            half_height: 0.05,
        };
        let (pose, shape) = cy.to_shared_shape();
        let aabb = shape.compute_aabb(&pose);
        assert!((aabb.maxs.z - 0.05).abs() < 1e-5, "{aabb:?}");
        assert!((aabb.maxs.y - 0.02).abs() < 1e-5, "{aabb:?}");
    }

    #[test]
    fn convex_hull_of_flat_points_is_none() {
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        assert!(ConvexHull::from_points(&flat).is_none());
        let tet = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let h = ConvexHull::from_points(&tet).unwrap();
        assert_eq!(h.points.len(), 4);
        assert_relative_eq!(h.mesh().unwrap().signed_volume(), 1.0 / 6.0, epsilon = 1e-6);
    }
}
