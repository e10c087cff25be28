//! Two-finger grasp candidates on a point cloud (Sec. V-B): normals by local PCA,
//! antipodal pairs and their geometric score, and the fallback across the cloud's narrow
//! axis.
//!
//! The paper scores two-finger candidates with PointNetGPD; this module provides the
//! candidate generator and a geometric score (antipodal quality, top-down preference and
//! closeness to the cloud centroid), so a grasp can be chosen without a learned scorer.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::pointcloud::CloudError;
use crate::robot::grasp_map::TwoFingerGrasp;

/// The mean of `points` (the origin for an empty slice).
pub fn centroid(points: &[Point3<f64>]) -> Point3<f64> {
    if points.is_empty() {
        return Point3::origin();
    }
    let s: Vector3<f64> = points.iter().map(|p| p.coords).sum();
    Point3::from(s / points.len() as f64)
}

/// Unit normals by local PCA: for each point, the eigenvector of the smallest
/// eigenvalue of the covariance of its `k` nearest neighbours (itself included),
/// oriented away from the cloud centroid. Brute-force neighbour search, O(n^2): fine for
/// clouds of a few thousand points. Needs `k >= 3` and at least `k` points.
pub fn estimate_normals(points: &[Point3<f64>], k: usize) -> Result<Vec<Vector3<f64>>, CloudError> {
    if k < 3 {
        return Err(CloudError::BadParameter {
            name: "k",
            detail: format!("{k} neighbours: at least 3 are needed for a plane"),
        });
    }
    if points.len() < k {
        return Err(CloudError::TooFewPoints {
            points: points.len(),
            needed: k,
        });
    }
    let c = centroid(points);
    let mut d2: Vec<(f64, usize)> = Vec::with_capacity(points.len());
    let mut normals = Vec::with_capacity(points.len());
    for p in points {
        d2.clear();
        d2.extend(
            points
                .iter()
                .enumerate()
                .map(|(j, q)| ((q - p).norm_squared(), j)),
        );
        d2.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let nb = &d2[..k];
        let mean: Vector3<f64> = nb
            .iter()
            .map(|&(_, j)| points[j].coords)
            .sum::<Vector3<f64>>()
            / k as f64;
        let mut cov = Matrix3::zeros();
        for &(_, j) in nb {
            let d = points[j].coords - mean;
            cov += d * d.transpose();
        }
        let eig = SymmetricEigen::new(cov);
        let imin = eig.eigenvalues.imin();
        let mut n: Vector3<f64> = eig.eigenvectors.column(imin).into_owned();
        n = n.try_normalize(1e-12).unwrap_or_else(Vector3::z);
        if n.dot(&(p - c)) < 0.0 {
            n = -n;
        }
        normals.push(n);
    }
    Ok(normals)
}

/// Parameters of the antipodal grasp sampler.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AntipodalConfig {
    /// Friction coefficient; the friction cone half-angle is `atan(mu)`.
    pub mu: f64,
    /// Smallest grasp width (m).
    pub min_width: f64,
    /// Largest grasp width: the gripper's maximum opening (m).
    pub max_width: f64,
    /// Number of first contact points sampled.
    pub samples: usize,
    /// Neighbours used for the normals.
    pub normal_k: usize,
    /// Weight of the antipodal alignment term.
    pub w_alignment: f64,
    /// Weight of the top-down term (`-z` component of the approach direction).
    pub w_top_down: f64,
    /// Weight of the centring term (grasp centre near the cloud centroid).
    pub w_center: f64,
    /// Seed of the sampler.
    pub seed: u64,
}

impl Default for AntipodalConfig {
    fn default() -> Self {
        AntipodalConfig {
            mu: 0.5,
            min_width: 0.01,
            max_width: 0.11,
            samples: 300,
            normal_k: 15,
            w_alignment: 1.0,
            w_top_down: 0.5,
            w_center: 1.0,
            seed: 0,
        }
    }
}

/// A scored two-finger grasp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspCandidate {
    /// The grasp: centre between the contacts, approach, closing direction p1 -> p2.
    pub grasp: TwoFingerGrasp,
    /// Total score (higher is better).
    pub score: f64,
    /// Distance between the contacts (m).
    pub width: f64,
    /// First contact.
    pub p1: Point3<f64>,
    /// Second contact.
    pub p2: Point3<f64>,
    /// Mean cosine between the inward normals and the closing line, in `[cos atan mu, 1]`.
    pub alignment: f64,
    /// `-z` component of the approach direction, in `[0, 1]`.
    pub top_down: f64,
}

/// Samples antipodal two-finger grasps on `points` with outward `normals`.
///
/// For each sampled first contact `p1`, every other point `p2` with a width in
/// `[min_width, max_width]` is tested: with `d = (p2 - p1)/|p2 - p1|`, the finger at `p1`
/// pushes along `d` and the one at `p2` along `-d`, so both `-n1` and `n2` must lie within
/// the friction cone about `d`: `-n1 . d >= cos(atan mu)` and `n2 . d >= cos(atan mu)`.
/// The approach is the direction orthogonal to `d` closest to world `-z`. The score is
/// `w_alignment * (-n1.d + n2.d)/2 + w_top_down * (approach . -z)
///  + w_center * max(0, 1 - |centre - centroid| / max_width)`.
///
/// The best partner of each `p1` is kept; the candidates are returned best first.
/// Deterministic for a given seed.
pub fn antipodal_grasps(
    points: &[Point3<f64>],
    normals: &[Vector3<f64>],
    cfg: &AntipodalConfig,
) -> Result<Vec<GraspCandidate>, CloudError> {
    if points.len() != normals.len() {
        return Err(CloudError::BadParameter {
            name: "normals",
            detail: format!("{} normals for {} points", normals.len(), points.len()),
        });
    }
    if points.len() < 2 {
        return Err(CloudError::BadParameter {
            name: "points",
            detail: format!("{} points: at least 2 are needed", points.len()),
        });
    }
    if !(cfg.mu.is_finite() && cfg.mu > 0.0) {
        return Err(CloudError::BadParameter {
            name: "mu",
            detail: format!("{} must be positive", cfg.mu),
        });
    }
    if !(cfg.min_width.is_finite()
        && cfg.max_width.is_finite()
        && 0.0 <= cfg.min_width
        && cfg.min_width < cfg.max_width)
    {
        return Err(CloudError::BadParameter {
            name: "min_width/max_width",
            detail: format!(
                "need 0 <= min_width {} < max_width {}",
                cfg.min_width, cfg.max_width
            ),
        });
    }
    let cos_cone = cfg.mu.atan().cos();
    let c = centroid(points);
    let down = -Vector3::z();
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut out = Vec::new();
    let mut seen = vec![false; points.len()];
    for _ in 0..cfg.samples {
        let i = rng.random_range(0..points.len());
        if std::mem::replace(&mut seen[i], true) {
            continue;
        }
        let (p1, n1) = (points[i], normals[i]);
        let mut best: Option<GraspCandidate> = None;
        for (j, (&p2, n2)) in points.iter().zip(normals).enumerate() {
            if j == i {
                continue;
            }
            let v = p2 - p1;
            let w = v.norm();
            if !(w >= cfg.min_width && w <= cfg.max_width) {
                continue;
            }
            let d = v / w;
            let (a1, a2) = (-n1.dot(&d), n2.dot(&d));
            if a1 < cos_cone || a2 < cos_cone {
                continue;
            }
            let alignment = 0.5 * (a1 + a2);
            let approach = approach_for(&d);
            let top_down = approach.dot(&down).max(0.0);
            let center = Point3::from((p1.coords + p2.coords) * 0.5);
            let centring = (1.0 - (center - c).norm() / cfg.max_width).max(0.0);
            let score =
                cfg.w_alignment * alignment + cfg.w_top_down * top_down + cfg.w_center * centring;
            if best.is_none_or(|b| score > b.score) {
                best = Some(GraspCandidate {
                    grasp: TwoFingerGrasp {
                        center,
                        approach,
                        closing: d,
                    },
                    score,
                    width: w,
                    p1,
                    p2,
                    alignment,
                    top_down,
                });
            }
        }
        out.extend(best);
    }
    out.sort_by(|a, b| b.score.total_cmp(&a.score));
    Ok(out)
}

/// The unit direction orthogonal to `d` (unit) closest to world `-z`; for a vertical
/// `d`, the direction orthogonal to `d` closest to world `x`.
fn approach_for(d: &Vector3<f64>) -> Vector3<f64> {
    let down = -Vector3::z();
    (down - d * d.dot(&down))
        .try_normalize(1e-6)
        .or_else(|| (Vector3::x() - d * d.x).try_normalize(1e-6))
        .unwrap_or_else(Vector3::y)
}

/// The top-down grasp across the cloud's narrowest horizontal extent: the fallback where
/// the antipodal sampler finds no usable pair (a flat or thin object lying down, whose
/// sides the cameras see at grazing angles or not at all).
///
/// The closing direction is the minor axis of the covariance of the points' horizontal
/// coordinates: with `a = var(x)`, `b = cov(x, y)`, `c = var(y)`, the major axis lies at
/// `theta = atan2(2b, a - c) / 2` and the closing direction at `theta + pi/2`, its sign
/// chosen with a positive `x` (positive `y` when `x` is 0). The centre is the points'
/// horizontal centroid at the middle of their height range; the approach is straight
/// down. `None` for fewer than 3 points or non-finite coordinates.
pub fn principal_axis_grasp(points: &[Point3<f64>]) -> Option<TwoFingerGrasp> {
    if points.len() < 3
        || points
            .iter()
            .any(|p| !p.coords.iter().all(|v| v.is_finite()))
    {
        return None;
    }
    let c = centroid(points);
    let n = points.len() as f64;
    let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
    let (mut zlo, mut zhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in points {
        let (dx, dy) = (p.x - c.x, p.y - c.y);
        a += dx * dx;
        b += dx * dy;
        cc += dy * dy;
        zlo = zlo.min(p.z);
        zhi = zhi.max(p.z);
    }
    let theta = 0.5 * (2.0 * b / n).atan2((a - cc) / n) + std::f64::consts::FRAC_PI_2;
    let (mut x, mut y) = (theta.cos(), theta.sin());
    if x < -1e-12 || (x.abs() <= 1e-12 && y < 0.0) {
        (x, y) = (-x, -y);
    }
    Some(TwoFingerGrasp {
        center: Point3::new(c.x, c.y, 0.5 * (zlo + zhi)),
        approach: -Vector3::z(),
        closing: Vector3::new(x, y, 0.0),
    })
}

/// The one-call pipeline from points to sorted candidates: normals by local PCA with
/// `cfg.normal_k` neighbours (oriented away from the centroid), then [`antipodal_grasps`].
pub fn grasp_candidates(
    points: &[Point3<f64>],
    cfg: &AntipodalConfig,
) -> Result<Vec<GraspCandidate>, CloudError> {
    let normals = estimate_normals(points, cfg.normal_k)?;
    antipodal_grasps(points, &normals, cfg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::partial_view::{sample_box_surface, sample_cylinder_surface};

    #[test]
    fn normals_on_a_plane_and_a_box_point_outward() {
        // Plane z = 0 on a grid, centroid below it is impossible: use a box.
        let s =
            sample_box_surface(Point3::origin(), Vector3::new(0.03, 0.03, 0.03), 1500, 5).unwrap();
        let n = estimate_normals(&s.points, 12).unwrap();
        // Away from the edges, the PCA normal equals the face normal.
        let mut checked = 0;
        for ((p, est), truth) in s.points.iter().zip(&n).zip(&s.normals) {
            let inner = (0..3).filter(|&a| p[a].abs() < 0.02).count() == 2;
            if inner {
                assert!(est.dot(truth) > 0.99, "{p} {est} {truth}");
                checked += 1;
            }
        }
        assert!(checked > 300);
        assert!(estimate_normals(&s.points[..5], 12).is_err());
        assert!(estimate_normals(&s.points, 2).is_err());
    }

    #[test]
    fn best_grasp_on_a_6cm_box_closes_across_opposite_faces_at_the_centre() {
        let c = Point3::new(0.4, -0.1, 0.03);
        let s = sample_box_surface(c, Vector3::new(0.03, 0.03, 0.03), 2000, 11).unwrap();
        let cfg = AntipodalConfig::default();
        let g = grasp_candidates(&s.points, &cfg).unwrap();
        assert!(!g.is_empty());
        let best = g[0];
        assert!((best.width - 0.06).abs() < 0.005, "width {}", best.width);
        assert!(
            (best.grasp.center - c).norm() < 0.01,
            "centre {}",
            best.grasp.center
        );
        // Closing across the x or y faces (horizontal), approach straight down.
        let d = best.grasp.closing;
        assert!(d.x.abs().max(d.y.abs()) > 0.98, "{d}");
        assert!(best.grasp.approach.dot(&-Vector3::z()) > 0.98);
        assert!(best.grasp.approach.dot(&d).abs() < 1e-9);
        assert!(best.grasp.frame().is_ok());
        // Sorted and deterministic.
        assert!(g.windows(2).all(|w| w[0].score >= w[1].score));
        assert_eq!(g, grasp_candidates(&s.points, &cfg).unwrap());
    }

    #[test]
    fn best_grasp_on_a_cylinder_closes_across_the_diameter() {
        let c = Point3::new(0.0, 0.0, 0.04);
        let s = sample_cylinder_surface(c, 0.025, 0.08, 2000, 2).unwrap();
        let g = grasp_candidates(&s.points, &AntipodalConfig::default()).unwrap();
        let best = g[0];
        assert!((best.width - 0.05).abs() < 0.005, "width {}", best.width);
        assert!(best.grasp.closing.z.abs() < 0.2);
        assert!((best.grasp.center - c).norm() < 0.015);
        // Too narrow a gripper finds nothing across a 5 cm cylinder side, only caps are
        // 8 cm apart: with max_width 0.04 no antipodal pair exists.
        let narrow = AntipodalConfig {
            max_width: 0.04,
            ..AntipodalConfig::default()
        };
        assert!(grasp_candidates(&s.points, &narrow).unwrap().is_empty());
    }

    #[test]
    fn antipodal_hand_computed_pair() {
        // Two points 5 cm apart on x with normals pointing away from each other.
        let pts = [Point3::new(-0.025, 0.0, 0.0), Point3::new(0.025, 0.0, 0.0)];
        let nrm = [-Vector3::x(), Vector3::x()];
        let cfg = AntipodalConfig {
            samples: 50,
            w_center: 0.0,
            ..AntipodalConfig::default()
        };
        let g = antipodal_grasps(&pts, &nrm, &cfg).unwrap();
        assert_eq!(g.len(), 2);
        // alignment 1, top-down 1 -> score 1 + 0.5 = 1.5
        assert!((g[0].score - 1.5).abs() < 1e-12);
        assert!((g[0].width - 0.05).abs() < 1e-12);
        // Tilt the second normal by 30 deg (inside atan 0.5 = 26.6 deg? no: outside).
        let t = 30f64.to_radians();
        let nrm2 = [-Vector3::x(), Vector3::new(t.cos(), t.sin(), 0.0)];
        assert!(antipodal_grasps(&pts, &nrm2, &cfg).unwrap().is_empty());
        let t = 20f64.to_radians();
        let nrm3 = [-Vector3::x(), Vector3::new(t.cos(), t.sin(), 0.0)];
        let g = antipodal_grasps(&pts, &nrm3, &cfg).unwrap();
        assert!((g[0].alignment - (1.0 + t.cos()) / 2.0).abs() < 1e-12);
        assert!(antipodal_grasps(&pts, &nrm[..1], &cfg).is_err());
    }

    #[test]
    fn principal_axis_grasp_hand_computed() {
        // (+-2, 0, 0) and (0, +-1, 0.02): var x = 8/4 = 2, var y = 2/4 = 0.5, cov 0: the
        // major axis is x (theta = 0), so the grasp closes along y, at the centroid, at
        // the middle of the height range (0.01), straight down.
        let pts = [
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(-2.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.02),
            Point3::new(0.0, -1.0, 0.02),
        ];
        let g = principal_axis_grasp(&pts).unwrap();
        assert!((g.closing - Vector3::y()).norm() < 1e-12, "{}", g.closing);
        assert!((g.center - Point3::new(0.0, 0.0, 0.01)).norm() < 1e-12);
        assert_eq!(g.approach, -Vector3::z());
        // The same cross turned by 0.5 rad and moved: the closing direction turns with it,
        // (-sin 0.5, cos 0.5) with its sign flipped to a positive x.
        let (s, c) = (0.5f64.sin(), 0.5f64.cos());
        let moved: Vec<Point3<f64>> = pts
            .iter()
            .map(|p| Point3::new(c * p.x - s * p.y + 0.3, s * p.x + c * p.y - 0.1, p.z))
            .collect();
        let g = principal_axis_grasp(&moved).unwrap();
        assert!(
            (g.closing - Vector3::new(s, -c, 0.0)).norm() < 1e-12,
            "{}",
            g.closing
        );
        assert!((g.center - Point3::new(0.3, -0.1, 0.01)).norm() < 1e-12);
        assert!(principal_axis_grasp(&pts[..2]).is_none());
        let mut bad = pts.to_vec();
        bad[1].y = f64::NAN;
        assert!(principal_axis_grasp(&bad).is_none());
    }
}
