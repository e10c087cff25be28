//! The object to grasp as the simulator sees it: a name, convex collision geometry, mass
//! properties and friction. One dynamic rigid body with one collider.
//!
//! An [`ObjectSpec`] is built from any library object ([`ObjectSpec::from_object`], the
//! convex parts of [`crate::objects::Object::collider_parts`]) or from the simulator's own
//! primitives ([`ObjectSpec::cuboid`], [`ObjectSpec::default_box`],
//! [`ObjectSpec::default_cylinder`], [`ObjectSpec::with_density`]) used by tests.
//!
//! # Body frame
//! For every object the rigid body's origin is the **centre of the object's bounding box**,
//! z up when resting. The object resting upright on the table (top at z = 0) therefore has
//! its body origin at `z = `[`ObjectSpec::rest_height`] (half its height), and the library's
//! object frame (origin at the bottom centre of the bounding box) sits at
//! `(0, 0, -rest_height)` in the body frame.
//!
//! # Mass properties
//! The body's mass, centre of mass and inertia are set explicitly
//! ([`ObjectSpec::mass_properties`]); colliders have density 0. Primitives are uniform
//! solids; library objects keep the centre of mass and inertia the library computed from
//! the visual mesh (not from the hulls, whose union overestimates the volume). Changing
//! [`ObjectSpec::mass`] scales the inertia with it.
//!
//! # Support feet
//! parry 0.31 builds the contact manifold of a convex polyhedron from at most the FIRST
//! four vertices of its support face (`ConvexPolyhedron::local_support_feature`, a TODO
//! there): a can's 48-sided bottom touches the table along one short arc only, and a
//! resting can slid 7 mm and tilted in 2 s. So every polyhedral face with more than four
//! vertices gets a thin convex "foot" inside the hull ([`support_feet`]): the hull of the
//! face's four vertices extreme along two in-face axes and the same four moved 1 mm toward
//! the hull's centre. The foot's outer face is a quadrilateral in the face's plane that
//! spans the face, so the face is supported over its whole extent; the foot lies inside the
//! hull (convex combinations of hull points), so the object's outer geometry is unchanged.

use crate::objects::{Object, ObjectError as LibraryError, Primitive};
use rapier3d::parry::shape::ConvexPolyhedron;
use rapier3d::prelude::{ColliderBuilder, MassProperties, Pose, SharedShape, Vector};
use serde::Serialize;
use std::sync::Arc;

/// Error of [`ObjectSpec::simulable_set`] and [`ObjectSpec::simulable_one`].
#[derive(Debug, thiserror::Error)]
pub enum ObjectSetError {
    /// The argument names no objects, or they cannot be built.
    #[error("cannot load objects `{arg}`")]
    Load {
        /// The argument.
        arg: String,
        /// Why.
        #[source]
        source: LibraryError,
    },
    /// An object of the set cannot be simulated.
    #[error("objects `{arg}`: {detail}")]
    NotSimulable {
        /// The argument.
        arg: String,
        /// The object and why.
        detail: String,
    },
    /// An `--object` argument that holds several objects or none.
    #[error("--object `{name}` holds {count} objects; it must name exactly one")]
    NotOne {
        /// The argument.
        name: String,
        /// Its objects.
        count: usize,
    },
}

/// Error of an invalid object description.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("object: field '{field}' = {value}: {message}")]
pub struct ObjectError {
    /// The field, e.g. `mass`.
    pub field: &'static str,
    /// The value found.
    pub value: f64,
    /// The allowed range.
    pub message: &'static str,
}

/// The convex parts of a library object, in the simulator's body frame.
#[derive(Clone)]
pub struct ConvexParts(Arc<PartsData>);

/// The parts and their convex hull.
struct PartsData {
    parts: Vec<(Pose, SharedShape)>,
    hull: Option<SharedShape>,
}

impl ConvexParts {
    /// The parts with the convex hull of all their vertices (body frame; `None` when parry
    /// cannot build it, e.g. for coplanar points).
    fn new(parts: Vec<(Pose, SharedShape)>) -> Self {
        let points: Vec<Vector> = parts
            .iter()
            .filter_map(|(pose, shape)| Some((pose, shape.as_convex_polyhedron()?)))
            .flat_map(|(pose, poly)| poly.points().iter().map(move |p| *pose * *p))
            .collect();
        let hull = SharedShape::convex_hull(&points);
        ConvexParts(Arc::new(PartsData { parts, hull }))
    }

    /// The parts: each a convex shape with its pose in the body frame.
    pub fn parts(&self) -> &[(Pose, SharedShape)] {
        &self.0.parts
    }

    /// The convex hull of the parts' vertices (body frame): a convex polyhedron, the shape
    /// the object meets the table with when `contacts.table_hull` is on (see
    /// [`crate::sim::contact`]).
    pub fn hull(&self) -> Option<&SharedShape> {
        self.0.hull.as_ref()
    }
}

impl std::fmt::Debug for ConvexParts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ConvexParts({} parts)", self.0.parts.len())
    }
}

impl PartialEq for ConvexParts {
    /// Parts are equal when they share the same storage: a rebuilt or scaled copy of the
    /// same parts compares unequal.
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Shape of an object in its body frame (origin at the bounding-box centre, z up).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ObjectShape {
    /// A box with half extents (m).
    Box {
        /// Half extents x, y, z (m).
        half: [f64; 3],
    },
    /// An upright cylinder (axis along z).
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Half height (m).
        half_height: f64,
    },
    /// The convex parts of a library object.
    Library {
        /// The collision pieces (not serialised; `part_count` says how many).
        #[serde(skip)]
        parts: ConvexParts,
        /// Number of convex pieces (hulls and support feet).
        part_count: usize,
        /// How many of the pieces are support feet (see the module docs).
        support_feet: usize,
        /// Half extents of the bounding box of the visual mesh (m).
        half: [f64; 3],
        /// Centre of mass in the body frame (m).
        com: [f64; 3],
        /// Inertia about the centre of mass per kilogram of mass (m^2), body axes.
        unit_inertia: [[f64; 3]; 3],
        /// Volume of the solid (m^3).
        volume: f64,
        /// The library's object frame in the body frame: translation (m) and unit
        /// quaternion (x, y, z, w); `p_body = R p_library + t` (today R is the identity and
        /// t = minus the bounding-box centre).
        body_from_library: ([f64; 3], [f64; 4]),
    },
}

/// `shape` scaled uniformly by `s` about its own origin; `None` for a shape kind library
/// objects never use.
fn scale_shape(shape: &SharedShape, s: f32) -> Option<SharedShape> {
    use rapier3d::parry::shape::TypedShape;
    match shape.as_typed_shape() {
        TypedShape::Ball(b) => Some(SharedShape::ball(b.radius * s)),
        TypedShape::Cuboid(c) => {
            let h = c.half_extents * s;
            Some(SharedShape::cuboid(h.x, h.y, h.z))
        }
        TypedShape::Capsule(c) => Some(SharedShape::capsule(
            c.segment.a * s,
            c.segment.b * s,
            c.radius * s,
        )),
        TypedShape::Cylinder(c) => Some(SharedShape::cylinder(c.half_height * s, c.radius * s)),
        // Scales the points and keeps the topology: no new hull is computed.
        TypedShape::ConvexPolyhedron(p) => p.clone().scaled(Vector::splat(s)).map(SharedShape::new),
        _ => None,
    }
}

impl ObjectShape {
    /// The shape scaled uniformly by `s` (> 0) about the body origin: sizes by `s`, volume
    /// by `s^3`, inertia per kilogram by `s^2` (domain randomisation of the object's size).
    /// `None` when a part cannot be scaled.
    pub fn scaled(&self, s: f64) -> Option<ObjectShape> {
        if !(s.is_finite() && s > 0.0) {
            return None;
        }
        Some(match self {
            ObjectShape::Box { half } => ObjectShape::Box {
                half: half.map(|h| h * s),
            },
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => ObjectShape::Cylinder {
                radius: radius * s,
                half_height: half_height * s,
            },
            ObjectShape::Library {
                parts,
                part_count,
                support_feet,
                half,
                com,
                unit_inertia,
                volume,
                body_from_library,
            } => {
                let sf = s as f32;
                let scaled: Option<Vec<(Pose, SharedShape)>> = parts
                    .parts()
                    .iter()
                    .map(|(pose, shape)| {
                        let mut p = *pose;
                        p.translation *= sf;
                        scale_shape(shape, sf).map(|sh| (p, sh))
                    })
                    .collect();
                let (t, q) = *body_from_library;
                ObjectShape::Library {
                    parts: ConvexParts(Arc::new(PartsData {
                        parts: scaled?,
                        hull: parts.hull().and_then(|h| scale_shape(h, sf)),
                    })),
                    part_count: *part_count,
                    support_feet: *support_feet,
                    half: half.map(|h| h * s),
                    com: com.map(|c| c * s),
                    unit_inertia: unit_inertia.map(|row| row.map(|v| v * s * s)),
                    volume: volume * s * s * s,
                    body_from_library: (t.map(|x| x * s), q),
                }
            }
        })
    }

    /// Number of collision pieces: 1 for a primitive, the convex parts (support feet
    /// included) of a library object.
    pub fn part_count(&self) -> usize {
        match self {
            ObjectShape::Library { part_count, .. } => *part_count,
            _ => 1,
        }
    }

    /// Volume (m^3).
    pub fn volume(&self) -> f64 {
        match *self {
            ObjectShape::Box { half } => 8.0 * half[0] * half[1] * half[2],
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => std::f64::consts::PI * radius * radius * 2.0 * half_height,
            ObjectShape::Library { volume, .. } => volume,
        }
    }

    /// Half extents of the bounding box (m).
    pub fn half_extents(&self) -> [f64; 3] {
        match *self {
            ObjectShape::Box { half } | ObjectShape::Library { half, .. } => half,
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => [radius, radius, half_height],
        }
    }

    /// Height of the body origin above a supporting plane when resting upright (m): half
    /// the bounding box's height.
    pub fn rest_height(&self) -> f64 {
        self.half_extents()[2]
    }

    fn primitive(&self) -> Option<Primitive> {
        match *self {
            ObjectShape::Box { half } => Some(Primitive::Box { half_extents: half }),
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => Some(Primitive::Cylinder {
                radius,
                half_height,
            }),
            ObjectShape::Library { .. } => None,
        }
    }

    /// The convex hull of a library object's parts (body frame), `None` for primitives:
    /// the shape it meets the table with when `contacts.table_hull` is on.
    pub fn table_hull(&self) -> Option<&SharedShape> {
        match self {
            ObjectShape::Library { parts, .. } => parts.hull(),
            _ => None,
        }
    }

    /// A collider builder with the shape upright in the body frame: one shape for a
    /// primitive or a single-part object, a compound of the convex parts otherwise.
    /// Density, friction and collision groups are left to the caller.
    pub fn collider(&self) -> ColliderBuilder {
        match self {
            ObjectShape::Library { parts, .. } => match parts.parts() {
                [(pose, shape)] => ColliderBuilder::new(shape.clone()).position(*pose),
                many => ColliderBuilder::new(SharedShape::compound(many.to_vec())),
            },
            _ => {
                // Box and cylinder are primitives by construction.
                let (pose, shape) = self
                    .primitive()
                    .map(|p| p.to_shared_shape())
                    .unwrap_or((Pose::IDENTITY, SharedShape::ball(0.01)));
                ColliderBuilder::new(shape).position(pose)
            }
        }
    }
}

/// Thin convex feet supporting the faces of `poly` that have more than four vertices (see
/// the module docs), in the polyhedron's frame. Thickness 1 mm (at most half the distance
/// from a vertex to the centre).
pub fn support_feet(poly: &ConvexPolyhedron) -> Vec<SharedShape> {
    let pts = poly.points();
    if pts.is_empty() {
        return Vec::new();
    }
    let centre = pts.iter().copied().sum::<Vector>() / pts.len() as f32;
    let adj = poly.vertices_adj_to_face();
    let mut feet = Vec::new();
    for face in poly.faces() {
        let (first, n) = (
            face.first_vertex_or_edge as usize,
            face.num_vertices_or_edges as usize,
        );
        let Some(ids) = adj.get(first..first + n) else {
            continue;
        };
        if n <= 4 {
            continue;
        }
        let u = face.normal.any_orthonormal_vector();
        let v = face.normal.cross(u);
        let mut chosen: Vec<u32> = Vec::with_capacity(4);
        for (axis, sign) in [(u, 1.0f32), (v, 1.0), (u, -1.0), (v, -1.0)] {
            let best = ids.iter().copied().max_by(|a, b| {
                let da = sign * axis.dot(pts[*a as usize]);
                let db = sign * axis.dot(pts[*b as usize]);
                da.total_cmp(&db)
            });
            if let Some(b) = best.filter(|b| !chosen.contains(b)) {
                chosen.push(b);
            }
        }
        if chosen.len() < 3 {
            continue;
        }
        let mut foot: Vec<Vector> = Vec::with_capacity(2 * chosen.len());
        for id in &chosen {
            let p = pts[*id as usize];
            let to_centre = centre - p;
            let t = (1e-3 / to_centre.length().max(1e-9)).min(0.5);
            foot.push(p);
            foot.push(p + to_centre * t);
        }
        if let Some(shape) = SharedShape::convex_hull(&foot) {
            feet.push(shape);
        }
    }
    feet
}

/// An object to simulate: its name, shape, mass and friction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectSpec {
    /// The object's name (results are reported per name): the library name, or `box` /
    /// `cylinder` for the simulator's primitives.
    pub name: String,
    /// The shape.
    pub shape: ObjectShape,
    /// Mass (kg).
    pub mass: f64,
    /// Friction coefficient (combined with MIN against the hand and the table).
    pub friction: f64,
}

impl ObjectSpec {
    /// A box named `box` of `mass` kg with half extents `half`.
    pub fn cuboid(half: [f64; 3], mass: f64, friction: f64) -> Self {
        ObjectSpec {
            name: "box".into(),
            shape: ObjectShape::Box { half },
            mass,
            friction,
        }
    }

    /// The default test box: 5 x 5 x 8 cm, 100 g, friction 0.8.
    pub fn default_box() -> Self {
        Self::cuboid([0.025, 0.025, 0.04], 0.1, 0.8)
    }

    /// The default cylinder: radius 3 cm, height 10 cm, 150 g, friction 0.8.
    pub fn default_cylinder() -> Self {
        ObjectSpec {
            name: "cylinder".into(),
            shape: ObjectShape::Cylinder {
                radius: 0.03,
                half_height: 0.05,
            },
            mass: 0.15,
            friction: 0.8,
        }
    }

    /// A spec of the shape with the density `rho` (kg/m^3), named after its kind (`box`,
    /// `cylinder` or `object`).
    pub fn with_density(shape: ObjectShape, rho: f64, friction: f64) -> Self {
        let name = match shape {
            ObjectShape::Box { .. } => "box",
            ObjectShape::Cylinder { .. } => "cylinder",
            ObjectShape::Library { .. } => "object",
        };
        ObjectSpec {
            name: name.into(),
            mass: rho * shape.volume(),
            shape,
            friction,
        }
    }

    /// The same spec under another name.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// The simulator's view of a library object: its convex parts, mass, centre of mass,
    /// inertia and friction, moved into the body frame (origin at the bounding-box centre,
    /// see the module docs). Fails when the object has no valid convex part.
    pub fn from_object(object: &Object) -> Result<ObjectSpec, LibraryError> {
        let (lo, hi) = (object.bbox.min, object.bbox.max);
        let c = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let shift = Pose::translation(-c[0] as f32, -c[1] as f32, -c[2] as f32);
        let mut parts: Vec<(Pose, SharedShape)> = object
            .collider_parts()?
            .into_iter()
            .map(|(pose, shape)| (shift * pose, shape))
            .collect();
        let mut feet = Vec::new();
        for (pose, shape) in &parts {
            if let Some(poly) = shape.as_convex_polyhedron() {
                feet.extend(support_feet(poly).into_iter().map(|f| (*pose, f)));
            }
        }
        let support_feet = feet.len();
        parts.extend(feet);
        let half = object.bbox.extents().map(|e| 0.5 * e);
        let com = [0, 1, 2].map(|k| object.com[k] - c[k]);
        let m = object.mass_kg;
        let unit_inertia = object.inertia.map(|row| row.map(|v| v / m));
        let body_from_library = ([-c[0], -c[1], -c[2]], [0.0, 0.0, 0.0, 1.0]);
        Ok(ObjectSpec {
            name: object.name.clone(),
            shape: ObjectShape::Library {
                part_count: parts.len(),
                support_feet,
                parts: ConvexParts::new(parts),
                half,
                com,
                unit_inertia,
                volume: object.volume_m3,
                body_from_library,
            },
            mass: m,
            friction: object.friction,
        })
    }

    /// [`ObjectSpec::from_object`] followed by the simulator's own checks
    /// ([`ObjectSpec::validate`]): an object the simulator would refuse at every reset is
    /// refused here, before any episode runs, with its name.
    pub fn simulable(object: &Object) -> Result<ObjectSpec, String> {
        let spec = ObjectSpec::from_object(object)
            .map_err(|e| format!("object '{}' cannot be simulated: {e}", object.name))?;
        spec.validate()
            .map_err(|e| format!("object '{}' cannot be simulated: {e}", object.name))?;
        Ok(spec)
    }

    /// The objects of an `--objects`-style argument (a set name, a manifest, a mesh or a
    /// comma list; [`crate::objects::sets::load_objects`], hulls from the cache), each
    /// [`ObjectSpec::simulable`] and named: every object is checked before any episode
    /// runs, the error naming the argument and the object.
    pub fn simulable_set(arg: &str) -> Result<Vec<(String, ObjectSpec)>, ObjectSetError> {
        let ctx = crate::objects::BuildContext::from_env();
        let objects = crate::objects::sets::load_objects(arg, &ctx).map_err(|source| {
            ObjectSetError::Load {
                arg: arg.to_string(),
                source,
            }
        })?;
        objects
            .iter()
            .map(|o| {
                let spec =
                    ObjectSpec::simulable(o).map_err(|detail| ObjectSetError::NotSimulable {
                        arg: arg.to_string(),
                        detail,
                    })?;
                Ok((o.name.clone(), spec))
            })
            .collect()
    }

    /// The one object of an `--object`-style argument: `box`, `cylinder` or an argument
    /// of [`ObjectSpec::simulable_set`] that holds exactly one object.
    pub fn simulable_one(name: &str) -> Result<ObjectSpec, ObjectSetError> {
        match name.trim() {
            "box" => return Ok(ObjectSpec::default_box()),
            "cylinder" => return Ok(ObjectSpec::default_cylinder()),
            _ => {}
        }
        let mut objs = ObjectSpec::simulable_set(name)?;
        if objs.len() != 1 {
            return Err(ObjectSetError::NotOne {
                name: name.to_string(),
                count: objs.len(),
            });
        }
        Ok(objs.remove(0).1)
    }

    /// Height of the body origin above the table when the object rests upright (m).
    pub fn rest_height(&self) -> f64 {
        self.shape.rest_height()
    }

    /// Mass, centre of mass and inertia of the body (body frame), for
    /// `RigidBodyBuilder::additional_mass_properties`: a uniform solid for primitives, the
    /// library's values for library objects, scaled to [`ObjectSpec::mass`].
    pub fn mass_properties(&self) -> MassProperties {
        let m = self.mass;
        match &self.shape {
            ObjectShape::Library {
                com, unit_inertia, ..
            } => {
                let i = unit_inertia.map(|row| row.map(|v| (v * m) as f32));
                // Column-major.
                let inertia = rapier3d::math::Matrix::from_cols_array(&[
                    i[0][0], i[1][0], i[2][0], i[0][1], i[1][1], i[2][1], i[0][2], i[1][2], i[2][2],
                ]);
                let com = Vector::new(com[0] as f32, com[1] as f32, com[2] as f32);
                MassProperties::with_inertia_matrix(com, m as f32, inertia)
            }
            shape => {
                let p = shape
                    .primitive()
                    .map_or([0.0; 3], |p| p.principal_inertia(m));
                MassProperties::new(
                    Vector::ZERO,
                    m as f32,
                    Vector::new(p[0] as f32, p[1] as f32, p[2] as f32),
                )
            }
        }
    }

    /// Checks sizes (half extents 0.5 mm .. 0.5 m), mass (1 g .. 20 kg), friction
    /// ([0, 1]) and, for library objects, a finite centre of mass inside the bounding box
    /// and a finite inertia with positive diagonal.
    pub fn validate(&self) -> Result<(), ObjectError> {
        let size = |field: &'static str, v: f64| {
            if v.is_finite() && (0.0005..=0.5).contains(&v) {
                Ok(())
            } else {
                Err(ObjectError {
                    field,
                    value: v,
                    message: "half size must be in [0.0005, 0.5] m",
                })
            }
        };
        match &self.shape {
            ObjectShape::Box { half } => {
                size("half[0]", half[0])?;
                size("half[1]", half[1])?;
                size("half[2]", half[2])?;
            }
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => {
                size("radius", *radius)?;
                size("half_height", *half_height)?;
            }
            ObjectShape::Library {
                half,
                com,
                unit_inertia,
                ..
            } => {
                size("half[0]", half[0])?;
                size("half[1]", half[1])?;
                size("half[2]", half[2])?;
                for k in 0..3 {
                    if !(com[k].is_finite() && com[k].abs() <= half[k] + 1e-6) {
                        return Err(ObjectError {
                            field: "com",
                            value: com[k],
                            message: "must be finite and inside the bounding box",
                        });
                    }
                }
                for (k, row) in unit_inertia.iter().enumerate() {
                    if row.iter().any(|v| !v.is_finite()) || row[k] <= 0.0 {
                        return Err(ObjectError {
                            field: "inertia",
                            value: row[k],
                            message: "must be finite with a positive diagonal",
                        });
                    }
                }
            }
        }
        if !(self.mass.is_finite() && (0.001..=20.0).contains(&self.mass)) {
            return Err(ObjectError {
                field: "mass",
                value: self.mass,
                message: "must be in [0.001, 20] kg",
            });
        }
        if !(self.friction.is_finite() && (0.0..=1.0).contains(&self.friction)) {
            return Err(ObjectError {
                field: "friction",
                value: self.friction,
                message: "must be in [0, 1]",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::sets::{build, resolve_specs};
    use crate::objects::BuildContext;

    fn library(name: &str) -> Object {
        let dir = tempfile::tempdir().unwrap();
        let spec = resolve_specs(name).unwrap().remove(0);
        build(&spec, &BuildContext::with_cache_dir(dir.path())).unwrap()
    }

    #[test]
    fn volumes_and_density() {
        let b = ObjectShape::Box {
            half: [0.01, 0.02, 0.03],
        };
        assert!((b.volume() - 8.0 * 6e-6).abs() < 1e-15);
        let s = ObjectSpec::with_density(b, 1000.0, 0.5);
        assert!((s.mass - 0.048).abs() < 1e-12);
        assert_eq!(s.name, "box");
        let c = ObjectShape::Cylinder {
            radius: 0.1,
            half_height: 0.5,
        };
        assert!((c.volume() - std::f64::consts::PI * 0.01).abs() < 1e-12);
        assert_eq!(c.rest_height(), 0.5);
    }

    #[test]
    fn scaling_scales_sizes_volume_and_inertia_hand_computed() {
        // Box 2 x 4 x 6 cm scaled by 2: 4 x 8 x 12 cm, volume 8 x 48e-6 = 3.84e-4 m^3.
        let b = ObjectShape::Box {
            half: [0.01, 0.02, 0.03],
        };
        let b2 = b.scaled(2.0).unwrap();
        assert_eq!(b2.half_extents(), [0.02, 0.04, 0.06]);
        assert!((b2.volume() - 3.84e-4).abs() < 1e-15);
        assert!(b.scaled(0.0).is_none() && b.scaled(f64::NAN).is_none());
        // A library object (a YCB-like mug: convex parts): half extents, com and volume
        // scale by 1.5, 1.5, 1.5^3; the per-kg inertia by 1.5^2; the collider's AABB with it.
        let s = ObjectSpec::from_object(&library("mug")).unwrap();
        let ObjectShape::Library {
            com, unit_inertia, ..
        } = &s.shape
        else {
            panic!("mug is a library object")
        };
        let big = s.shape.scaled(1.5).unwrap();
        let ObjectShape::Library {
            com: c2,
            unit_inertia: i2,
            ..
        } = &big
        else {
            panic!("scaling keeps the kind")
        };
        for k in 0..3 {
            assert!((big.half_extents()[k] - 1.5 * s.shape.half_extents()[k]).abs() < 1e-12);
            assert!((c2[k] - 1.5 * com[k]).abs() < 1e-12);
            assert!((i2[k][k] - 2.25 * unit_inertia[k][k]).abs() < 1e-15);
        }
        assert!((big.volume() - 3.375 * s.shape.volume()).abs() < 1e-12);
        let aabb = |sh: &ObjectShape| {
            let c = sh.collider().build();
            let a = c.shape().compute_local_aabb();
            (a.maxs - a.mins).x as f64
        };
        assert!((aabb(&big) - 1.5 * aabb(&s.shape)).abs() < 1e-5);
    }

    #[test]
    fn validation_names_the_field() {
        let mut s = ObjectSpec::default_box();
        s.validate().unwrap();
        s.friction = 1.5;
        assert_eq!(s.validate().unwrap_err().field, "friction");
        s.friction = 0.5;
        s.mass = f64::NAN;
        assert_eq!(s.validate().unwrap_err().field, "mass");
    }

    #[test]
    fn box_mass_properties_are_a_uniform_solid() {
        // 2 x 4 x 6 cm, 0.6 kg: Ixx = m (b^2 + c^2) / 12 = 0.6 (16 + 36) e-4 / 12 = 2.6e-4.
        let s = ObjectSpec::cuboid([0.01, 0.02, 0.03], 0.6, 0.5);
        let mp = s.mass_properties();
        assert!((mp.mass() - 0.6).abs() < 1e-6);
        let i = mp.principal_inertia();
        assert!((i.x - 2.6e-4).abs() < 1e-9, "{i:?}");
        assert!(
            (i.z - 0.6 * (4.0 + 16.0) * 1e-4 / 12.0).abs() < 1e-9,
            "{i:?}"
        );
        assert_eq!(mp.local_com, Vector::ZERO);
    }

    #[test]
    fn library_box_matches_the_primitive_box() {
        // box_gelatin: 9 x 7 x 3 cm, a primitive in the library.
        let o = library("box_gelatin");
        let s = ObjectSpec::from_object(&o).unwrap();
        s.validate().unwrap();
        assert_eq!(s.name, "box_gelatin");
        assert!((s.rest_height() - 0.015).abs() < 1e-9);
        assert_eq!(s.mass, o.mass_kg);
        assert_eq!(s.friction, o.friction);
        let prim = ObjectSpec::cuboid([0.045, 0.035, 0.015], o.mass_kg, o.friction);
        let (a, b) = (s.mass_properties(), prim.mass_properties());
        assert!((a.mass() - b.mass()).abs() < 1e-6);
        assert!(a.local_com.length() < 1e-6, "{:?}", a.local_com);
        let (ia, ib) = (a.principal_inertia(), b.principal_inertia());
        // Principal moments agree up to their order.
        let mut va = [ia.x, ia.y, ia.z];
        let mut vb = [ib.x, ib.y, ib.z];
        va.sort_by(f32::total_cmp);
        vb.sort_by(f32::total_cmp);
        for k in 0..3 {
            assert!((va[k] - vb[k]).abs() < 1e-3 * vb[k], "{va:?} {vb:?}");
        }
        // The collider spans the bounding box centred on the body origin.
        let aabb = s.shape.collider().build().compute_aabb();
        assert!((aabb.mins.z + 0.015).abs() < 1e-4, "{aabb:?}");
        assert!((aabb.maxs.x - 0.045).abs() < 1e-4, "{aabb:?}");
    }

    #[test]
    fn multi_part_object_becomes_a_compound_in_the_body_frame() {
        let o = library("mug");
        let s = ObjectSpec::from_object(&o).unwrap();
        s.validate().unwrap();
        let ObjectShape::Library {
            part_count, com, ..
        } = &s.shape
        else {
            panic!("not a library shape")
        };
        assert!(*part_count >= o.hulls.len());
        // The centre of mass moved with the frame: object-frame z minus half the height.
        let h = o.bbox.extents()[2];
        assert!((com[2] - (o.com[2] - 0.5 * h)).abs() < 1e-12);
        let aabb = s.shape.collider().build().compute_aabb();
        assert!((aabb.mins.z as f64 + 0.5 * h).abs() < 2e-3, "{aabb:?}");
        assert!((aabb.maxs.z as f64 - 0.5 * h).abs() < 2e-3, "{aabb:?}");
        // Doubling the mass doubles the inertia.
        let mut heavy = s.clone();
        heavy.mass *= 2.0;
        let (a, b) = (s.mass_properties(), heavy.mass_properties());
        let ratio = b.principal_inertia().x / a.principal_inertia().x;
        assert!((ratio - 2.0).abs() < 1e-4, "{ratio}");
    }

    #[test]
    fn table_hull_encloses_every_part_and_scales_with_the_object() {
        let s = ObjectSpec::from_object(&library("mug")).unwrap();
        let ObjectShape::Library { parts, .. } = &s.shape else {
            panic!("not a library shape")
        };
        let hull = s.shape.table_hull().unwrap();
        let poly = hull.as_convex_polyhedron().unwrap();
        // Every vertex of every part is inside the hull (within rounding) and the hull's
        // box is the parts' box.
        for (pose, part) in parts.parts() {
            for p in part.as_convex_polyhedron().unwrap().points() {
                let q = *pose * *p;
                for f in poly.faces() {
                    let v = poly.points()
                        [poly.vertices_adj_to_face()[f.first_vertex_or_edge as usize] as usize];
                    assert!(f.normal.dot(q - v) < 1e-5, "{q:?} outside a face");
                }
            }
        }
        let (a, b) = (
            hull.compute_aabb(&Pose::IDENTITY),
            s.shape.collider().build().compute_aabb(),
        );
        assert!((a.mins - b.mins).length() < 1e-6 && (a.maxs - b.maxs).length() < 1e-6);
        // Scaled with the object; primitives have none.
        let big = s.shape.scaled(2.0).unwrap();
        let c = big.table_hull().unwrap().compute_aabb(&Pose::IDENTITY);
        assert!((c.maxs - a.maxs * 2.0).length() < 1e-6, "{c:?}");
        assert!(ObjectSpec::default_box().shape.table_hull().is_none());
    }

    #[test]
    fn large_faces_get_feet_spanning_them_inside_the_hull() {
        // A 12-sided prism, radius 3 cm, 0 <= z <= 4 cm: two 12-vertex faces, quads around.
        let mut pts = Vec::new();
        for k in 0..12 {
            let a = k as f32 * std::f32::consts::TAU / 12.0;
            for z in [0.0, 0.04] {
                pts.push(Vector::new(0.03 * a.cos(), 0.03 * a.sin(), z));
            }
        }
        let hull = SharedShape::convex_hull(&pts).unwrap();
        let poly = hull.as_convex_polyhedron().unwrap();
        let feet = support_feet(poly);
        assert_eq!(feet.len(), 2);
        for f in &feet {
            let a = f.compute_aabb(&Pose::IDENTITY);
            // Inside the prism's box, spanning most of the 6 cm face (a square inscribed in
            // the circle is 4.2 cm wide), 1 mm thick at most.
            assert!(a.mins.z >= -1e-6 && a.maxs.z <= 0.04 + 1e-6, "{a:?}");
            assert!(a.maxs.x - a.mins.x > 0.04, "{a:?}");
            assert!(a.maxs.y - a.mins.y > 0.04, "{a:?}");
            let thick = (a.maxs.z - a.mins.z).min(0.04 - (a.maxs.z - a.mins.z));
            assert!(thick < 1.1e-3, "{a:?}");
        }
        // One foot lies on the bottom face (z = 0), one on the top face.
        let lows: Vec<f32> = feet
            .iter()
            .map(|f| f.compute_aabb(&Pose::IDENTITY).mins.z)
            .collect();
        assert!(lows.iter().any(|z| z.abs() < 1e-6), "{lows:?}");
        // A box (quadrilateral faces only) needs no feet.
        let cube = SharedShape::convex_hull(&[
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.0, 1.0, 0.0),
            Vector::new(1.0, 1.0, 0.0),
            Vector::new(0.0, 0.0, 1.0),
            Vector::new(1.0, 0.0, 1.0),
            Vector::new(0.0, 1.0, 1.0),
            Vector::new(1.0, 1.0, 1.0),
        ])
        .unwrap();
        assert!(support_feet(cube.as_convex_polyhedron().unwrap()).is_empty());
    }
}
