//! Built-in object sets, the `--objects` resolver, and building specs into [`Object`]s.
//!
//! # Built-in sets
//!
//! `train` mirrors the paper's 61 training objects (Sec. IV-A, Fig. 4). Its caption lists
//! 11 YCB, 14 ShapeNet, 5 primitive shapes (4 boxes, 1 cylinder) and 31 EGAD objects; the
//! text counts the primitives among 19 ShapeNet objects. The mapping used here:
//!
//! | paper                         | here                                   | count |
//! |-------------------------------|----------------------------------------|-------|
//! | YCB                           | `ycb-like` everyday shapes, YCB sizes and masses | 11 |
//! | ShapeNet (without primitives) | `shapenet-like` everyday shapes        | 14 |
//! | primitive shapes              | `primitive`: 4 boxes, 1 cylinder       | 5 |
//! | EGAD                          | `egad` grid `egad_c{0..5}_d{0..4}` plus `egad_c6_d2` | 31 |
//!
//! The EGAD-like grid covers complexity levels 0-5 by difficulty levels 0-4 (30 cells)
//! plus one object at the highest complexity level, 6, middle difficulty.
//!
//! `unseen` (19 objects) holds shape families absent from `train` (prisms, a cone frustum,
//! a star, a ring, a dumbbell, a goblet, an egg, a pear, flat blocks, a spatula, a sphere
//! and a capsule) and five EGAD-like shapes from other seeds and sizes. `all` is both.
//!
//! # Masses and friction of built-ins
//!
//! YCB-like objects use the real YCB object's mass; other kinds use a density per object
//! (apparent density: hollow bottles count as light solids; EGAD-like shapes use
//! 350 kg/m^3, a 3-D print with sparse infill). Built-in masses are then clamped into
//! [`BUILTIN_MASS_RANGE`] (50..600 g) so that every object suits the hand. Friction is
//! 0.8 (YCB-like), 0.75 (ShapeNet-like), 0.9 (EGAD-like, rough prints), 0.7 (primitives).
//!
//! # The `--objects` argument ([`resolve_specs`])
//!
//! `train`, `unseen`, `all`; `procedural` (the first 64 objects of the procedural stream,
//! see [`super::stream`]); a folder of `.obj`/`.stl` files (one object each, named by
//! the file stem, default density and friction); a manifest `.toml` (see [`super::spec`]);
//! a single `.obj`/`.stl` file; or a comma-separated list of built-in object names and
//! stream objects (`proc-<seed>-<index>`).

use super::decomp::{decompose, decompose_cached, CacheStatus, DecompParams};
use super::mesh::{MassProps, TriMesh};
use super::procedural::{box_mesh, generate, icosphere, revolve};
use super::spec::{load_manifest, MassSpec, ObjectKind, ObjectSpec, ShapeSpec};
use super::{convex_hull_mesh, ConvexHull, HullSource, Object, ObjectError, Primitive};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// The built-in set names.
pub const BUILTIN_SETS: [&str; 3] = ["train", "unseen", "all"];

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

/// Resolves an `--objects` argument and builds the objects.
pub fn load_objects(arg: &str, ctx: &BuildContext) -> Result<Vec<Object>, ObjectError> {
    build_all(&resolve_specs(arg)?, ctx)
}

// ---------------------------------------------------------------------------------------
// Built-in specs

fn params(p: &[(&str, f64)]) -> BTreeMap<String, f64> {
    p.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

fn friction_of(kind: ObjectKind) -> f64 {
    match kind {
        ObjectKind::YcbLike => 0.8,
        ObjectKind::ShapenetLike => 0.75,
        ObjectKind::Egad => 0.9,
        ObjectKind::Primitive => 0.7,
        ObjectKind::User | ObjectKind::Procedural => super::spec::DEFAULT_FRICTION,
    }
}

enum M {
    Kg(f64),
    Density(f64),
}

fn spec(name: &str, kind: ObjectKind, shape: ShapeSpec, m: M) -> ObjectSpec {
    let (mass_kg, density_kg_m3) = match m {
        M::Kg(x) => (Some(x), None),
        M::Density(d) => (None, Some(d)),
    };
    ObjectSpec {
        name: name.to_string(),
        kind,
        shape,
        mass_kg,
        density_kg_m3,
        friction: friction_of(kind),
    }
}

fn gen(
    name: &str,
    kind: ObjectKind,
    generator: &str,
    seed: u64,
    p: &[(&str, f64)],
    m: M,
) -> ObjectSpec {
    spec(
        name,
        kind,
        ShapeSpec::Procedural {
            generator: generator.to_string(),
            seed,
            params: params(p),
            scale: 1.0,
        },
        m,
    )
}

fn egad(name: &str, c: u32, d: u32, seed: u64, size: f64) -> ObjectSpec {
    gen(
        name,
        ObjectKind::Egad,
        "egad",
        seed,
        &[
            ("complexity", c as f64),
            ("difficulty", d as f64),
            ("size", size),
        ],
        M::Density(350.0),
    )
}

/// The 61 training objects (see the module docs for the mapping to the paper).
pub fn train_set() -> Vec<ObjectSpec> {
    use ObjectKind::{Primitive as P, ShapenetLike as S, YcbLike as Y};
    let bx = |n: &str, s: [f64; 3], d: f64| spec(n, P, ShapeSpec::Box { size: s }, M::Density(d));
    let mut v = vec![
        bx("box_cracker", [0.16, 0.06, 0.21], 200.0),
        bx("box_sugar", [0.09, 0.045, 0.175], 700.0),
        bx("box_pudding", [0.11, 0.09, 0.035], 550.0),
        bx("box_gelatin", [0.09, 0.07, 0.03], 500.0),
        spec(
            "cylinder_wood",
            P,
            ShapeSpec::Cylinder {
                radius: 0.03,
                height: 0.1,
            },
            M::Density(600.0),
        ),
        // YCB-like, with the YCB objects' masses.
        gen(
            "can_soup",
            Y,
            "can",
            0,
            &[("radius", 0.0335), ("height", 0.102)],
            M::Kg(0.349),
        ),
        gen(
            "can_tuna",
            Y,
            "can",
            0,
            &[("radius", 0.043), ("height", 0.033)],
            M::Kg(0.171),
        ),
        gen(
            "can_chips",
            Y,
            "can",
            0,
            &[("radius", 0.0375), ("height", 0.25)],
            M::Kg(0.205),
        ),
        gen(
            "bottle_mustard",
            Y,
            "bottle",
            0,
            &[
                ("radius", 0.03),
                ("height", 0.19),
                ("neck_radius", 0.011),
                ("neck_height", 0.03),
                ("shoulder", 0.05),
            ],
            M::Kg(0.45),
        ),
        gen(
            "mug",
            Y,
            "mug",
            0,
            &[("radius", 0.04), ("height", 0.08)],
            M::Kg(0.118),
        ),
        gen(
            "bowl",
            Y,
            "vessel",
            0,
            &[
                ("radius_top", 0.058),
                ("radius_bottom", 0.035),
                ("height", 0.055),
                ("wall", 0.006),
                ("curve", 1.0),
            ],
            M::Kg(0.147),
        ),
        gen("banana", Y, "banana", 0, &[], M::Kg(0.066)),
        gen(
            "apple",
            Y,
            "superquadric",
            21,
            &[
                ("rx", 0.037),
                ("ry", 0.037),
                ("rz", 0.035),
                ("bump", 0.04),
                ("bump_freq", 1.5),
            ],
            M::Kg(0.068),
        ),
        gen(
            "lemon",
            Y,
            "superquadric",
            22,
            &[("rx", 0.034), ("ry", 0.026), ("rz", 0.026), ("bump", 0.03)],
            M::Kg(0.06),
        ),
        gen("hammer", Y, "hammer", 0, &[], M::Kg(0.5)),
        gen(
            "cup_stacking",
            Y,
            "vessel",
            0,
            &[
                ("radius_top", 0.04),
                ("radius_bottom", 0.032),
                ("height", 0.07),
                ("wall", 0.003),
                ("curve", 0.0),
            ],
            M::Kg(0.06),
        ),
        // ShapeNet-like, apparent densities.
        gen(
            "bottle_tall",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.035),
                ("height", 0.26),
                ("neck_radius", 0.013),
                ("neck_height", 0.06),
                ("shoulder", 0.05),
            ],
            M::Density(250.0),
        ),
        gen(
            "bottle_wine",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.037),
                ("height", 0.29),
                ("neck_radius", 0.014),
                ("neck_height", 0.08),
                ("shoulder", 0.06),
            ],
            M::Density(300.0),
        ),
        gen(
            "bottle_water",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.032),
                ("height", 0.21),
                ("neck_radius", 0.014),
                ("neck_height", 0.02),
                ("shoulder", 0.04),
                ("waist", 0.15),
            ],
            M::Density(300.0),
        ),
        gen(
            "bottle_flask",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.05),
                ("height", 0.14),
                ("neck_radius", 0.012),
                ("neck_height", 0.03),
                ("shoulder", 0.04),
            ],
            M::Density(250.0),
        ),
        gen(
            "jar_round",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.045),
                ("height", 0.12),
                ("neck_radius", 0.04),
                ("neck_height", 0.02),
                ("shoulder", 0.01),
            ],
            M::Density(350.0),
        ),
        gen(
            "can_soda",
            S,
            "can",
            0,
            &[("radius", 0.033), ("height", 0.122), ("bevel", 0.006)],
            M::Density(800.0),
        ),
        gen(
            "mug_tall",
            S,
            "mug",
            0,
            &[("radius", 0.038), ("height", 0.11), ("handle_reach", 0.03)],
            M::Density(1800.0),
        ),
        gen(
            "mug_short",
            S,
            "mug",
            0,
            &[("radius", 0.045), ("height", 0.07)],
            M::Density(1800.0),
        ),
        gen(
            "bowl_deep",
            S,
            "vessel",
            0,
            &[
                ("radius_top", 0.055),
                ("radius_bottom", 0.038),
                ("height", 0.07),
                ("wall", 0.005),
                ("curve", 0.5),
            ],
            M::Density(1500.0),
        ),
        gen("vase", S, "vase", 5, &[], M::Density(300.0)),
        gen(
            "remote",
            S,
            "superquadric",
            0,
            &[
                ("rx", 0.025),
                ("ry", 0.09),
                ("rz", 0.012),
                ("exponent", 6.0),
            ],
            M::Density(600.0),
        ),
        gen("camera", S, "camera", 0, &[], M::Density(500.0)),
        gen("flashlight", S, "flashlight", 0, &[], M::Density(900.0)),
        gen("teapot", S, "teapot", 0, &[], M::Density(400.0)),
    ];
    for c in 0..=5u32 {
        for d in 0..=4u32 {
            v.push(egad(
                &format!("egad_c{c}_d{d}"),
                c,
                d,
                1000 + 10 * c as u64 + d as u64,
                1.0,
            ));
        }
    }
    v.push(egad("egad_c6_d2", 6, 2, 1062, 1.0));
    v
}

/// The held-out objects: families and sizes absent from [`train_set`].
pub fn unseen_set() -> Vec<ObjectSpec> {
    use ObjectKind::{Primitive as P, ShapenetLike as S, YcbLike as Y};
    vec![
        gen(
            "prism_hex",
            S,
            "prism",
            0,
            &[("sides", 6.0), ("radius", 0.035), ("height", 0.09)],
            M::Density(600.0),
        ),
        gen(
            "prism_tri",
            S,
            "prism",
            0,
            &[("sides", 3.0), ("radius", 0.045), ("height", 0.06)],
            M::Density(600.0),
        ),
        gen("frustum_cone", S, "frustum", 0, &[], M::Density(500.0)),
        gen("star_5", S, "star", 0, &[], M::Density(500.0)),
        gen("torus_ring", S, "torus", 0, &[], M::Density(700.0)),
        gen("dumbbell", S, "dumbbell", 0, &[], M::Density(1500.0)),
        gen("goblet", S, "goblet", 0, &[], M::Density(400.0)),
        gen(
            "block_l",
            S,
            "block",
            0,
            &[("layout", 0.0)],
            M::Density(600.0),
        ),
        gen(
            "block_cross",
            S,
            "block",
            0,
            &[("layout", 2.0), ("arm", 0.045)],
            M::Density(600.0),
        ),
        gen(
            "spatula",
            S,
            "hammer",
            0,
            &[("flat", 1.0), ("head_length", 0.07), ("head_size", 0.035)],
            M::Kg(0.1),
        ),
        gen("egg", Y, "egg", 0, &[], M::Kg(0.06)),
        gen("pear", Y, "pear", 0, &[], M::Kg(0.15)),
        spec(
            "ball_tennis",
            P,
            ShapeSpec::Sphere { radius: 0.033 },
            M::Kg(0.058),
        ),
        spec(
            "capsule_pill",
            P,
            ShapeSpec::Capsule {
                radius: 0.02,
                height: 0.11,
            },
            M::Density(800.0),
        ),
        egad("egad_u1_c1_d3", 1, 3, 9001, 1.1),
        egad("egad_u2_c2_d1", 2, 1, 9002, 0.8),
        egad("egad_u3_c3_d4", 3, 4, 9003, 1.2),
        egad("egad_u4_c5_d0", 5, 0, 9004, 0.9),
        egad("egad_u5_c6_d3", 6, 3, 9005, 1.0),
    ]
}

/// The specs of a built-in set (`train`, `unseen`, `all`).
pub fn builtin_set(name: &str) -> Option<Vec<ObjectSpec>> {
    match name {
        "train" => Some(train_set()),
        "unseen" => Some(unseen_set()),
        "all" => {
            let mut v = train_set();
            v.extend(unseen_set());
            Some(v)
        }
        _ => None,
    }
}

/// The built-in object called `name`.
pub fn builtin_object(name: &str) -> Option<ObjectSpec> {
    builtin_set("all")?.into_iter().find(|s| s.name == name)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, &cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Up to five known names close to `name` (edit distance or substring).
pub fn suggest(name: &str) -> Vec<String> {
    let mut known: Vec<String> = BUILTIN_SETS.iter().map(|s| s.to_string()).collect();
    known.extend(
        builtin_set("all")
            .unwrap_or_default()
            .into_iter()
            .map(|s| s.name),
    );
    let lim = (name.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, String)> = known
        .into_iter()
        .filter_map(|k| {
            let d = levenshtein(name, &k);
            let sub = name.len() >= 3 && (k.contains(name) || name.contains(&k));
            // A misspelt prefix: `bottel` for `bottle_tall`.
            let prefix: String = k.chars().take(name.chars().count()).collect();
            let sub = sub || (name.len() >= 4 && levenshtein(name, &prefix) <= 2);
            (d <= lim || sub).then_some((if sub { d.min(lim) } else { d }, k))
        })
        .collect();
    scored.sort();
    scored.into_iter().take(5).map(|(_, k)| k).collect()
}

fn unknown(name: &str) -> ObjectError {
    let sugg = suggest(name);
    let mut hint = format!(
        "known sets are {}, procedural (or a folder of .obj/.stl files, a manifest .toml, a mesh file, or a comma-separated list of built-in object names; `grasp objects list` shows them)",
        BUILTIN_SETS.join(", ")
    );
    if !sugg.is_empty() {
        hint.push_str(&format!("; did you mean {}?", sugg.join(", ")));
    }
    ObjectError::Unknown {
        name: name.to_string(),
        hint,
    }
}

fn is_mesh_file(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj") || e.eq_ignore_ascii_case("stl"))
}

fn mesh_spec(path: &Path) -> ObjectSpec {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "mesh".into());
    let name: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    ObjectSpec::new(
        name,
        ShapeSpec::Mesh {
            path: path.to_path_buf(),
            scale: 1.0,
        },
    )
}

fn check_unique(specs: &[ResolvedSpec], source: &str) -> Result<(), ObjectError> {
    let mut seen = HashSet::new();
    for s in specs {
        if !seen.insert(s.spec.name.as_str()) {
            return Err(ObjectError::DuplicateName {
                name: s.spec.name.clone(),
                source_name: source.to_string(),
            });
        }
    }
    Ok(())
}

/// Resolves an `--objects` argument (see the module docs) into validated specs.
pub fn resolve_specs(arg: &str) -> Result<Vec<ResolvedSpec>, ObjectError> {
    let arg = arg.trim();
    if arg.is_empty() {
        return Err(unknown(arg));
    }
    let builtin = |s: ObjectSpec| ResolvedSpec {
        spec: s,
        builtin: true,
        source: "built-in".into(),
    };
    if let Some(set) = builtin_set(arg) {
        return Ok(set.into_iter().map(builtin).collect());
    }
    if arg == super::stream::STREAM_SET {
        return Ok(super::stream::stream_specs(0, super::stream::DEFAULT_COUNT));
    }
    let path = Path::new(arg);
    let src = path.display().to_string();
    let looks_like_path = arg.contains('/')
        || arg.contains('\\')
        || is_mesh_file(path)
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if path.is_dir() {
        let entries = std::fs::read_dir(path).map_err(|error| ObjectError::Io {
            path: src.clone(),
            error,
        })?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_mesh_file(p))
            .collect();
        files.sort();
        let specs: Vec<ResolvedSpec> = files
            .iter()
            .map(|f| ResolvedSpec {
                spec: mesh_spec(f),
                builtin: false,
                source: src.clone(),
            })
            .collect();
        if specs.is_empty() {
            return Err(ObjectError::EmptySet {
                source_name: format!("folder {src} (no .obj or .stl files)"),
            });
        }
        check_unique(&specs, &src)?;
        return Ok(specs);
    }
    if path.is_file() {
        if is_mesh_file(path) {
            return Ok(vec![ResolvedSpec {
                spec: mesh_spec(path),
                builtin: false,
                source: src,
            }]);
        }
        let specs: Vec<ResolvedSpec> = load_manifest(path)?
            .into_iter()
            .map(|s| ResolvedSpec {
                spec: s,
                builtin: false,
                source: src.clone(),
            })
            .collect();
        if specs.is_empty() {
            return Err(ObjectError::EmptySet {
                source_name: format!("manifest {src} (no [[object]] tables)"),
            });
        }
        check_unique(&specs, &src)?;
        return Ok(specs);
    }
    if looks_like_path {
        return Err(ObjectError::Io {
            path: src,
            error: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or folder"),
        });
    }
    let all = builtin_set("all").unwrap_or_default();
    let mut out = Vec::new();
    for name in arg.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if BUILTIN_SETS.contains(&name) || name == super::stream::STREAM_SET {
            return Err(ObjectError::SetInList {
                name: name.to_string(),
            });
        }
        if let Some((seed, index)) = super::stream::parse_name(name) {
            out.push(super::stream::stream_spec(seed, index));
            continue;
        }
        let s = all
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| unknown(name))?;
        out.push(builtin(s.clone()));
    }
    if out.is_empty() {
        return Err(unknown(arg));
    }
    check_unique(&out, "the name list")?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn prepared(set: &str) -> Vec<Prepared> {
        resolve_specs(set)
            .unwrap()
            .iter()
            .map(|s| prepare(s).unwrap_or_else(|e| panic!("{e}")))
            .collect()
    }

    #[test]
    fn set_counts_match_the_paper() {
        let train = train_set();
        assert_eq!(train.len(), 61);
        let count = |k: ObjectKind| train.iter().filter(|s| s.kind == k).count();
        assert_eq!(count(ObjectKind::YcbLike), 11);
        assert_eq!(count(ObjectKind::ShapenetLike), 14);
        assert_eq!(count(ObjectKind::Primitive), 5);
        assert_eq!(count(ObjectKind::Egad), 31);
        let boxes = train
            .iter()
            .filter(|s| matches!(s.shape, ShapeSpec::Box { .. }))
            .count();
        let cyl = train
            .iter()
            .filter(|s| matches!(s.shape, ShapeSpec::Cylinder { .. }))
            .count();
        assert_eq!((boxes, cyl), (4, 1));
        let unseen = unseen_set();
        assert!(unseen.len() >= 14);
        let names: HashSet<_> = train.iter().map(|s| s.name.clone()).collect();
        assert!(unseen.iter().all(|s| !names.contains(&s.name)));
        let all = builtin_set("all").unwrap();
        let unique: HashSet<_> = all.iter().map(|s| &s.name).collect();
        assert_eq!(unique.len(), all.len());
    }

    #[test]
    fn unseen_uses_other_families_and_seeds() {
        let family = |s: &ObjectSpec| match &s.shape {
            ShapeSpec::Procedural {
                generator,
                seed,
                params,
                ..
            } => format!("{generator}:{seed}:{params:?}"),
            other => format!("{other:?}"),
        };
        let train: HashSet<String> = train_set().iter().map(family).collect();
        for s in unseen_set() {
            assert!(
                !train.contains(&family(&s)),
                "{} duplicates a train shape",
                s.name
            );
        }
    }

    #[test]
    fn every_builtin_is_watertight_graspable_and_light() {
        for p in prepared("all") {
            let name = &p.spec.spec.name;
            p.mesh.validate(name).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                (0.05..=0.6).contains(&p.mass_kg),
                "{name}: mass {} kg",
                p.mass_kg
            );
            let e = p.mesh.aabb().unwrap().extents();
            let min_xy = e[0].min(e[1]);
            assert!(
                (0.02..=0.12).contains(&min_xy),
                "{name}: narrowest horizontal width {min_xy} m"
            );
            assert!(e.iter().all(|&x| x <= 0.30), "{name}: extents {e:?}");
            assert!(e[2] >= 0.01, "{name}: height {}", e[2]);
            // Object frame: bottom centre of the bounding box at the origin.
            let bb = p.mesh.aabb().unwrap();
            assert!(bb.min[2].abs() < 1e-12, "{name}");
            assert!((bb.min[0] + bb.max[0]).abs() < 1e-9, "{name}");
            assert!((bb.min[1] + bb.max[1]).abs() < 1e-9, "{name}");
            assert!(p.com[2] > 0.0 && p.com[2] < bb.max[2], "{name}");
            assert!((0.5..=1.0).contains(&p.spec.spec.friction), "{name}");
        }
    }

    #[test]
    fn builtins_are_deterministic() {
        let a = prepared("egad_c4_d1,banana,vase");
        let b = prepared("egad_c4_d1,banana,vase");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.mesh, y.mesh);
            assert_eq!(x.mass_kg, y.mass_kg);
        }
    }

    #[test]
    fn primitive_mass_properties_are_exact() {
        let p = &prepared("box_sugar")[0];
        let prim = p.primitive.unwrap();
        assert_relative_eq!(p.volume_m3, 0.09 * 0.045 * 0.175, epsilon = 1e-12);
        assert_relative_eq!(p.mass_kg, 700.0 * p.volume_m3, epsilon = 1e-12);
        assert_relative_eq!(p.com[2], 0.0875, epsilon = 1e-12);
        assert_relative_eq!(
            p.inertia[0][0],
            p.mass_kg * (0.045f64.powi(2) + 0.175f64.powi(2)) / 12.0,
            epsilon = 1e-12
        );
        assert_eq!(prim.half_height_total(), 0.0875);
    }

    #[test]
    fn resolver_errors_are_helpful() {
        let e = resolve_specs("trian").unwrap_err().to_string();
        assert!(
            e.contains("train, unseen, all") && e.contains("did you mean train"),
            "{e}"
        );
        let e = resolve_specs("bottle_tal,mug").unwrap_err().to_string();
        assert!(e.contains("bottle_tall"), "{e}");
        let e = resolve_specs("no/such/dir").unwrap_err().to_string();
        assert!(e.contains("no/such/dir"), "{e}");
        let e = resolve_specs("mug,mug").unwrap_err().to_string();
        assert!(e.contains("duplicate"), "{e}");
        assert_eq!(resolve_specs("mug, banana").unwrap().len(), 2);
    }

    #[test]
    fn levenshtein_distance() {
        assert_eq!(levenshtein("kitten", "sitting"), 3);
        assert_eq!(levenshtein("", "abc"), 3);
        assert_eq!(levenshtein("mug", "mug"), 0);
    }

    #[test]
    fn vhacd_cache_is_reused_and_rebuilt_when_stale_or_corrupt() {
        use crate::objects::CacheStatus;
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        let spec = &resolve_specs("bottle_water").unwrap()[0];
        let file = dir.path().join("hulls/bottle_water.hulls.json");
        let a = build(spec, &ctx).unwrap();
        assert_eq!(a.hull_source, HullSource::Vhacd(CacheStatus::Built));
        assert!(file.is_file());
        let b = build(spec, &ctx).unwrap();
        assert_eq!(b.hull_source, HullSource::Vhacd(CacheStatus::Hit));
        assert_eq!(a.hulls, b.hulls);
        // Corrupt file: rebuilt, same result (VHACD is deterministic), file repaired.
        std::fs::write(&file, b"{ this is not json").unwrap();
        let c = build(spec, &ctx).unwrap();
        assert_eq!(c.hull_source, HullSource::Vhacd(CacheStatus::Rebuilt));
        assert_eq!(a.hulls, c.hulls);
        assert_eq!(
            build(spec, &ctx).unwrap().hull_source,
            HullSource::Vhacd(CacheStatus::Hit)
        );
        // Stale file (other parameters): rebuilt.
        let ctx2 = BuildContext {
            decomp: DecompParams {
                max_hulls: 4,
                ..ctx.decomp
            },
            ..ctx.clone()
        };
        let d = build(spec, &ctx2).unwrap();
        assert_eq!(d.hull_source, HullSource::Vhacd(CacheStatus::Rebuilt));
        assert!(d.hulls.len() <= 4);
    }

    #[test]
    fn vhacd_hulls_cover_the_object() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        for name in ["bottle_tall", "egad_c5_d2", "vase"] {
            let o = build(&resolve_specs(name).unwrap()[0], &ctx).unwrap();
            assert!(matches!(o.hull_source, HullSource::Vhacd(_)), "{name}");
            assert!(o.hulls.len() <= ctx.decomp.max_hulls as usize, "{name}");
            let hull_vol: f64 = o
                .hulls
                .iter()
                .map(|h| h.mesh().unwrap().signed_volume())
                .sum();
            let ratio = hull_vol / o.volume_m3;
            assert!(
                (0.9..1.35).contains(&ratio),
                "{name}: hull/mesh volume {ratio}"
            );
            let pts: Vec<[f64; 3]> = o.hulls.iter().flat_map(|h| h.points.clone()).collect();
            let hb = crate::objects::Aabb::of_points(&pts).unwrap();
            for k in 0..3 {
                assert!((hb.min[k] - o.bbox.min[k]).abs() < 0.006, "{name} {hb:?}");
                assert!((hb.max[k] - o.bbox.max[k]).abs() < 0.006, "{name} {hb:?}");
            }
        }
    }

    #[test]
    fn shared_shapes_match_the_object() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        for name in [
            "cylinder_wood",
            "capsule_pill",
            "mug",
            "egad_c0_d0",
            "box_gelatin",
        ] {
            let o = build(&resolve_specs(name).unwrap()[0], &ctx).unwrap();
            let shape = o.to_shared_shape().unwrap();
            let aabb = shape.compute_local_aabb();
            let (lo, hi) = (aabb.mins, aabb.maxs);
            let got = [[lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]];
            for k in 0..3 {
                assert!(
                    (got[0][k] as f64 - o.bbox.min[k]).abs() < 2e-3,
                    "{name} {got:?} {:?}",
                    o.bbox
                );
                assert!(
                    (got[1][k] as f64 - o.bbox.max[k]).abs() < 2e-3,
                    "{name} {got:?} {:?}",
                    o.bbox
                );
            }
            let d = o.collider_desc();
            assert_eq!(d.hulls.len(), o.hulls.len());
            assert_eq!(d.primitive.is_some(), o.primitive.is_some());
            assert_eq!(d.mass_kg, o.mass_kg);
        }
    }

    #[test]
    fn user_mesh_folder_and_manifest() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/objects");
        let dir = tempfile::tempdir().unwrap();
        for f in ["cube.obj", "cube_ascii.stl", "l_block.obj"] {
            std::fs::copy(data.join(f), dir.path().join(f)).unwrap();
        }
        let ctx = BuildContext::with_cache_dir(dir.path().join("cache"));
        let objs = load_objects(&dir.path().display().to_string(), &ctx).unwrap();
        let names: Vec<&str> = objs.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["cube", "cube_ascii", "l_block"]);
        let cube = &objs[0];
        assert_relative_eq!(
            cube.mass_kg,
            0.05f64.powi(3) * super::super::spec::DEFAULT_DENSITY,
            max_relative = 1e-6
        );
        assert_eq!(cube.hull_source, HullSource::Convex);
        assert_relative_eq!(cube.com[2], 0.025, epsilon = 1e-9);
        assert!(matches!(objs[2].hull_source, HullSource::Vhacd(_)));
        assert!(dir.path().join("l_block.obj.hulls.json").is_file());

        let manifest = dir.path().join("set.toml");
        std::fs::write(
            &manifest,
            "[[object]]\nname = \"small\"\nshape = { type = \"mesh\", path = \"cube.obj\", scale = 0.5 }\nmass_kg = 0.2\nfriction = 0.3\n\
             [[object]]\nname = \"b3\"\nshape = { type = \"procedural\", generator = \"bottle\", seed = 3 }\n",
        )
        .unwrap();
        let objs = load_objects(&manifest.display().to_string(), &ctx).unwrap();
        assert_eq!(objs.len(), 2);
        assert_relative_eq!(objs[0].size()[0], 0.025, epsilon = 1e-9);
        assert_eq!(objs[0].mass_kg, 0.2);
        assert_eq!(objs[0].friction, 0.3);
        assert_eq!(objs[1].kind, ObjectKind::User);
    }
}
