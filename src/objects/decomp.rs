//! Convex decomposition of non-convex meshes (parry3d's VHACD), cached on disk.
//!
//! VHACD is slow (tenths of a second to seconds per object), so each result is stored in
//! a JSON cache file and reused while the mesh and the parameters are unchanged:
//!
//! - user meshes: next to the mesh, `<mesh file>.hulls.json`;
//! - generated objects: `<cache dir>/hulls/<object name>.hulls.json`, where the cache dir
//!   is [`default_cache_dir`] (`$GRASP_CACHE_DIR`, else `$XDG_CACHE_HOME/grasp`, else
//!   `~/.cache/grasp`).
//!
//! The cache key ([`cache_key`]) is a 128-bit FNV-1a digest ([`Fnv128`]) of a format
//! tag, the mesh content (every vertex coordinate's bits and every index, in order) and
//! every decomposition parameter. A cache file whose key differs (stale) or that cannot be
//! parsed (corrupt) is rebuilt with a `tracing` warning; a cache that cannot be written
//! (read-only folder) only costs a warning. Files are written with
//! [`crate::util::fsx::write_atomic`].

use super::mesh::{Aabb, TriMesh};
use super::{ConvexHull, ObjectError};
use crate::util::fsx::write_atomic;
use crate::util::hash::Fnv128;
use parry3d::math::Vector;
use parry3d::transformation::vhacd::{VHACDParameters, VHACD};
use parry3d::transformation::voxelization::FillMode;
use std::path::{Path, PathBuf};

/// Version of the cache file layout; part of the key, so a layout change invalidates old
/// files.
pub const CACHE_FORMAT: u32 = 1;

/// VHACD settings. The defaults keep a typical object (a few thousand triangles) well under
/// a second in an optimised build while giving at most 16 hulls.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecompParams {
    /// Voxel grid resolution along the longest axis.
    pub resolution: u32,
    /// Concavity each part may keep (VHACD's relative measure, 0..1).
    pub concavity: f64,
    /// Maximum number of convex hulls.
    pub max_hulls: u32,
    /// Cutting-plane search downsampling (higher is faster and coarser).
    pub plane_downsampling: u32,
    /// Hull computation downsampling during the search.
    pub hull_downsampling: u32,
}

impl Default for DecompParams {
    fn default() -> Self {
        DecompParams {
            resolution: 40,
            concavity: 0.01,
            max_hulls: 16,
            plane_downsampling: 4,
            hull_downsampling: 4,
        }
    }
}

impl DecompParams {
    fn to_vhacd(self) -> VHACDParameters {
        VHACDParameters {
            concavity: self.concavity as f32,
            alpha: 0.05,
            beta: 0.05,
            resolution: self.resolution.max(8),
            plane_downsampling: self.plane_downsampling.max(1),
            convex_hull_downsampling: self.hull_downsampling.max(1),
            fill_mode: FillMode::FloodFill {
                detect_cavities: false,
            },
            convex_hull_approximation: true,
            max_convex_hulls: self.max_hulls.max(1),
        }
    }

    fn hash_into(&self, h: &mut Fnv128) {
        h.write(&self.resolution.to_le_bytes());
        h.write(&self.concavity.to_bits().to_le_bytes());
        h.write(&self.max_hulls.to_le_bytes());
        h.write(&self.plane_downsampling.to_le_bytes());
        h.write(&self.hull_downsampling.to_le_bytes());
    }
}

/// The cache key of decomposing `mesh` with `params`: 32 hex digits.
pub fn cache_key(mesh: &TriMesh, params: &DecompParams) -> String {
    let mut h = Fnv128::new();
    h.write(b"grasp-hulls");
    h.write(&CACHE_FORMAT.to_le_bytes());
    h.write(&mesh.content_hash().to_le_bytes());
    params.hash_into(&mut h);
    format!("{:032x}", h.finish())
}

/// The cache directory for generated objects: `$GRASP_CACHE_DIR` when set, else
/// `$XDG_CACHE_HOME/grasp`, else `$HOME/.cache/grasp`, else `<temp dir>/grasp-cache`.
pub fn default_cache_dir() -> PathBuf {
    let var = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    if let Some(d) = var("GRASP_CACHE_DIR") {
        return d;
    }
    if let Some(d) = var("XDG_CACHE_HOME") {
        return d.join("grasp");
    }
    if let Some(d) = var("HOME") {
        return d.join(".cache").join("grasp");
    }
    std::env::temp_dir().join("grasp-cache")
}

/// Where a decomposition came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CacheStatus {
    /// Read from a valid cache file.
    Hit,
    /// Computed (no cache file existed) and written.
    Built,
    /// The cache file was stale or corrupt; computed again and rewritten.
    Rebuilt,
}

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CacheFile {
    format: u32,
    key: String,
    params: DecompParams,
    hulls: Vec<ConvexHull>,
}

/// Decomposes the closed mesh `mesh` into at most `params.max_hulls` convex hulls with
/// VHACD (no cache). `label` names the object in errors and warnings.
pub fn decompose(
    mesh: &TriMesh,
    params: &DecompParams,
    label: &str,
) -> Result<Vec<ConvexHull>, ObjectError> {
    let points: Vec<Vector> = mesh
        .vertices
        .iter()
        .map(|v| Vector::new(v[0] as f32, v[1] as f32, v[2] as f32))
        .collect();
    let indices = mesh.triangles.clone();
    let vparams = params.to_vhacd();
    // VHACD works on validated meshes; a panic inside parry on an unforeseen input must
    // still not take the process down.
    let raw = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let d = VHACD::decompose(&vparams, &points, &indices, true);
        d.compute_exact_convex_hulls(&points, &indices)
    }))
    .map_err(|_| ObjectError::Decomposition {
        name: label.to_string(),
        message: "VHACD failed on this mesh".into(),
    })?;
    let hulls: Vec<ConvexHull> = raw
        .into_iter()
        .filter_map(|(pts, _)| {
            let p: Vec<[f64; 3]> = pts
                .iter()
                .map(|v| [v.x as f64, v.y as f64, v.z as f64])
                .collect();
            ConvexHull::from_points(&p)
        })
        .collect();
    let hulls = merge_hulls(hulls, params.max_hulls.max(1) as usize);
    let mut hulls = hulls;
    if hulls.is_empty() {
        tracing::warn!("{label}: VHACD gave no usable hull; using the mesh's convex hull");
        hulls.push(ConvexHull::from_points(&mesh.vertices).ok_or_else(|| {
            ObjectError::Decomposition {
                name: label.to_string(),
                message: "the mesh has no 3-D convex hull".into(),
            }
        })?);
    }
    Ok(hulls)
}

/// Merges hulls pairwise until at most `max` remain. parry's VHACD splits to a depth that
/// can yield up to twice the requested count and has no merge step, so this greedy pass
/// (as in the original V-HACD) repeatedly merges the pair whose merged hull adds the
/// least volume beyond the two hulls' volumes. Ties go to the lowest indices, so the
/// result is deterministic.
pub fn merge_hulls(mut hulls: Vec<ConvexHull>, max: usize) -> Vec<ConvexHull> {
    let volume = |h: &ConvexHull| h.mesh().map_or(0.0, |m| m.signed_volume());
    let union = |a: &ConvexHull, b: &ConvexHull| {
        let pts: Vec<[f64; 3]> = a.points.iter().chain(&b.points).copied().collect();
        ConvexHull::from_points(&pts)
    };
    let mut vols: Vec<f64> = hulls.iter().map(volume).collect();
    // cost[i][j] for i < j: added volume of merging i and j.
    let pair_cost = |hulls: &[ConvexHull], vols: &[f64], i: usize, j: usize| {
        union(&hulls[i], &hulls[j]).map_or(f64::INFINITY, |u| volume(&u) - vols[i] - vols[j])
    };
    let n = hulls.len();
    let mut cost: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if j > i {
                        pair_cost(&hulls, &vols, i, j)
                    } else {
                        f64::INFINITY
                    }
                })
                .collect()
        })
        .collect();
    while hulls.len() > max.max(1) {
        let mut best = (f64::INFINITY, 0, 1);
        for (i, row) in cost.iter().enumerate() {
            for (j, &c) in row.iter().enumerate().skip(i + 1) {
                if c < best.0 {
                    best = (c, i, j);
                }
            }
        }
        let (_, i, j) = best;
        let Some(merged) = union(&hulls[i], &hulls[j]) else {
            break;
        };
        hulls[i] = merged;
        vols[i] = volume(&hulls[i]);
        hulls.remove(j);
        vols.remove(j);
        cost.remove(j);
        for row in &mut cost {
            row.remove(j);
        }
        for k in 0..hulls.len() {
            if k != i {
                let (a, b) = (k.min(i), k.max(i));
                cost[a][b] = pair_cost(&hulls, &vols, a, b);
            }
        }
    }
    hulls
}

/// [`decompose`] through the cache file `cache_file` (see the module docs).
pub fn decompose_cached(
    mesh: &TriMesh,
    params: &DecompParams,
    cache_file: &Path,
    label: &str,
) -> Result<(Vec<ConvexHull>, CacheStatus), ObjectError> {
    let key = cache_key(mesh, params);
    let mut status = CacheStatus::Built;
    // A link (which could point at any file of the user's), a FIFO (which would block the
    // read for good) or a device at the cache's path is neither read nor written: the
    // hulls are computed and the cache skipped.
    let usable = crate::util::fsx::is_plain_file_or_missing(cache_file);
    if !usable {
        tracing::warn!(
            "{label}: hull cache {} is not a regular file (a link, FIFO or device); \
             computing the hulls without caching them",
            cache_file.display()
        );
    }
    let read = if usable {
        crate::util::fsx::read_bounded(cache_file, crate::util::fsx::limits::DATA)
    } else {
        Err(std::io::ErrorKind::NotFound.into())
    };
    match read {
        Ok(bytes) => match serde_json::from_slice::<CacheFile>(&bytes) {
            Ok(c) if c.format == CACHE_FORMAT && c.key == key => {
                match hulls_fit_mesh(&c.hulls, mesh) {
                    Ok(()) => return Ok((c.hulls, CacheStatus::Hit)),
                    Err(why) => {
                        tracing::warn!(
                            "{label}: hull cache {} does not fit the mesh ({why}); rebuilding",
                            cache_file.display()
                        );
                        status = CacheStatus::Rebuilt;
                    }
                }
            }
            Ok(_) => {
                tracing::warn!(
                    "{label}: stale hull cache {} (mesh or parameters changed); rebuilding",
                    cache_file.display()
                );
                status = CacheStatus::Rebuilt;
            }
            Err(e) => {
                tracing::warn!(
                    "{label}: corrupt hull cache {} ({e}); rebuilding",
                    cache_file.display()
                );
                status = CacheStatus::Rebuilt;
            }
        },
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => {
            tracing::warn!(
                "{label}: cannot read hull cache {} ({e}); rebuilding",
                cache_file.display()
            );
            status = CacheStatus::Rebuilt;
        }
    }
    let hulls = decompose(mesh, params, label)?;
    let file = CacheFile {
        format: CACHE_FORMAT,
        key,
        params: *params,
        hulls,
    };
    match serde_json::to_vec(&file) {
        Ok(bytes) => {
            // Checked again just before the write: never through a link or into a FIFO.
            if !crate::util::fsx::is_plain_file_or_missing(cache_file) {
                // Said above when it was so before the decomposition.
                if usable {
                    tracing::warn!(
                        "{label}: hull cache {} is not a regular file; not saved",
                        cache_file.display()
                    );
                }
            } else if let Err(e) = write_atomic(cache_file, &bytes) {
                tracing::warn!("{label}: hull cache not saved: {e}");
            }
            // Return exactly what a later cache hit will read (serde_json's float parsing
            // may differ from the computed value in the last bit), so the first run and
            // every later run simulate the same geometry.
            if let Ok(back) = serde_json::from_slice::<CacheFile>(&bytes) {
                return Ok((back.hulls, status));
            }
        }
        Err(e) => tracing::warn!("{label}: hull cache not serialised: {e}"),
    }
    Ok((file.hulls, status))
}

/// Whether cached hulls can be the decomposition of `mesh`: at least one hull, each of
/// at least 4 finite points; every point within the mesh's bounding box (a tolerance of
/// 1 % of its diagonal); the hulls' points spanning the box along each axis (to 10 % of
/// the axis' extent at each side); and the hulls' volumes summing to at least half the
/// mesh's volume (convex parts cover the solid). A hand-edited or truncated file that
/// keeps a valid key fails one of these and is rebuilt. `Err` says which.
pub fn hulls_fit_mesh(hulls: &[ConvexHull], mesh: &TriMesh) -> Result<(), String> {
    use crate::util::num::short;
    if hulls.is_empty() {
        return Err("no hulls".into());
    }
    if let Some(k) = hulls.iter().position(|h| {
        h.points.len() < 4 || h.points.iter().any(|p| p.iter().any(|x| !x.is_finite()))
    }) {
        return Err(format!(
            "hull {k} has fewer than 4 points or a non-finite one"
        ));
    }
    let Some(bb) = mesh.aabb() else {
        return Err("the mesh is empty".into());
    };
    let e = bb.extents();
    let tol = 0.01 * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    for (k, h) in hulls.iter().enumerate() {
        for p in &h.points {
            if (0..3).any(|a| p[a] < bb.min[a] - tol || p[a] > bb.max[a] + tol) {
                return Err(format!(
                    "hull {k} has the point ({}, {}, {}) m outside the mesh's box",
                    short(p[0]),
                    short(p[1]),
                    short(p[2])
                ));
            }
        }
    }
    let span = Aabb::of_points(hulls.iter().flat_map(|h| h.points.iter()))
        .ok_or_else(|| "no hull points".to_string())?;
    for a in 0..3 {
        let slack = 0.1 * e[a] + tol;
        if span.min[a] > bb.min[a] + slack || span.max[a] < bb.max[a] - slack {
            return Err(format!(
                "the hulls do not span the mesh along {}",
                ["x", "y", "z"][a]
            ));
        }
    }
    let mesh_volume = mesh.signed_volume().abs();
    let hull_volume: f64 = hulls
        .iter()
        .map(|h| h.mesh().map_or(0.0, |m| m.signed_volume().abs()))
        .sum();
    if hull_volume < 0.5 * mesh_volume {
        return Err(format!(
            "the hulls hold {} of the mesh's {} m^3",
            short(hull_volume),
            short(mesh_volume)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_joins_the_cheapest_pair_first() {
        let cube = |x: f64| {
            ConvexHull::from_points(&crate::objects::shape_kit::box_points(
                [x, 0.0, 0.0],
                [0.5, 0.5, 0.5],
            ))
            .unwrap()
        };
        // Two touching unit cubes and one far away: the touching pair merges at no cost.
        let merged = merge_hulls(vec![cube(0.0), cube(10.0), cube(1.0)], 2);
        assert_eq!(merged.len(), 2);
        let v = merged[0].mesh().unwrap().signed_volume();
        assert!((v - 2.0).abs() < 1e-5, "{v}");
        assert_eq!(merge_hulls(vec![cube(0.0), cube(3.0)], 5).len(), 2);
        assert_eq!(
            merge_hulls(vec![cube(0.0), cube(3.0), cube(7.0)], 1).len(),
            1
        );
    }

    #[test]
    fn key_depends_on_params_and_mesh() {
        let m = crate::objects::shape_kit::box_mesh([0.05, 0.04, 0.03]);
        let p = DecompParams::default();
        let k = cache_key(&m, &p);
        assert_eq!(k.len(), 32);
        assert_eq!(k, cache_key(&m, &p));
        let p2 = DecompParams { max_hulls: 8, ..p };
        assert_ne!(k, cache_key(&m, &p2));
        let mut m2 = m.clone();
        m2.translate([1e-6, 0.0, 0.0]);
        assert_ne!(k, cache_key(&m2, &p));
    }

    #[test]
    fn caches_that_do_not_fit_the_mesh_are_rebuilt() {
        let m = crate::objects::shape_kit::box_mesh([0.05, 0.04, 0.03]);
        let p = DecompParams::default();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("box.hulls.json");
        let (hulls, status) = decompose_cached(&m, &p, &file, "box").unwrap();
        assert_eq!(status, CacheStatus::Built);
        hulls_fit_mesh(&hulls, &m).unwrap();
        assert_eq!(
            decompose_cached(&m, &p, &file, "box").unwrap().1,
            CacheStatus::Hit
        );
        let good: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
        // A point moved 5 m away keeps the key but no longer fits.
        let mut moved = good.clone();
        moved["hulls"][0]["points"][0] = serde_json::json!([5.0, 0.0, 0.0]);
        std::fs::write(&file, moved.to_string()).unwrap();
        let (back, status) = decompose_cached(&m, &p, &file, "box").unwrap();
        assert_eq!(status, CacheStatus::Rebuilt);
        assert_eq!(back, hulls);
        // Hulls that hold a sliver of the box.
        let sliver = ConvexHull::from_points(&crate::objects::shape_kit::box_points(
            [0.0, 0.0, 0.015],
            [0.025, 0.02, 0.001],
        ))
        .unwrap();
        let e = hulls_fit_mesh(&[sliver], &m).unwrap_err();
        assert!(e.contains("span") || e.contains("m^3"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn links_and_fifos_at_the_cache_path_are_left_alone() {
        let m = crate::objects::shape_kit::box_mesh([0.05, 0.04, 0.03]);
        let p = DecompParams::default();
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, "keep").unwrap();
        let link = dir.path().join("link.hulls.json");
        std::os::unix::fs::symlink("victim.txt", &link).unwrap();
        let (hulls, _) = decompose_cached(&m, &p, &link, "box").unwrap();
        assert!(!hulls.is_empty());
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep");
        // A FIFO is not opened (the read would block for good) nor replaced.
        let fifo = dir.path().join("fifo.hulls.json");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        decompose_cached(&m, &p, &fifo, "box").unwrap();
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
    }
}
