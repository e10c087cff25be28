//! Building object specs into [`Object`]s: the shape made and turned to rest, its mass
//! properties, its collision hulls (a primitive's exact shape, one hull, the generator's
//! parts or a cached VHACD decomposition), with the mass of built-ins clamped into
//! [`BUILTIN_MASS_RANGE`].

use super::decomp::{decompose, decompose_cached, CacheStatus, DecompParams};
use super::mesh::{MassProps, TriMesh};
use super::procedural::generate;
use super::shape_kit::{box_mesh, icosphere, revolve};
use super::spec::{MassSpec, ObjectSpec, ShapeSpec};
use super::{convex_hull_mesh, ConvexHull, HullSource, Object, ObjectError, Primitive};
use rayon::prelude::*;
use std::path::PathBuf;

/// Mass range (kg) built-in objects are clamped into.
pub const BUILTIN_MASS_RANGE: (f64, f64) = (0.05, 0.6);

/// A mesh whose volume is at least this fraction of its convex hull's is treated as
/// convex and gets one hull instead of a VHACD decomposition.
pub const NEAR_CONVEX_RATIO: f64 = 0.97;

/// Where to cache decompositions and how to decompose.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildContext {
    /// Cache folder for generated objects' hulls (user meshes cache next to the file).
    pub cache_dir: PathBuf,
    /// VHACD parameters.
    pub decomp: DecompParams,
    /// Whether decompositions are read from and written to the cache folder (false: always
    /// computed, nothing written; the per-episode objects of the training stream).
    pub cache: bool,
}

impl BuildContext {
    /// The default context: [`super::decomp::default_cache_dir`] and default parameters.
    pub fn from_env() -> Self {
        Self::with_cache_dir(super::decomp::default_cache_dir())
    }

    /// Default parameters with an explicit cache folder (tests use a temporary one).
    pub fn with_cache_dir(dir: impl Into<PathBuf>) -> Self {
        BuildContext {
            cache_dir: dir.into(),
            decomp: DecompParams::default(),
            cache: true,
        }
    }

    /// Default parameters, no cache: every decomposition is computed, nothing is written.
    pub fn uncached() -> Self {
        BuildContext {
            cache: false,
            ..Self::with_cache_dir(PathBuf::new())
        }
    }
}

/// A spec together with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedSpec {
    /// The object spec (mesh paths already absolute or relative to the working folder).
    pub spec: ObjectSpec,
    /// Whether it is a built-in object (stricter friction, clamped mass).
    pub builtin: bool,
    /// Origin for error messages: "built-in", the manifest, the folder or the file.
    pub source: String,
}

/// The geometry and mass of an object before its collision hulls are computed.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The spec it came from.
    pub spec: ResolvedSpec,
    /// Visual mesh in the object frame.
    pub mesh: TriMesh,
    /// Exact primitive, if any.
    pub primitive: Option<Primitive>,
    /// Convex parts from the generator, in the object frame.
    pub parts: Option<Vec<ConvexHull>>,
    /// Total mass in kg.
    pub mass_kg: f64,
    /// Volume in m^3.
    pub volume_m3: f64,
    /// Centre of mass in the object frame.
    pub com: [f64; 3],
    /// Inertia about the centre of mass (kg m^2).
    pub inertia: [[f64; 3]; 3],
}

fn primitive_of(shape: &ShapeSpec) -> Option<Primitive> {
    match *shape {
        ShapeSpec::Box { size } => Some(Primitive::Box {
            half_extents: size.map(|s| 0.5 * s),
        }),
        ShapeSpec::Cylinder { radius, height } => Some(Primitive::Cylinder {
            radius,
            half_height: 0.5 * height,
        }),
        ShapeSpec::Sphere { radius } => Some(Primitive::Sphere { radius }),
        ShapeSpec::Capsule { radius, height } => Some(Primitive::Capsule {
            radius,
            half_height: 0.5 * height - radius,
        }),
        _ => None,
    }
}

/// A closed tessellation of a primitive centred at the origin.
pub fn primitive_mesh(p: &Primitive) -> Result<TriMesh, String> {
    Ok(match *p {
        Primitive::Box { half_extents } => box_mesh(half_extents),
        Primitive::Cylinder {
            radius,
            half_height,
        } => revolve(
            &[
                [0.0, -half_height],
                [radius, -half_height],
                [radius, half_height],
                [0.0, half_height],
            ],
            48,
        )?,
        Primitive::Sphere { radius } => {
            let mut m = icosphere(3);
            m.scale([radius; 3]);
            m
        }
        Primitive::Capsule {
            radius,
            half_height,
        } => {
            let n = 12;
            let mut prof = vec![[0.0, -half_height - radius]];
            for i in 1..n {
                let a = -std::f64::consts::FRAC_PI_2
                    + std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
                prof.push([radius * a.cos(), -half_height + radius * a.sin()]);
            }
            prof.push([radius, -half_height]);
            if half_height > 0.0 {
                prof.push([radius, half_height]);
            }
            for i in 1..n {
                let a = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
                prof.push([radius * a.cos(), half_height + radius * a.sin()]);
            }
            prof.push([0.0, half_height + radius]);
            revolve(&prof, 32)?
        }
    })
}

/// Builds the geometry and mass of a spec (everything but the collision hulls).
pub fn prepare(rs: &ResolvedSpec) -> Result<Prepared, ObjectError> {
    let spec = &rs.spec;
    spec.validate(&rs.source, rs.builtin)?;
    let invalid = |m: String| ObjectError::InvalidSpec {
        source_name: rs.source.clone(),
        object: spec.name.clone(),
        field: "shape".into(),
        message: m,
    };
    let primitive = primitive_of(&spec.shape);
    let (mut mesh, mut parts, label) = match &spec.shape {
        ShapeSpec::Mesh { path, scale } => {
            let label = path.display().to_string();
            let mut m = TriMesh::load(path)?;
            m.validate(&label)?;
            m.scale([*scale; 3]);
            m.orient_outward();
            (m, None, label)
        }
        ShapeSpec::Procedural {
            generator,
            seed,
            params,
            scale,
        } => {
            let mut g = generate(generator, *seed, params, &spec.name, &rs.source)?;
            let label = format!("{} (generator {generator}, {})", spec.name, rs.source);
            g.mesh.validate(&label)?;
            if *scale != 1.0 {
                g.mesh.scale([*scale; 3]);
                for h in g.parts.iter_mut().flatten() {
                    for q in &mut h.points {
                        *q = q.map(|x| x * scale);
                    }
                }
            }
            (g.mesh, g.parts, label)
        }
        _ => {
            let p = primitive.ok_or_else(|| invalid("not a primitive".into()))?;
            let m = primitive_mesh(&p).map_err(invalid)?;
            (m, None, format!("{} ({})", spec.name, rs.source))
        }
    };
    mesh.check_size(&label)?;
    if primitive.is_none() {
        turn_to_rest(&mut mesh, parts.as_mut());
    }
    let bb = mesh.aabb().ok_or_else(|| ObjectError::EmptyMesh {
        path: label.clone(),
    })?;
    let shift = [
        -0.5 * (bb.min[0] + bb.max[0]),
        -0.5 * (bb.min[1] + bb.max[1]),
        -bb.min[2],
    ];
    mesh.translate(shift);
    if let Some(ps) = &mut parts {
        for h in ps.iter_mut() {
            for q in &mut h.points {
                for k in 0..3 {
                    q[k] += shift[k];
                }
            }
        }
    }
    let props: MassProps = match primitive {
        Some(p) => MassProps {
            volume: p.volume(),
            centroid: [0.0, 0.0, p.half_height_total()],
            inertia_unit_density: diag(p.principal_inertia(p.volume())),
        },
        None => mesh.mass_properties(),
    };
    let mut mass = match spec.mass_spec() {
        MassSpec::Mass(m) => m,
        MassSpec::Density(d) => d * props.volume,
    };
    if rs.builtin {
        mass = mass.clamp(BUILTIN_MASS_RANGE.0, BUILTIN_MASS_RANGE.1);
    }
    if !(mass.is_finite() && mass > 0.0) {
        return Err(invalid(format!("mass {mass} kg is not positive")));
    }
    // A density gives the mass only with the volume: held to the bound of `mass_kg`.
    let (lo, hi) = super::spec::MASS_RANGE_KG;
    if let MassSpec::Density(d) = spec.mass_spec() {
        if !rs.builtin && !(lo..=hi).contains(&mass) {
            return Err(ObjectError::InvalidSpec {
                source_name: rs.source.clone(),
                object: spec.name.clone(),
                field: "density_kg_m3".into(),
                message: format!(
                    "{d} kg/m^3 over {:.3e} m^3 gives {} kg, outside the {lo}..={hi} kg \
                     that mass_kg allows",
                    props.volume,
                    if mass >= 0.01 {
                        format!("{mass:.1}")
                    } else {
                        format!("{mass:.2e}")
                    }
                ),
            });
        }
    }
    Ok(Prepared {
        spec: rs.clone(),
        inertia: props.inertia_for_mass(mass),
        mesh,
        primitive,
        parts,
        mass_kg: mass,
        volume_m3: props.volume,
        com: props.centroid,
    })
}

/// Turns a mesh (and its convex parts) onto a stable rest face (see [`super::rest`]).
fn turn_to_rest(mesh: &mut TriMesh, parts: Option<&mut Vec<ConvexHull>>) {
    let points: Vec<[f64; 3]> = match &parts {
        Some(ps) => ps.iter().flat_map(|h| h.points.iter().copied()).collect(),
        None => mesh.vertices.clone(),
    };
    let Some(hull) = convex_hull_mesh(&points) else {
        return;
    };
    let Some(r) = super::rest::rest_rotation(&hull, mesh.mass_properties().centroid) else {
        return;
    };
    let turn = |p: &mut [f64; 3]| {
        let q = r * nalgebra::Vector3::from(*p);
        *p = [q.x, q.y, q.z];
    };
    mesh.vertices.iter_mut().for_each(turn);
    for h in parts.into_iter().flatten() {
        h.points.iter_mut().for_each(turn);
    }
}

fn diag(d: [f64; 3]) -> [[f64; 3]; 3] {
    [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]]
}

impl Prepared {
    /// The hull cache file of this object: `<mesh>.hulls.json` for a mesh file, else
    /// `<cache dir>/hulls/<name>.hulls.json`.
    pub fn cache_file(&self, ctx: &BuildContext) -> PathBuf {
        match &self.spec.spec.shape {
            ShapeSpec::Mesh { path, .. } => {
                let mut s = path.as_os_str().to_owned();
                s.push(".hulls.json");
                PathBuf::from(s)
            }
            _ => ctx
                .cache_dir
                .join("hulls")
                .join(format!("{}.hulls.json", self.spec.spec.name)),
        }
    }

    /// Computes the collision hulls (see the module docs of [`super`]) and returns the
    /// finished object.
    pub fn finish(self, ctx: &BuildContext) -> Result<Object, ObjectError> {
        let name = self.spec.spec.name.clone();
        let no_hull = || ObjectError::Decomposition {
            name: name.clone(),
            message: "the mesh has no 3-D convex hull".into(),
        };
        let (hulls, source) = if self.primitive.is_some() {
            let h = ConvexHull::from_points(&self.mesh.vertices).ok_or_else(no_hull)?;
            (vec![h], HullSource::Primitive)
        } else if let Some(parts) = &self.parts {
            (parts.clone(), HullSource::Parts)
        } else {
            let hull = convex_hull_mesh(&self.mesh.vertices).ok_or_else(no_hull)?;
            if self.volume_m3 >= NEAR_CONVEX_RATIO * hull.signed_volume() {
                (
                    vec![ConvexHull {
                        points: hull.vertices,
                    }],
                    HullSource::Convex,
                )
            } else {
                let (h, status) = if ctx.cache {
                    let file = self.cache_file(ctx);
                    decompose_cached(&self.mesh, &ctx.decomp, &file, &name)?
                } else {
                    (
                        decompose(&self.mesh, &ctx.decomp, &name)?,
                        CacheStatus::Built,
                    )
                };
                (h, HullSource::Vhacd(status))
            }
        };
        let bbox = self.mesh.aabb().ok_or_else(no_hull)?;
        Ok(Object {
            name,
            kind: self.spec.spec.kind,
            mass_kg: self.mass_kg,
            friction: self.spec.spec.friction,
            volume_m3: self.volume_m3,
            com: self.com,
            inertia: self.inertia,
            bbox,
            hulls,
            primitive: self.primitive,
            hull_source: source,
            mesh: self.mesh,
        })
    }
}

/// Prepares and finishes one spec.
pub fn build(rs: &ResolvedSpec, ctx: &BuildContext) -> Result<Object, ObjectError> {
    prepare(rs)?.finish(ctx)
}

/// Builds every spec (in parallel on the current rayon pool), keeping the order.
pub fn build_all(specs: &[ResolvedSpec], ctx: &BuildContext) -> Result<Vec<Object>, ObjectError> {
    // Collect every result first so the reported error is the first failing object in
    // order, whatever the thread timing.
    let results: Vec<Result<Object, ObjectError>> =
        specs.par_iter().map(|s| build(s, ctx)).collect();
    results.into_iter().collect()
}
