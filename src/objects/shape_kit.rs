//! The building blocks of the procedural shapes ([`super::procedural`],
//! [`super::random_shapes`]): what a generator returns ([`Generated`]), its resolved
//! parameters ([`Params`]), the four watertight constructions ([`revolve`], [`radial_mesh`],
//! [`sweep`], [`Assembly`]) with boxes, icospheres and convex part points, and small
//! vector helpers on `[f64; 3]`.

use super::mesh::TriMesh;
use super::{convex_hull_mesh, ConvexHull};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;
use std::f64::consts::TAU;

/// The output of a generator: the visual mesh (one or more closed components) and, for
/// assemblies, the convex parts to use as collision hulls.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The visual mesh, outward oriented.
    pub mesh: TriMesh,
    /// Convex collision parts, when the generator knows them.
    pub parts: Option<Vec<ConvexHull>>,
}

/// Resolved parameter values of one generator call.
#[derive(Debug, Clone)]
pub struct Params {
    values: HashMap<&'static str, f64>,
}

impl Params {
    /// The resolved values of one call.
    pub(crate) fn new(values: HashMap<&'static str, f64>) -> Self {
        Params { values }
    }

    /// The value of `name` (NaN, rejected later by mesh validation, if the generator did
    /// not declare it).
    pub fn get(&self, name: &str) -> f64 {
        self.values.get(name).copied().unwrap_or(f64::NAN)
    }
}

// ---------------------------------------------------------------------------------------
// Vector helpers

pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn mul(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 {
        mul(a, 1.0 / n)
    } else {
        a
    }
}

/// A random unit vector (rejection sampling in the unit ball).
pub(crate) fn unit_vector(rng: &mut ChaCha8Rng) -> [f64; 3] {
    loop {
        let v = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let n2 = dot(v, v);
        if n2 > 1e-4 && n2 <= 1.0 {
            return mul(v, 1.0 / n2.sqrt());
        }
    }
}

/// A box centred at the origin with half extents `h`, outward oriented.
pub fn box_mesh(h: [f64; 3]) -> TriMesh {
    let mut v = Vec::with_capacity(8);
    for k in 0..8 {
        v.push([
            if k & 1 == 0 { -h[0] } else { h[0] },
            if k & 2 == 0 { -h[1] } else { h[1] },
            if k & 4 == 0 { -h[2] } else { h[2] },
        ]);
    }
    let t = vec![
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
    ];
    let mut m = TriMesh::new(v, t);
    m.orient_outward();
    m
}

/// The solid of revolution of `profile` (pairs `(r, z)`) about the z axis with `segments`
/// sides. The profile must start and end on the axis (`r = 0`) with `r > 0` in between.
pub fn revolve(profile: &[[f64; 2]], segments: usize) -> Result<TriMesh, String> {
    let n = profile.len();
    if n < 3 || segments < 3 {
        return Err("a revolution profile needs 3 points and 3 segments".into());
    }
    if profile[0][0] != 0.0 || profile[n - 1][0] != 0.0 {
        return Err("the profile must start and end on the axis".into());
    }
    if profile[1..n - 1]
        .iter()
        .any(|q| !q[0].is_finite() || q[0] <= 0.0)
    {
        return Err("the profile radius must be positive between its ends".into());
    }
    let mut v = vec![[0.0, 0.0, profile[0][1]]];
    for q in &profile[1..n - 1] {
        for j in 0..segments {
            let a = TAU * j as f64 / segments as f64;
            v.push([q[0] * a.cos(), q[0] * a.sin(), q[1]]);
        }
    }
    let top = v.len() as u32;
    v.push([0.0, 0.0, profile[n - 1][1]]);
    let s = segments as u32;
    let ring = |i: usize, j: u32| 1 + (i as u32) * s + (j % s);
    let rings = n - 2;
    let mut t = Vec::new();
    for j in 0..s {
        t.push([0, ring(0, j + 1), ring(0, j)]);
    }
    for i in 0..rings - 1 {
        for j in 0..s {
            let (a0, a1, b0, b1) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            t.push([a0, a1, b1]);
            t.push([a0, b1, b0]);
        }
    }
    for j in 0..s {
        t.push([top, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    let mut m = TriMesh::new(v, t);
    m.orient_outward();
    Ok(m)
}

/// A unit icosphere: the icosahedron subdivided `level` times, vertices on the unit sphere.
pub fn icosphere(level: u32) -> TriMesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| normalize(p))
    .collect();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut nt = Vec::with_capacity(t.len() * 4);
        for tri in &t {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    v.push(normalize(mul(add(v[a as usize], v[b as usize]), 0.5)));
                    (v.len() - 1) as u32
                });
            }
            nt.push([tri[0], m[0], m[2]]);
            nt.push([tri[1], m[1], m[0]]);
            nt.push([tri[2], m[2], m[1]]);
            nt.push([m[0], m[1], m[2]]);
        }
        t = nt;
    }
    let mut mesh = TriMesh::new(v, t);
    mesh.orient_outward();
    mesh
}

/// The star-shaped mesh `{ r(d) d : d on the unit sphere }` sampled on an icosphere of
/// the given `level`. `r` must be positive.
pub fn radial_mesh(level: u32, r: impl Fn([f64; 3]) -> f64) -> Result<TriMesh, String> {
    let mut m = icosphere(level);
    for v in &mut m.vertices {
        let rad = r(*v);
        if !(rad.is_finite() && rad > 0.0) {
            return Err(format!(
                "radius {rad} along direction {v:?} is not positive"
            ));
        }
        *v = mul(*v, rad);
    }
    m.orient_outward();
    Ok(m)
}

/// The vertex rings of a swept tube, one point list per centre-line sample.
pub type Rings = Vec<Vec<[f64; 3]>>;

/// A tube swept along `centres` with radii `radii` and `sides` sides. The ring frames use
/// `up` as reference normal, so the curve must never run parallel to `up`. An open tube
/// is closed at each end by a cone whose apex lies `cap * radius` beyond the end; a
/// `closed` tube joins its last ring to the first. Returns the mesh and the rings.
pub fn sweep(
    centres: &[[f64; 3]],
    radii: &[f64],
    sides: usize,
    up: [f64; 3],
    closed: bool,
    cap: f64,
) -> Result<(TriMesh, Rings), String> {
    let n = centres.len();
    if n < 2 || radii.len() != n || sides < 3 {
        return Err("a sweep needs 2 centres, one radius per centre and 3 sides".into());
    }
    let tangent = |i: usize| -> [f64; 3] {
        let (a, b) = if closed {
            (centres[(i + n - 1) % n], centres[(i + 1) % n])
        } else {
            (centres[i.saturating_sub(1)], centres[(i + 1).min(n - 1)])
        };
        normalize(sub(b, a))
    };
    let mut rings = Vec::with_capacity(n);
    for i in 0..n {
        let tg = tangent(i);
        let nrm = normalize(sub(up, mul(tg, dot(up, tg))));
        if dot(nrm, nrm) < 0.5 {
            return Err("the sweep curve runs parallel to its reference normal".into());
        }
        let bin = cross(tg, nrm);
        let ring: Vec<[f64; 3]> = (0..sides)
            .map(|j| {
                let a = TAU * j as f64 / sides as f64;
                add(
                    centres[i],
                    add(mul(nrm, radii[i] * a.cos()), mul(bin, radii[i] * a.sin())),
                )
            })
            .collect();
        rings.push(ring);
    }
    let mut v: Vec<[f64; 3]> = rings.iter().flatten().copied().collect();
    let s = sides as u32;
    let idx = |i: usize, j: u32| (i as u32) * s + (j % s);
    let mut t = Vec::new();
    let spans = if closed { n } else { n - 1 };
    for i in 0..spans {
        let k = (i + 1) % n;
        for j in 0..s {
            let (a0, a1, b0, b1) = (idx(i, j), idx(i, j + 1), idx(k, j), idx(k, j + 1));
            t.push([a0, a1, b1]);
            t.push([a0, b1, b0]);
        }
    }
    if !closed {
        let start = sub(centres[0], mul(tangent(0), cap * radii[0]));
        let end = add(centres[n - 1], mul(tangent(n - 1), cap * radii[n - 1]));
        let a = v.len() as u32;
        v.push(start);
        let b = v.len() as u32;
        v.push(end);
        for j in 0..s {
            t.push([a, idx(0, j + 1), idx(0, j)]);
            t.push([b, idx(n - 1, j), idx(n - 1, j + 1)]);
        }
        rings[0].push(start);
        rings[n - 1].push(end);
    }
    let mut m = TriMesh::new(v, t);
    m.orient_outward();
    Ok((m, rings))
}

/// Convex parts covering a swept tube: hulls of groups of consecutive rings, at most
/// `max_parts` of them (a closed tube wraps around).
pub fn ring_parts(
    rings: &[Vec<[f64; 3]>],
    closed: bool,
    max_parts: usize,
) -> Result<Vec<ConvexHull>, String> {
    let n = rings.len();
    let spans = if closed { n } else { n - 1 };
    let groups = spans.min(max_parts.max(1));
    let mut parts = Vec::with_capacity(groups);
    for g in 0..groups {
        let s = g * spans / groups;
        let e = (g + 1) * spans / groups;
        let pts: Vec<[f64; 3]> = (s..=e).flat_map(|i| rings[i % n].iter().copied()).collect();
        parts.push(ConvexHull::from_points(&pts).ok_or("a tube segment has no 3-D hull")?);
    }
    Ok(parts)
}

/// Points of a cylinder from `a` to `b` with radius `r` (two `sides`-gons).
pub fn cylinder_points(a: [f64; 3], b: [f64; 3], r: f64, sides: usize) -> Vec<[f64; 3]> {
    let axis = normalize(sub(b, a));
    let helper = if axis[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let u = normalize(cross(axis, helper));
    let w = cross(axis, u);
    let mut pts = Vec::with_capacity(2 * sides);
    for c in [a, b] {
        for j in 0..sides {
            let ang = TAU * j as f64 / sides as f64;
            pts.push(add(c, add(mul(u, r * ang.cos()), mul(w, r * ang.sin()))));
        }
    }
    pts
}

/// Corner points of the axis-aligned box centred at `c` with half extents `h`.
pub fn box_points(c: [f64; 3], h: [f64; 3]) -> Vec<[f64; 3]> {
    box_mesh(h).vertices.iter().map(|&v| add(v, c)).collect()
}

/// A set of convex parts: the visual mesh is the union of the parts' closed hull meshes.
#[derive(Debug, Default, Clone)]
pub struct Assembly {
    mesh: TriMesh,
    parts: Vec<ConvexHull>,
}

impl Assembly {
    /// An empty assembly.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the convex hull of `points` as a part.
    pub fn add(&mut self, points: &[[f64; 3]]) -> Result<&mut Self, String> {
        let m = convex_hull_mesh(points).ok_or("a part has no 3-D convex hull")?;
        self.parts.push(ConvexHull {
            points: m.vertices.clone(),
        });
        self.mesh.append(&m);
        Ok(self)
    }

    /// Adds a visual component whose collision is covered by `parts`.
    pub fn add_with_parts(&mut self, mesh: &TriMesh, parts: Vec<ConvexHull>) {
        self.mesh.append(mesh);
        self.parts.extend(parts);
    }

    /// The finished shape.
    pub fn finish(self) -> Generated {
        Generated {
            mesh: self.mesh,
            parts: Some(self.parts),
        }
    }
}

pub(crate) fn mesh_only(mesh: TriMesh) -> Generated {
    Generated { mesh, parts: None }
}

pub(crate) fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}
