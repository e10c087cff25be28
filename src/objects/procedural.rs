//! Procedural shapes, deterministic from a seed ([`ChaCha8Rng`]), watertight by
//! construction, in metres.
//!
//! Four constructions keep every mesh closed:
//!
//! - **surfaces of revolution** ([`revolve`]): a profile `(r, z)` that starts and ends on
//!   the axis (`r = 0`), revolved into rings joined by quads and closed by two fans
//!   (bottles, cans, bowls, vases...);
//! - **radial meshes** ([`radial_mesh`]): a subdivided icosahedron whose vertices move along
//!   their own direction to a positive radius `r(direction)`; the result is star-shaped
//!   and cannot self-intersect (EGAD-like shapes, fruit, superquadrics);
//! - **swept tubes** ([`sweep`]): rings along a curve, closed by cones or into a loop
//!   (bananas, rings);
//! - **assemblies of convex parts** ([`Assembly`]): each part is the convex hull of a few
//!   points, a closed mesh of its own; the parts double as the collision hulls (mugs,
//!   hammers, cameras...).
//!
//! Each generator ([`GENERATORS`]) declares its parameters with defaults and ranges; a
//! spec may override any of them by name ([`generate`]). Unknown names, values outside the
//! range and inconsistent combinations are errors naming the parameter.

use super::mesh::TriMesh;
use super::shape_kit::{
    add, box_points, cylinder_points, dot, lerp, mesh_only, mul, radial_mesh, revolve, ring_parts,
    sweep, unit_vector, Assembly, Generated, Params,
};
use super::{convex_hull_mesh, ConvexHull, ObjectError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::{BTreeMap, HashMap};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// One generator parameter: name, default, inclusive range and meaning.
#[derive(Debug, Clone, Copy)]
pub struct ParamDef {
    /// Parameter name as written in a spec's `params` table.
    pub name: &'static str,
    /// Value used when the spec does not set it.
    pub default: f64,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// Meaning and unit.
    pub doc: &'static str,
}

pub(super) type BuildFn = fn(&mut ChaCha8Rng, &Params) -> Result<Generated, String>;

/// A named generator with its parameters.
#[derive(Clone, Copy)]
pub struct GeneratorDef {
    /// Name used in `generator = "..."`.
    pub name: &'static str,
    /// What it makes.
    pub doc: &'static str,
    /// Its parameters.
    pub params: &'static [ParamDef],
    build: BuildFn,
}

impl std::fmt::Debug for GeneratorDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeneratorDef")
            .field("name", &self.name)
            .finish()
    }
}

const fn p(name: &'static str, default: f64, min: f64, max: f64, doc: &'static str) -> ParamDef {
    ParamDef {
        name,
        default,
        min,
        max,
        doc,
    }
}

// The catalogue of generators, each with its parameters, is in generators.rs.
mod generators;
pub use generators::GENERATORS;

/// Looks a generator up by name.
pub fn find_generator(name: &str) -> Option<&'static GeneratorDef> {
    GENERATORS.iter().find(|g| g.name == name)
}

/// Runs generator `generator` with `seed` and the parameter overrides `params`. `object`
/// and `source` (manifest or "built-in") name the object in errors.
pub fn generate(
    generator: &str,
    seed: u64,
    params: &BTreeMap<String, f64>,
    object: &str,
    source: &str,
) -> Result<Generated, ObjectError> {
    let err = |field: String, message: String| ObjectError::InvalidSpec {
        source_name: source.to_string(),
        object: object.to_string(),
        field,
        message,
    };
    let def = find_generator(generator).ok_or_else(|| {
        let known: Vec<_> = GENERATORS.iter().map(|g| g.name).collect();
        err(
            "shape.generator".into(),
            format!(
                "unknown generator `{generator}`; known: {}",
                known.join(", ")
            ),
        )
    })?;
    let mut values: HashMap<&'static str, f64> =
        def.params.iter().map(|pd| (pd.name, pd.default)).collect();
    for (k, &v) in params {
        let pd = def.params.iter().find(|pd| pd.name == k).ok_or_else(|| {
            let known: Vec<_> = def.params.iter().map(|pd| pd.name).collect();
            err(
                format!("shape.params.{k}"),
                format!(
                    "unknown parameter for generator `{}`; known: {}",
                    def.name,
                    known.join(", ")
                ),
            )
        })?;
        if !v.is_finite() || v < pd.min || v > pd.max {
            return Err(err(
                format!("shape.params.{k}"),
                format!(
                    "{} is outside {}..={} ({})",
                    crate::util::num::short(v),
                    pd.min,
                    pd.max,
                    pd.doc
                ),
            ));
        }
        values.insert(pd.name, v);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (def.build)(&mut rng, &Params::new(values)).map_err(|m| {
        err(
            "shape.params".into(),
            format!("generator `{}`: {m}", def.name),
        )
    })
}

// ---------------------------------------------------------------------------------------
// Generators

/// Ray from the origin along unit `d` to the ellipsoid centred at `o` with semi-axes `a`
/// (which must contain the origin): the positive root of |(t d - o) / a|^2 = 1.
fn ellipsoid_ray(d: [f64; 3], o: [f64; 3], a: [f64; 3]) -> f64 {
    let mut qa = 0.0;
    let mut qb = 0.0;
    let mut qc = -1.0;
    for k in 0..3 {
        let ia = 1.0 / (a[k] * a[k]);
        qa += d[k] * d[k] * ia;
        qb += d[k] * o[k] * ia;
        qc += o[k] * o[k] * ia;
    }
    (qb + (qb * qb - qa * qc).max(0.0).sqrt()) / qa
}

/// Distance along unit `d` to the superellipsoid with semi-axes `a` and exponent `e`.
fn superquadric_ray(d: [f64; 3], a: [f64; 3], e: f64) -> f64 {
    let s: f64 = (0..3).map(|k| (d[k].abs() / a[k]).powf(e)).sum();
    s.powf(-1.0 / e)
}

/// Smooth seeded noise on the sphere: a sum of `terms` plane waves.
struct SphereNoise {
    waves: Vec<([f64; 3], f64, f64, f64)>,
}

impl SphereNoise {
    fn new(rng: &mut ChaCha8Rng, terms: usize, total_amp: f64, freq: f64) -> Self {
        let weights: Vec<f64> = (0..terms).map(|_| rng.random_range(0.5..1.0)).collect();
        let wsum: f64 = weights.iter().sum::<f64>().max(1e-12);
        let waves = weights
            .iter()
            .map(|w| {
                let u = unit_vector(rng);
                let f = freq * rng.random_range(0.8..1.25);
                let phase = rng.random_range(0.0..TAU);
                (u, total_amp * w / wsum, f, phase)
            })
            .collect();
        SphereNoise { waves }
    }

    /// A value in [-total_amp, total_amp].
    fn at(&self, d: [f64; 3]) -> f64 {
        self.waves
            .iter()
            .map(|(u, a, f, ph)| a * (f * PI * dot(*u, d) + ph).sin())
            .sum()
    }
}

fn build_egad(rng: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let c = p.get("complexity").round();
    let d = p.get("difficulty");
    let r0 = (0.042 - 0.0045 * d) * p.get("size");
    let aspect = [
        (1.0 + 0.35 * d) * rng.random_range(0.92..1.08),
        (1.0 - 0.06 * d) * rng.random_range(0.92..1.08),
        (1.0 - 0.1 * d) * rng.random_range(0.92..1.08),
    ];
    let exponent = 2.0 + rng.random_range(0.0..=0.4 * c);
    let lobes: Vec<([f64; 3], [f64; 3])> = (0..(c as usize) / 2)
        .map(|_| {
            let o = mul(unit_vector(rng), 0.4 * r0);
            let a = [
                rng.random_range(0.5..0.85) * r0,
                rng.random_range(0.5..0.85) * r0,
                rng.random_range(0.5..0.85) * r0,
            ];
            (o, a)
        })
        .collect();
    let noise = SphereNoise::new(rng, c as usize, 0.035 * c, 1.0 + 0.6 * c);
    let level = if c <= 3.0 { 3 } else { 4 };
    let mut m = radial_mesh(level, |dir| {
        let mut r = superquadric_ray(dir, [r0, r0, r0], exponent);
        for (o, a) in &lobes {
            r = r.max(ellipsoid_ray(dir, *o, *a));
        }
        r * (1.0 + noise.at(dir))
    })?;
    m.scale(aspect);
    Ok(mesh_only(m))
}

fn build_superquadric(rng: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let a = [p.get("rx"), p.get("ry"), p.get("rz")];
    let e = p.get("exponent");
    let noise = SphereNoise::new(rng, 3, p.get("bump"), p.get("bump_freq"));
    let m = radial_mesh(3, |d| superquadric_ray(d, a, e) * (1.0 + noise.at(d)))?;
    Ok(mesh_only(m))
}

fn build_can(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h, b) = (p.get("radius"), p.get("height"), p.get("bevel"));
    if 2.0 * b >= h.min(r) {
        return Err("bevel must be smaller than half the radius and half the height".into());
    }
    let prof = [
        [0.0, 0.0],
        [r - b, 0.0],
        [r, b],
        [r, h - b],
        [r - b, h],
        [0.0, h],
    ];
    Ok(mesh_only(revolve(&dedup(&prof), 48)?))
}

/// Drops consecutive duplicate profile points (a zero bevel).
fn dedup(prof: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(prof.len());
    for q in prof {
        if out.last() != Some(q) {
            out.push(*q);
        }
    }
    out
}

fn build_bottle(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h) = (p.get("radius"), p.get("height"));
    let (nr, nh, sh) = (
        p.get("neck_radius"),
        p.get("neck_height"),
        p.get("shoulder"),
    );
    let waist = p.get("waist");
    if nr >= r {
        return Err("neck_radius must be smaller than radius".into());
    }
    let b = 0.003_f64.min(0.2 * r);
    let lip = 0.004_f64.min(0.3 * nh);
    let body_top = h - nh - sh;
    if body_top < 4.0 * b {
        return Err("neck_height + shoulder leave no room for the body (raise height)".into());
    }
    let mut prof = vec![[0.0, 0.0], [r - b, 0.0]];
    let nb = 8;
    for i in 0..=nb {
        let t = i as f64 / nb as f64;
        let z = lerp(b, body_top, t);
        prof.push([r * (1.0 - waist * (PI * t).sin().powi(2)), z]);
    }
    let ns = 8;
    for i in 1..=ns {
        let t = i as f64 / ns as f64;
        prof.push([
            nr + (r - nr) * 0.5 * (1.0 + (PI * t).cos()),
            body_top + sh * t,
        ]);
    }
    let lip_r = (nr * 1.15).min(r);
    prof.extend_from_slice(&[
        [nr, h - lip],
        [lip_r, h - lip],
        [lip_r, h - 0.2 * lip],
        [0.8 * lip_r, h],
        [0.0, h],
    ]);
    Ok(mesh_only(revolve(&dedup(&prof), 40)?))
}

/// Outer radius of a vessel at relative height `t`.
fn vessel_radius(rb: f64, rt: f64, curve: f64, t: f64) -> f64 {
    rb + (rt - rb) * ((1.0 - curve) * t + curve * (1.0 - (1.0 - t) * (1.0 - t)))
}

/// A thick-walled vessel: the closed revolution mesh and convex wall-sector parts.
fn vessel(
    rb: f64,
    rt: f64,
    h: f64,
    wall: f64,
    curve: f64,
) -> Result<(TriMesh, Vec<ConvexHull>), String> {
    if wall >= 0.7 * rb.min(rt) || wall >= 0.5 * h {
        return Err("wall is too thick for the radius or the height".into());
    }
    let rad = |z: f64| vessel_radius(rb, rt, curve, z / h);
    let n = 12;
    let mut prof = vec![[0.0, 0.0]];
    for i in 0..=n {
        let z = h * i as f64 / n as f64;
        prof.push([rad(z), z]);
    }
    for i in (0..=n).rev() {
        let z = lerp(wall, h, i as f64 / n as f64);
        prof.push([rad(z) - wall, z]);
    }
    prof.push([0.0, wall]);
    let mesh = revolve(&prof, 48)?;
    // Collision: floor disc plus wall sectors (outer arc, inner chord) in height bands.
    let mut parts = Vec::new();
    let floor: Vec<[f64; 3]> = (0..24)
        .flat_map(|j| {
            let a = TAU * j as f64 / 24.0;
            [
                [rad(0.0) * a.cos(), rad(0.0) * a.sin(), 0.0],
                [
                    (rad(wall) - wall) * a.cos(),
                    (rad(wall) - wall) * a.sin(),
                    wall,
                ],
            ]
        })
        .collect();
    parts.push(ConvexHull::from_points(&floor).ok_or("vessel floor has no hull")?);
    let (sectors, bands) = if curve < 0.3 { (10, 1) } else { (7, 2) };
    for band in 0..bands {
        let z0 = h * band as f64 / bands as f64;
        let z1 = h * (band + 1) as f64 / bands as f64;
        for s in 0..sectors {
            let a0 = TAU * s as f64 / sectors as f64;
            let a1 = TAU * (s + 1) as f64 / sectors as f64;
            let mut pts = Vec::new();
            for z in [z0, z1] {
                let ro = rad(z);
                let ri = (rad(z.max(wall)) - wall).max(0.0);
                for k in 0..=4 {
                    let a = lerp(a0, a1, k as f64 / 4.0);
                    pts.push([ro * a.cos(), ro * a.sin(), z]);
                }
                for a in [a0, a1] {
                    pts.push([ri * a.cos(), ri * a.sin(), z]);
                }
            }
            parts.push(ConvexHull::from_points(&pts).ok_or("vessel sector has no hull")?);
        }
    }
    Ok((mesh, parts))
}

fn build_vessel(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (mesh, parts) = vessel(
        p.get("radius_bottom"),
        p.get("radius_top"),
        p.get("height"),
        p.get("wall"),
        p.get("curve"),
    )?;
    Ok(Generated {
        mesh,
        parts: Some(parts),
    })
}

/// A D-shaped handle on the +x side of a body of radius `r` spanning `z0..z1`.
fn add_handle(
    asm: &mut Assembly,
    r: f64,
    z0: f64,
    z1: f64,
    reach: f64,
    thick: f64,
) -> Result<(), String> {
    let zc = 0.5 * (z0 + z1);
    let hz = 0.5 * (z1 - z0);
    let k = 7;
    let centres: Vec<[f64; 3]> = (0..=k)
        .map(|i| {
            let phi = -FRAC_PI_2 + PI * i as f64 / k as f64;
            [
                r - 0.5 * thick + reach * phi.cos(),
                0.0,
                zc + hz * phi.sin(),
            ]
        })
        .collect();
    let radii = vec![thick; centres.len()];
    let (_, rings) = sweep(&centres, &radii, 10, [0.0, 1.0, 0.0], false, 0.0)?;
    for i in 0..k {
        let pts: Vec<[f64; 3]> = rings[i]
            .iter()
            .chain(rings[i + 1].iter())
            .copied()
            .collect();
        asm.add(&pts)?;
    }
    Ok(())
}

fn build_mug(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h, wall) = (p.get("radius"), p.get("height"), p.get("wall"));
    let (body, parts) = vessel(0.95 * r, r, h, wall, 0.0)?;
    let mut asm = Assembly::new();
    asm.add_with_parts(&body, parts);
    let thick = p.get("handle_thickness");
    add_handle(&mut asm, r, 0.2 * h, 0.85 * h, p.get("handle_reach"), thick)?;
    Ok(asm.finish())
}

fn build_banana(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (len, rad, bend) = (p.get("length"), p.get("radius"), p.get("bend"));
    let rc = len / (2.0 * (bend / 2.0).sin());
    let n = 13;
    let mut centres = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    for i in 0..n {
        let s = i as f64 / (n - 1) as f64;
        let th = lerp(-bend / 2.0, bend / 2.0, s);
        centres.push([rc * th.sin(), rc * th.cos(), rad]);
        radii.push(rad * (0.35 + 0.65 * (PI * s).sin().sqrt()));
    }
    let (mesh, rings) = sweep(&centres, &radii, 14, [0.0, 0.0, 1.0], false, 0.8)?;
    let parts = ring_parts(&rings, false, 12)?;
    Ok(Generated {
        mesh,
        parts: Some(parts),
    })
}

fn build_hammer(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (hl, hr) = (p.get("handle_length"), p.get("handle_radius"));
    let (head_l, hs) = (p.get("head_length"), p.get("head_size"));
    let flat = p.get("flat") >= 0.5;
    let mut asm = Assembly::new();
    // Head across y at x in [0, hs]; handle along +x from the head.
    let head_h = if flat {
        [hs, 0.5 * head_l, 0.004]
    } else {
        [0.5 * hs, 0.5 * head_l, 0.5 * hs]
    };
    let zc = head_h[2].max(hr);
    let head_c = if flat {
        [-hs, 0.0, zc]
    } else {
        [0.5 * hs, 0.0, zc]
    };
    asm.add(&box_points(head_c, head_h))?;
    let x0 = if flat { 0.0 } else { hs };
    asm.add(&cylinder_points([x0, 0.0, zc], [x0 + hl, 0.0, zc], hr, 16))?;
    Ok(asm.finish())
}

fn build_vase(rng: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h) = (p.get("radius"), p.get("height"));
    let (waves, amp, neck) = (p.get("waves"), p.get("amplitude"), p.get("neck"));
    let phase = rng.random_range(0.0..TAU);
    let n = 24;
    let mut prof = vec![[0.0, 0.0]];
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let rr = r * (1.0 + amp * (TAU * waves * t + phase).sin()) * lerp(1.0, neck, t * t);
        prof.push([rr.max(0.2 * r), h * t]);
    }
    prof.push([0.0, h]);
    Ok(mesh_only(revolve(&prof, 40)?))
}

fn build_camera(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (w, d, h) = (p.get("width"), p.get("depth"), p.get("height"));
    let (lr, ll) = (p.get("lens_radius"), p.get("lens_length"));
    if 2.0 * lr >= h.min(w) {
        return Err("lens_radius must be below half the body height and width".into());
    }
    let mut asm = Assembly::new();
    asm.add(&box_points(
        [0.0, 0.0, 0.5 * h],
        [0.5 * w, 0.5 * d, 0.5 * h],
    ))?;
    let zc = 0.45 * h;
    asm.add(&cylinder_points(
        [0.0, -0.5 * d, zc],
        [0.0, -0.5 * d - ll, zc],
        lr,
        20,
    ))?;
    let vf = [0.15 * w, 0.3 * d, 0.08 * h];
    asm.add(&box_points([0.0, 0.0, h + vf[2]], vf))?;
    Ok(asm.finish())
}

fn build_teapot(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h) = (p.get("radius"), p.get("height"));
    let mut asm = Assembly::new();
    // Body: hull of a flattened sphere with a flat base and a flat top.
    let n = 12;
    let mut body = Vec::new();
    for i in 0..=n {
        let z = h * i as f64 / n as f64;
        let t = 2.0 * z / h - 1.0;
        let rr = (r * (1.0 - 0.85 * t * t).sqrt()).max(0.35 * r);
        for j in 0..32 {
            let a = TAU * j as f64 / 32.0;
            body.push([rr * a.cos(), rr * a.sin(), z]);
        }
    }
    asm.add(&body)?;
    // Lid knob.
    asm.add(&cylinder_points(
        [0.0, 0.0, h],
        [0.0, 0.0, h + 0.012],
        0.012,
        12,
    ))?;
    // Spout: a tapered tube rising at 45 degrees on -x.
    let base = [-0.75 * r, 0.0, 0.35 * h];
    let tip = [-(r + 0.5 * h * 0.45), 0.0, 0.85 * h];
    let mut spout = cylinder_points(base, tip, 0.012, 12);
    let tip_ring = cylinder_points(tip, add(tip, [-0.001, 0.0, 0.001]), 0.007, 12);
    spout.truncate(12);
    spout.extend_from_slice(&tip_ring[..12]);
    asm.add(&spout)?;
    add_handle(&mut asm, 0.9 * r, 0.3 * h, 0.85 * h, 0.035, 0.007)?;
    Ok(asm.finish())
}

fn build_flashlight(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, len, hr, hl) = (
        p.get("radius"),
        p.get("length"),
        p.get("head_radius"),
        p.get("head_length"),
    );
    if hl >= 0.6 * len {
        return Err("head_length must be below 60 % of length".into());
    }
    let b = 0.002_f64.min(0.2 * r);
    let flare = 0.3 * hl;
    let prof = [
        [0.0, 0.0],
        [r - b, 0.0],
        [r, b],
        [r, len - hl - flare],
        [hr, len - hl],
        [hr, len - b],
        [hr - b, len],
        [0.0, len],
    ];
    Ok(mesh_only(revolve(&dedup(&prof), 32)?))
}

fn build_prism(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let n = p.get("sides").round() as usize;
    let (r, h) = (p.get("radius"), p.get("height"));
    let pts: Vec<[f64; 3]> = (0..n)
        .flat_map(|j| {
            let a = TAU * j as f64 / n as f64;
            [
                [r * a.cos(), r * a.sin(), 0.0],
                [r * a.cos(), r * a.sin(), h],
            ]
        })
        .collect();
    let m = convex_hull_mesh(&pts).ok_or("prism has no hull")?;
    Ok(mesh_only(m))
}

fn build_star(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let n = p.get("points").round() as usize;
    let (ro, ri, h) = (p.get("outer"), p.get("inner"), p.get("height"));
    if ri >= 0.9 * ro {
        return Err("inner must be below 90 % of outer".into());
    }
    let at = |rad: f64, a: f64, z: f64| [rad * a.cos(), rad * a.sin(), z];
    let mut asm = Assembly::new();
    let core: Vec<[f64; 3]> = (0..n)
        .flat_map(|k| {
            let a = TAU * (k as f64 + 0.5) / n as f64;
            [at(ri, a, 0.0), at(ri, a, h)]
        })
        .collect();
    asm.add(&core)?;
    for k in 0..n {
        let a0 = TAU * (k as f64 - 0.5) / n as f64;
        let a1 = TAU * (k as f64 + 0.5) / n as f64;
        let tip = TAU * k as f64 / n as f64;
        let mut pts = Vec::new();
        for z in [0.0, h] {
            pts.push(at(ri, a0, z));
            pts.push(at(ri, a1, z));
            pts.push(at(ro, tip, z));
        }
        asm.add(&pts)?;
    }
    Ok(asm.finish())
}

fn build_torus(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (big, small) = (p.get("major"), p.get("minor"));
    if small >= 0.8 * big {
        return Err("minor must be below 80 % of major".into());
    }
    let n = 24;
    let centres: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let a = TAU * i as f64 / n as f64;
            [big * a.cos(), big * a.sin(), small]
        })
        .collect();
    let radii = vec![small; n];
    let (mesh, rings) = sweep(&centres, &radii, 12, [0.0, 0.0, 1.0], true, 0.0)?;
    let parts = ring_parts(&rings, true, 12)?;
    Ok(Generated {
        mesh,
        parts: Some(parts),
    })
}

fn build_egg(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, len, k) = (p.get("radius"), p.get("length"), p.get("pointiness"));
    let n = 24;
    let mut prof = vec![[0.0, 0.0]];
    for i in 1..n {
        let th = PI * i as f64 / n as f64;
        let z = 0.5 * len * (1.0 - th.cos());
        prof.push([r * th.sin() * (1.0 + k * th.cos()) / (1.0 + k * 0.3), z]);
    }
    prof.push([0.0, len]);
    let mut m = revolve(&prof, 32)?;
    // Lay it on its side: z -> x.
    for v in &mut m.vertices {
        *v = [v[2], v[1], -v[0]];
    }
    Ok(mesh_only(m))
}

fn build_pear(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (r, h, neck) = (p.get("radius"), p.get("height"), p.get("neck"));
    let n = 24;
    let mut prof = vec![[0.0, 0.0], [0.45 * r, 0.0]];
    for i in 1..n {
        let t = i as f64 / n as f64;
        let z = h * t;
        // Body sphere in the lower half blending into a narrower top lobe.
        let body = r * (1.0 - ((t - 0.32) / 0.34).powi(2)).max(0.0).sqrt();
        let top_r = neck * r;
        let top = top_r * (1.0 - ((t - 0.78) / 0.24).powi(2)).max(0.0).sqrt();
        let rr = body.max(top).max(0.45 * r * (1.0 - t / 0.1).max(0.0));
        prof.push([rr.max(0.1 * r), z]);
    }
    prof.push([0.0, h]);
    Ok(mesh_only(revolve(&prof, 32)?))
}

fn build_dumbbell(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (er, el, br, len) = (
        p.get("end_radius"),
        p.get("end_length"),
        p.get("bar_radius"),
        p.get("length"),
    );
    if br >= er || 2.0 * el >= 0.8 * len {
        return Err("bar_radius must be below end_radius and the ends shorter than the bar".into());
    }
    let mut asm = Assembly::new();
    asm.add(&cylinder_points([0.0, 0.0, 0.0], [0.0, 0.0, el], er, 24))?;
    asm.add(&cylinder_points(
        [0.0, 0.0, el],
        [0.0, 0.0, len - el],
        br,
        16,
    ))?;
    asm.add(&cylinder_points(
        [0.0, 0.0, len - el],
        [0.0, 0.0, len],
        er,
        24,
    ))?;
    Ok(asm.finish())
}

fn build_goblet(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (cr, h, sr) = (p.get("cup_radius"), p.get("height"), p.get("stem_radius"));
    let foot = 0.9 * cr;
    let stem_top = 0.4 * h;
    let mut prof = vec![
        [0.0, 0.0],
        [foot, 0.0],
        [foot, 0.004],
        [sr * 1.5, 0.012],
        [sr, 0.02],
        [sr, stem_top],
    ];
    let n = 12;
    for i in 1..=n {
        let t = i as f64 / n as f64;
        let rr = cr * (1.0 - (1.0 - t).powi(2)).sqrt().max(sr / cr);
        prof.push([rr, lerp(stem_top, h, t)]);
    }
    prof.push([0.0, h]);
    Ok(mesh_only(revolve(&prof, 32)?))
}

fn build_frustum(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let (rb, rt, h) = (p.get("radius_bottom"), p.get("radius_top"), p.get("height"));
    Ok(mesh_only(revolve(
        &[[0.0, 0.0], [rb, 0.0], [rt, h], [0.0, h]],
        40,
    )?))
}

fn build_block(_: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let layout = p.get("layout").round() as u32;
    let (arm, th, h) = (p.get("arm"), p.get("thickness"), p.get("height"));
    if th >= arm {
        return Err("thickness must be below arm".into());
    }
    let t2 = 0.5 * th;
    let hz = 0.5 * h;
    let mut asm = Assembly::new();
    // Centre square, then arms that touch it face to face.
    asm.add(&box_points([0.0, 0.0, hz], [t2, t2, hz]))?;
    let arm_h = 0.5 * (arm - t2);
    let arm_c = t2 + arm_h;
    let dirs: &[[f64; 2]] = match layout {
        0 => &[[1.0, 0.0], [0.0, 1.0]],
        1 => &[[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]],
        _ => &[[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]],
    };
    for d in dirs {
        let c = [d[0] * arm_c, d[1] * arm_c, hz];
        let half = [
            if d[0] != 0.0 { arm_h } else { t2 },
            if d[1] != 0.0 { arm_h } else { t2 },
            hz,
        ];
        asm.add(&box_points(c, half))?;
    }
    Ok(asm.finish())
}

#[cfg(test)]
mod tests;
