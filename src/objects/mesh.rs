//! Triangle meshes: loading (OBJ, STL), validation, mass properties and OBJ export.
//!
//! A [`TriMesh`] holds vertices in metres and triangles as vertex-index triples. The
//! validation rules every object mesh must pass ([`TriMesh::validate`]):
//!
//! - not empty, every coordinate finite, every index in range, no triangle that repeats a
//!   vertex;
//! - closed and consistently oriented: every directed edge `a -> b` appears in exactly one
//!   triangle and its reverse `b -> a` in exactly one other (so each undirected edge is
//!   shared by exactly two triangles). A mesh made of several closed components (a mug
//!   built from convex parts) passes as long as each component is closed;
//! - a non-zero enclosed volume.
//!
//! Size limits (bounding box larger than 1 m or smaller than 5 mm) are checked separately by
//! [`TriMesh::check_size`], because they apply to objects, not to every intermediate mesh.
//!
//! Mass properties use the signed-tetrahedron decomposition: each triangle `(a, b, c)` with
//! the origin spans a tetrahedron of signed volume `det[a b c] / 6`; its second moment is
//! `det / 120 * (a a^T + b b^T + c c^T + s s^T)` with `s = a + b + c`.

use super::ObjectError;
use crate::util::fsx::write_atomic;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// Largest allowed bounding-box extent of an object, in metres.
pub const MAX_EXTENT_M: f64 = 1.0;
/// Smallest allowed largest bounding-box extent of an object, in metres.
pub const MIN_EXTENT_M: f64 = 0.005;

/// A triangle mesh in metres.
///
/// Triangles are counter-clockwise seen from outside (outward normals) once the mesh has
/// passed [`TriMesh::validate`] and [`TriMesh::orient_outward`].
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct TriMesh {
    /// Vertex positions in metres.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

impl Aabb {
    /// The extents `max - min` along x, y, z.
    pub fn extents(&self) -> [f64; 3] {
        [
            self.max[0] - self.min[0],
            self.max[1] - self.min[1],
            self.max[2] - self.min[2],
        ]
    }

    /// The largest of the three extents.
    pub fn max_extent(&self) -> f64 {
        let e = self.extents();
        e[0].max(e[1]).max(e[2])
    }

    /// The bounding box of a set of points (`None` when empty).
    pub fn of_points<'a>(points: impl IntoIterator<Item = &'a [f64; 3]>) -> Option<Aabb> {
        let mut it = points.into_iter();
        let first = *it.next()?;
        let mut bb = Aabb {
            min: first,
            max: first,
        };
        for p in it {
            for ((lo, hi), &x) in bb.min.iter_mut().zip(bb.max.iter_mut()).zip(p) {
                *lo = lo.min(x);
                *hi = hi.max(x);
            }
        }
        Some(bb)
    }
}

/// Volume, centroid and inertia of a solid of unit density.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MassProps {
    /// Enclosed volume in m^3.
    pub volume: f64,
    /// Centroid (centre of mass at uniform density), in metres.
    pub centroid: [f64; 3],
    /// Inertia tensor about the centroid for a density of 1 kg/m^3 (kg m^2); multiply by the
    /// density (or by `mass / volume`) to get the physical tensor.
    pub inertia_unit_density: [[f64; 3]; 3],
}

impl MassProps {
    /// The inertia tensor about the centroid for a total mass `mass_kg` (kg m^2).
    pub fn inertia_for_mass(&self, mass_kg: f64) -> [[f64; 3]; 3] {
        let s = mass_kg / self.volume;
        let mut out = self.inertia_unit_density;
        for row in &mut out {
            for v in row.iter_mut() {
                *v *= s;
            }
        }
        out
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Checks an OBJ file's `v` and `f` lines before it is parsed, so that errors name the
/// line (counted from 1): a vertex coordinate that is not a finite number (NaN, or beyond
/// the parser's 32-bit range) and a face index 0 (OBJ indices count from 1, negative
/// ones from the end), which the parser reports as "index out of bounds" only.
fn check_obj_lines(path: &Path, bytes: &[u8]) -> Result<(), ObjectError> {
    let text = String::from_utf8_lossy(bytes);
    let mut vertex = 0usize;
    let bad = |line: usize, message: String| ObjectError::MeshParse {
        path: path.display().to_string(),
        message: format!("line {line}: {message}"),
    };
    for (i, line) in text.lines().enumerate() {
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => {
                vertex += 1;
                for t in tokens.take(3) {
                    if t.parse::<f32>().is_ok_and(|x| !x.is_finite()) {
                        return Err(bad(
                            i + 1,
                            format!(
                                "vertex {vertex} has a NaN or infinite coordinate ({t}; at \
                                 most about 3.4e38 is finite here)"
                            ),
                        ));
                    }
                }
            }
            Some("f") => {
                for t in tokens {
                    let index = t.split('/').next().unwrap_or_default();
                    if index.parse::<i64>() == Ok(0) {
                        return Err(bad(
                            i + 1,
                            "face index 0: OBJ vertex indices count from 1 (negative ones \
                             from the last vertex)"
                                .into(),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Checks a binary STL file's size against its triangle count (84 bytes of header and
/// count, 50 per triangle) before it is parsed: a wrong count was reported as "failed to
/// fill whole buffer" or a mesh "not watertight". A file that starts with `solid` and
/// does not have the binary size is read as ASCII STL.
fn check_stl_size(path: &Path, bytes: &[u8]) -> Result<(), ObjectError> {
    let bad = |message: String| ObjectError::MeshParse {
        path: path.display().to_string(),
        message,
    };
    if bytes.len() < 84 {
        if bytes.starts_with(b"solid") {
            return Ok(());
        }
        return Err(bad(format!(
            "{} bytes: shorter than a binary STL's 84-byte header and triangle count, and \
             not ASCII STL (which starts with `solid`)",
            bytes.len()
        )));
    }
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let want = 84 + 50 * count;
    if want == bytes.len() as u64 || bytes.starts_with(b"solid") {
        return Ok(());
    }
    Err(bad(format!(
        "the binary STL header gives {count} triangles, which take {want} bytes, but the \
         file has {} bytes (a truncated or edited file)",
        bytes.len()
    )))
}

impl TriMesh {
    /// A mesh from vertices (metres) and triangles.
    pub fn new(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        TriMesh {
            vertices,
            triangles,
        }
    }

    /// Loads an OBJ or STL file (chosen by extension, case-insensitive). Faces are
    /// triangulated, vertices at identical positions are merged. The mesh is NOT validated:
    /// call [`TriMesh::validate`].
    pub fn load(path: &Path) -> Result<TriMesh, ObjectError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        let is_obj = match ext.as_deref() {
            Some("obj") => true,
            Some("stl") => false,
            _ => {
                return Err(ObjectError::UnsupportedFormat {
                    path: path.display().to_string(),
                })
            }
        };
        let bytes = crate::util::fsx::read_bounded(path, crate::util::fsx::limits::MESH).map_err(
            |error| ObjectError::Io {
                path: path.display().to_string(),
                error,
            },
        )?;
        if is_obj {
            Self::from_obj_bytes(path, &bytes)
        } else {
            Self::from_stl_bytes(path, &bytes)
        }
    }

    /// Parses OBJ text; `path` is used in error messages only.
    pub fn from_obj_bytes(path: &Path, bytes: &[u8]) -> Result<TriMesh, ObjectError> {
        check_obj_lines(path, bytes)?;
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let mut reader = std::io::BufReader::new(bytes);
        let (models, _materials) = tobj::load_obj_buf(&mut reader, &opts, |_| {
            // Materials are irrelevant for collision; do not touch other files.
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| ObjectError::MeshParse {
            path: path.display().to_string(),
            message: format!("invalid OBJ: {e}"),
        })?;
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for model in &models {
            let m = &model.mesh;
            let base = vertices.len();
            for p in m.positions.chunks_exact(3) {
                vertices.push([p[0] as f64, p[1] as f64, p[2] as f64]);
            }
            let nv = m.positions.len() / 3;
            for t in m.indices.chunks_exact(3) {
                for &i in t {
                    if i as usize >= nv {
                        return Err(ObjectError::IndexOutOfRange {
                            path: path.display().to_string(),
                            triangle: triangles.len(),
                            index: i as usize,
                            vertex_count: nv,
                        });
                    }
                }
                let off = |i: u32| (base + i as usize) as u32;
                triangles.push([off(t[0]), off(t[1]), off(t[2])]);
            }
        }
        let mut mesh = TriMesh::new(vertices, triangles);
        mesh.weld_identical();
        Ok(mesh)
    }

    /// Parses ASCII or binary STL; `path` is used in error messages only.
    pub fn from_stl_bytes(path: &Path, bytes: &[u8]) -> Result<TriMesh, ObjectError> {
        check_stl_size(path, bytes)?;
        let mut cursor = std::io::Cursor::new(bytes);
        let stl = stl_io::read_stl(&mut cursor).map_err(|e| ObjectError::MeshParse {
            path: path.display().to_string(),
            message: format!("invalid STL: {e}"),
        })?;
        let vertices = stl
            .vertices
            .iter()
            .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
            .collect::<Vec<_>>();
        let mut triangles = Vec::with_capacity(stl.faces.len());
        for (k, f) in stl.faces.iter().enumerate() {
            let mut t = [0u32; 3];
            for (j, &i) in f.vertices.iter().enumerate() {
                if i >= vertices.len() {
                    return Err(ObjectError::IndexOutOfRange {
                        path: path.display().to_string(),
                        triangle: k,
                        index: i,
                        vertex_count: vertices.len(),
                    });
                }
                t[j] = i as u32;
            }
            triangles.push(t);
        }
        Ok(TriMesh::new(vertices, triangles))
    }

    /// Merges vertices with bit-identical coordinates (as STL readers do), dropping unused
    /// ones. Needed for OBJ files whose groups repeat shared vertices.
    pub fn weld_identical(&mut self) {
        let mut map: HashMap<[u64; 3], u32> = HashMap::new();
        let mut new_vertices = Vec::new();
        let mut remap = Vec::with_capacity(self.vertices.len());
        for v in &self.vertices {
            // -0.0 and 0.0 are the same point.
            let key = v.map(|x| if x == 0.0 { 0u64 } else { x.to_bits() });
            let idx = *map.entry(key).or_insert_with(|| {
                new_vertices.push(*v);
                (new_vertices.len() - 1) as u32
            });
            remap.push(idx);
        }
        for t in &mut self.triangles {
            for i in t.iter_mut() {
                if let Some(&r) = remap.get(*i as usize) {
                    *i = r;
                }
            }
        }
        self.vertices = new_vertices;
    }

    /// Appends `other` as a separate component (vertices are not merged).
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// Moves every vertex by `d`.
    pub fn translate(&mut self, d: [f64; 3]) {
        for v in &mut self.vertices {
            for k in 0..3 {
                v[k] += d[k];
            }
        }
    }

    /// Scales every vertex about the origin by `s` per axis.
    pub fn scale(&mut self, s: [f64; 3]) {
        for v in &mut self.vertices {
            for k in 0..3 {
                v[k] *= s[k];
            }
        }
        // A reflection (odd number of negative factors) flips the orientation.
        if s[0] * s[1] * s[2] < 0.0 {
            self.flip();
        }
    }

    /// Reverses the orientation of every triangle.
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Flips the whole mesh when its signed volume is negative (inward normals).
    pub fn orient_outward(&mut self) {
        if self.signed_volume() < 0.0 {
            self.flip();
        }
    }

    /// The bounding box (`None` for a mesh without vertices).
    pub fn aabb(&self) -> Option<Aabb> {
        Aabb::of_points(&self.vertices)
    }

    /// The signed enclosed volume (positive for outward-oriented closed meshes), in m^3.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    /// Volume, centroid and unit-density inertia about the centroid of the closed mesh.
    ///
    /// Computed relative to a reference point inside the bounding box to limit rounding.
    /// The result is meaningless for an open mesh: validate first.
    pub fn mass_properties(&self) -> MassProps {
        let reference = self
            .aabb()
            .map(|b| {
                [
                    0.5 * (b.min[0] + b.max[0]),
                    0.5 * (b.min[1] + b.max[1]),
                    0.5 * (b.min[2] + b.max[2]),
                ]
            })
            .unwrap_or([0.0; 3]);
        let mut vol = 0.0;
        let mut first = [0.0; 3];
        let mut second = [[0.0; 3]; 3];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| sub(self.vertices[i as usize], reference));
            let det = dot(a, cross(b, c));
            vol += det / 6.0;
            let s = [a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]];
            for k in 0..3 {
                first[k] += det / 24.0 * s[k];
            }
            for j in 0..3 {
                for k in 0..3 {
                    second[j][k] +=
                        det / 120.0 * (a[j] * a[k] + b[j] * b[k] + c[j] * c[k] + s[j] * s[k]);
                }
            }
        }
        let c_local = if vol != 0.0 {
            first.map(|x| x / vol)
        } else {
            [0.0; 3]
        };
        // Second moment about the centroid: C_c = C - V c c^T.
        let mut cc = second;
        for j in 0..3 {
            for k in 0..3 {
                cc[j][k] -= vol * c_local[j] * c_local[k];
            }
        }
        let tr = cc[0][0] + cc[1][1] + cc[2][2];
        let mut inertia = [[0.0; 3]; 3];
        for j in 0..3 {
            for k in 0..3 {
                inertia[j][k] = if j == k { tr - cc[j][k] } else { -cc[j][k] };
            }
        }
        MassProps {
            volume: vol,
            centroid: [
                c_local[0] + reference[0],
                c_local[1] + reference[1],
                c_local[2] + reference[2],
            ],
            inertia_unit_density: inertia,
        }
    }

    /// Checks the structural rules listed in the module docs; `source` (a file path or an
    /// object name) names the mesh in errors.
    pub fn validate(&self, source: &str) -> Result<(), ObjectError> {
        let src = || source.to_string();
        if self.vertices.is_empty() || self.triangles.is_empty() {
            return Err(ObjectError::EmptyMesh { path: src() });
        }
        if let Some(i) = self
            .vertices
            .iter()
            .position(|v| v.iter().any(|x| !x.is_finite()))
        {
            return Err(ObjectError::NonFiniteVertex {
                path: src(),
                index: i,
            });
        }
        let n = self.vertices.len();
        for (k, t) in self.triangles.iter().enumerate() {
            if let Some(&i) = t.iter().find(|&&i| i as usize >= n) {
                return Err(ObjectError::IndexOutOfRange {
                    path: src(),
                    triangle: k,
                    index: i as usize,
                    vertex_count: n,
                });
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(ObjectError::DegenerateTriangle {
                    path: src(),
                    triangle: k,
                });
            }
        }
        self.check_closed(source)?;
        let vol = self.signed_volume().abs();
        let scale = self.aabb().map_or(0.0, |b| b.max_extent());
        if !(vol.is_finite() && vol > 1e-9 * scale.powi(3)) {
            return Err(ObjectError::ZeroVolume {
                path: src(),
                volume: vol,
            });
        }
        Ok(())
    }

    /// Checks that every directed edge is used once and its reverse once (closed, manifold,
    /// consistently oriented).
    pub fn check_closed(&self, source: &str) -> Result<(), ObjectError> {
        let mut directed: HashMap<(u32, u32), u32> =
            HashMap::with_capacity(self.triangles.len() * 3);
        for t in &self.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *directed.entry((a, b)).or_insert(0) += 1;
            }
        }
        let mut worst: Option<(u32, u32, u32)> = None;
        let mut boundary = 0usize;
        let mut first_boundary = None;
        for (&(a, b), &count) in &directed {
            if count > 1 {
                let undirected = count + directed.get(&(b, a)).copied().unwrap_or(0);
                let cand = (a.min(b), a.max(b), undirected);
                if worst.is_none_or(|w| (cand.0, cand.1) < (w.0, w.1)) {
                    worst = Some(cand);
                }
            } else if !directed.contains_key(&(b, a)) {
                boundary += 1;
                let e = (a.min(b), a.max(b));
                if first_boundary.is_none_or(|f| e < f) {
                    first_boundary = Some(e);
                }
            }
        }
        if let Some((a, b, count)) = worst {
            return Err(ObjectError::NonManifold {
                path: source.to_string(),
                a,
                b,
                count,
            });
        }
        if let Some((a, b)) = first_boundary {
            return Err(ObjectError::NotWatertight {
                path: source.to_string(),
                boundary_edges: boundary,
                a,
                b,
            });
        }
        Ok(())
    }

    /// Checks the object size limits: the largest bounding-box extent must lie within
    /// [`MIN_EXTENT_M`]..=[`MAX_EXTENT_M`].
    pub fn check_size(&self, source: &str) -> Result<(), ObjectError> {
        let ext = self.aabb().map_or(0.0, |b| b.max_extent());
        if ext > MAX_EXTENT_M {
            return Err(ObjectError::TooLarge {
                path: source.to_string(),
                extent_m: ext,
            });
        }
        if ext < MIN_EXTENT_M {
            return Err(ObjectError::TooSmall {
                path: source.to_string(),
                extent_m: ext,
            });
        }
        Ok(())
    }

    /// The mesh as Wavefront OBJ text (`v` and 1-based `f` lines).
    pub fn to_obj_string(&self, comment: &str) -> String {
        let mut s = String::with_capacity(self.vertices.len() * 40 + self.triangles.len() * 24);
        for line in comment.lines() {
            let _ = writeln!(s, "# {line}");
        }
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", v[0], v[1], v[2]);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// Writes the mesh as OBJ to `path` atomically.
    pub fn write_obj(&self, path: &Path, comment: &str) -> Result<(), ObjectError> {
        write_atomic(path, self.to_obj_string(comment).as_bytes()).map_err(ObjectError::Write)
    }

    /// The mesh as binary STL (metres, one facet per triangle with its unit normal).
    pub fn to_stl_bytes(&self) -> Vec<u8> {
        let v = |i: u32| {
            let p = self.vertices[i as usize];
            [p[0] as f32, p[1] as f32, p[2] as f32]
        };
        let tris: Vec<stl_io::Triangle> = self
            .triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (v(t[0]), v(t[1]), v(t[2]));
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                let n = if len > 0.0 {
                    n.map(|x| x / len)
                } else {
                    [0.0; 3]
                };
                stl_io::Triangle {
                    normal: stl_io::Normal::new(n),
                    vertices: [
                        stl_io::Vertex::new(a),
                        stl_io::Vertex::new(b),
                        stl_io::Vertex::new(c),
                    ],
                }
            })
            .collect();
        let mut bytes = Vec::with_capacity(84 + 50 * tris.len());
        // Writing into memory cannot fail.
        let _ = stl_io::write_stl(&mut bytes, tris.iter());
        bytes
    }

    /// Writes the mesh as binary STL to `path`, atomically.
    pub fn write_stl(&self, path: &Path) -> Result<(), ObjectError> {
        write_atomic(path, &self.to_stl_bytes()).map_err(ObjectError::Write)
    }

    /// A stable 128-bit digest of the mesh content (vertex bits and indices), see
    /// [`crate::util::hash::Fnv128`].
    pub fn content_hash(&self) -> u128 {
        let mut h = crate::util::hash::Fnv128::new();
        h.write(&(self.vertices.len() as u64).to_le_bytes());
        for v in &self.vertices {
            for x in v {
                h.write(&x.to_bits().to_le_bytes());
            }
        }
        h.write(&(self.triangles.len() as u64).to_le_bytes());
        for t in &self.triangles {
            for i in t {
                h.write(&i.to_le_bytes());
            }
        }
        h.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The unit cube [0,1]^3, outward oriented.
    pub(crate) fn unit_cube() -> TriMesh {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let t = vec![
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [1, 2, 6],
            [1, 6, 5],
            [2, 3, 7],
            [2, 7, 6],
            [3, 0, 4],
            [3, 4, 7],
        ];
        TriMesh::new(v, t)
    }

    #[test]
    fn unit_cube_mass_properties() {
        let m = unit_cube();
        m.validate("cube").unwrap();
        let p = m.mass_properties();
        assert_relative_eq!(p.volume, 1.0, epsilon = 1e-12);
        for k in 0..3 {
            assert_relative_eq!(p.centroid[k], 0.5, epsilon = 1e-12);
        }
        // Cube of side 1, mass 1: I = (1 + 1) / 12 = 1/6 on the diagonal, 0 elsewhere.
        for j in 0..3 {
            for k in 0..3 {
                let want = if j == k { 1.0 / 6.0 } else { 0.0 };
                assert_relative_eq!(p.inertia_unit_density[j][k], want, epsilon = 1e-12);
            }
        }
        // Translating and scaling: a 2 x 1 x 1 box far from the origin.
        let mut b = unit_cube();
        b.scale([2.0, 1.0, 1.0]);
        b.translate([10.0, -5.0, 3.0]);
        let p = b.mass_properties();
        assert_relative_eq!(p.volume, 2.0, epsilon = 1e-9);
        assert_relative_eq!(p.centroid[0], 11.0, epsilon = 1e-9);
        // I_xx = m (b^2 + c^2) / 12 = 2 * 2 / 12; I_yy = I_zz = 2 * (4 + 1) / 12.
        assert_relative_eq!(p.inertia_unit_density[0][0], 4.0 / 12.0, epsilon = 1e-9);
        assert_relative_eq!(p.inertia_unit_density[1][1], 10.0 / 12.0, epsilon = 1e-9);
        assert_relative_eq!(p.inertia_unit_density[0][1], 0.0, epsilon = 1e-9);
    }

    #[test]
    fn inverted_cube_has_negative_volume_and_is_fixed() {
        let mut m = unit_cube();
        m.flip();
        assert!(m.signed_volume() < 0.0);
        m.orient_outward();
        assert_relative_eq!(m.signed_volume(), 1.0, epsilon = 1e-12);
    }

    #[test]
    fn open_and_non_manifold_meshes_are_rejected() {
        let mut m = unit_cube();
        m.triangles.pop();
        let e = m.validate("open.obj").unwrap_err().to_string();
        assert!(
            e.contains("open.obj") && e.contains("not watertight"),
            "{e}"
        );

        let mut m = unit_cube();
        m.triangles[0].swap(1, 2); // one inconsistently oriented face
        let e = m.validate("flip.obj").unwrap_err().to_string();
        assert!(e.contains("flip.obj"), "{e}");

        let mut m = unit_cube();
        let extra = m.triangles[0];
        m.triangles.push(extra);
        let e = m.validate("dup.obj").unwrap_err().to_string();
        assert!(e.contains("non-manifold"), "{e}");
    }

    #[test]
    fn bad_values_are_rejected() {
        let mut m = unit_cube();
        m.vertices[3][1] = f64::NAN;
        let e = m.validate("nan.obj").unwrap_err().to_string();
        assert!(
            e.contains("nan.obj") && e.contains("vertex 4 (counted from 1)"),
            "{e}"
        );
        let mut m = unit_cube();
        m.triangles[2][1] = 99;
        assert!(matches!(
            m.validate("x"),
            Err(ObjectError::IndexOutOfRange { index: 99, .. })
        ));
        assert!(matches!(
            TriMesh::default().validate("x"),
            Err(ObjectError::EmptyMesh { .. })
        ));
        // Two copies of a face with opposite orientation: closed but flat.
        let flat = TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2], [0, 2, 1]],
        );
        assert!(matches!(
            flat.validate("flat"),
            Err(ObjectError::ZeroVolume { .. })
        ));
    }

    #[test]
    fn size_limits() {
        let mut m = unit_cube();
        assert!(m.check_size("big").is_ok()); // exactly 1 m
        m.scale([2.0, 2.0, 2.0]);
        assert!(matches!(
            m.check_size("big"),
            Err(ObjectError::TooLarge { .. })
        ));
        m.scale([0.001, 0.001, 0.001]);
        assert!(matches!(
            m.check_size("tiny"),
            Err(ObjectError::TooSmall { .. })
        ));
    }

    #[test]
    fn obj_round_trip() {
        let m = unit_cube();
        let text = m.to_obj_string("cube");
        let back = TriMesh::from_obj_bytes(Path::new("mem.obj"), text.as_bytes()).unwrap();
        assert_eq!(back.vertices.len(), 8);
        assert_eq!(back.triangles.len(), 12);
        back.validate("mem.obj").unwrap();
        assert_relative_eq!(back.signed_volume(), 1.0, epsilon = 1e-9);
    }

    #[test]
    fn quads_are_triangulated() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                    f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
        let m = TriMesh::from_obj_bytes(Path::new("q.obj"), text.as_bytes()).unwrap();
        assert_eq!(m.triangles.len(), 12);
        m.validate("q.obj").unwrap();
        assert_relative_eq!(m.signed_volume(), 1.0, epsilon = 1e-9);
    }

    #[test]
    fn content_hash_changes_with_content() {
        let a = unit_cube();
        let mut b = unit_cube();
        assert_eq!(a.content_hash(), b.content_hash());
        b.vertices[0][0] = 1e-9;
        assert_ne!(a.content_hash(), b.content_hash());
    }

    fn fixture(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/objects")
            .join(name)
    }

    #[test]
    fn loads_obj_and_ascii_stl_fixtures() {
        for f in ["cube.obj", "cube_ascii.stl"] {
            let m = TriMesh::load(&fixture(f)).unwrap();
            m.validate(f).unwrap();
            assert_eq!((m.vertices.len(), m.triangles.len()), (8, 12), "{f}");
            assert_relative_eq!(m.signed_volume(), 0.05f64.powi(3), epsilon = 1e-9);
            m.check_size(f).unwrap();
        }
    }

    #[test]
    fn loads_binary_stl() {
        let cube = unit_cube();
        let tris: Vec<stl_io::Triangle> = cube
            .triangles
            .iter()
            .map(|t| stl_io::Triangle {
                normal: stl_io::Normal::new([0.0, 0.0, 0.0]),
                vertices: t.map(|i| {
                    let v = cube.vertices[i as usize];
                    stl_io::Vertex::new([v[0] as f32 * 0.1, v[1] as f32 * 0.1, v[2] as f32 * 0.1])
                }),
            })
            .collect();
        let mut bytes = Vec::new();
        stl_io::write_stl(&mut bytes, tris.iter()).unwrap();
        assert_eq!(bytes.len(), 84 + 50 * 12);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cube_binary.STL");
        std::fs::write(&path, &bytes).unwrap();
        let m = TriMesh::load(&path).unwrap();
        m.validate("cube_binary.STL").unwrap();
        assert_eq!(m.vertices.len(), 8);
        assert_relative_eq!(m.signed_volume(), 0.001, epsilon = 1e-8);
    }

    #[test]
    fn bad_fixtures_give_errors_naming_the_file() {
        let check = |f: &str, want: &str| {
            let path = fixture(f);
            let e = TriMesh::load(&path)
                .and_then(|m| {
                    m.validate(&path.display().to_string())?;
                    m.check_size(&path.display().to_string())
                })
                .unwrap_err()
                .to_string();
            assert!(e.contains(f) && e.contains(want), "{f}: {e}");
        };
        check("empty.obj", "empty");
        check("nan.obj", "line 5: vertex 4 has a NaN");
        // A face index 0 and a binary STL whose count does not fit its size say so.
        let e =
            TriMesh::from_obj_bytes(Path::new("z.obj"), b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
                .unwrap_err()
                .to_string();
        assert!(e.contains("line 4: face index 0"), "{e}");
        let mut stl = vec![0u8; 80];
        stl.extend_from_slice(&2u32.to_le_bytes());
        stl.extend_from_slice(&[0u8; 50]);
        let e = TriMesh::from_stl_bytes(Path::new("c.stl"), &stl)
            .unwrap_err()
            .to_string();
        assert!(e.contains("gives 2 triangles, which take 184 bytes"), "{e}");
        check("open_box.obj", "not watertight");
        check("huge.obj", "too large");
        check("missing.obj", "cannot read");
        let e = TriMesh::load(Path::new("x.ply")).unwrap_err().to_string();
        assert!(e.contains("x.ply") && e.contains("unsupported"), "{e}");
        let bad = TriMesh::from_stl_bytes(Path::new("bad.stl"), b"solid x\nfacet nonsense\n");
        assert!(bad.unwrap_err().to_string().contains("bad.stl"));
    }

    #[test]
    fn non_convex_fixture_is_valid() {
        let m = TriMesh::load(&fixture("l_block.obj")).unwrap();
        m.validate("l_block.obj").unwrap();
        // 8x8 minus 5x5 cm, 4 cm high.
        assert_relative_eq!(
            m.signed_volume().abs(),
            (0.0064 - 0.0025) * 0.04,
            epsilon = 1e-9
        );
    }
}
