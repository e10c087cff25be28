//! Synthetic point clouds: surface samples of simple shapes and the partial view a depth
//! camera would see of them.
//!
//! A camera at `cam` sees a surface point `p` with outward normal `n` when the surface
//! faces it: `n . (cam - p) > 0` (back faces are dropped; self-occlusion by other parts of
//! a non-convex object is not modelled). Each kept point gets isotropic Gaussian noise of
//! standard deviation `sigma` (default 2 mm). Everything is seeded.

use super::pointcloud::CloudError;
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Default depth noise (m).
pub const DEFAULT_NOISE_SIGMA: f64 = 0.002;

/// Surface samples: points and their outward unit normals.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceSamples {
    /// Points on the surface (m).
    pub points: Vec<Point3<f64>>,
    /// Outward unit normals, one per point.
    pub normals: Vec<Vector3<f64>>,
}

fn check_positive(name: &'static str, v: f64) -> Result<(), CloudError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(CloudError::BadParameter {
            name,
            detail: format!("{v} must be positive and finite"),
        })
    }
}

/// `n` points uniformly on the surface of an axis-aligned box with `half_extents`
/// centred at `center` (faces chosen in proportion to their area).
pub fn sample_box_surface(
    center: Point3<f64>,
    half_extents: Vector3<f64>,
    n: usize,
    seed: u64,
) -> Result<SurfaceSamples, CloudError> {
    for (name, v) in [
        ("half_extents.x", half_extents.x),
        ("half_extents.y", half_extents.y),
        ("half_extents.z", half_extents.z),
    ] {
        check_positive(name, v)?;
    }
    let h = half_extents;
    // Face areas for the x, y, z face pairs.
    let areas = [h.y * h.z, h.x * h.z, h.x * h.y];
    let total: f64 = areas.iter().sum();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s = SurfaceSamples::default();
    for _ in 0..n {
        let mut u = rng.random::<f64>() * total;
        let mut axis = 0;
        while axis < 2 && u >= areas[axis] {
            u -= areas[axis];
            axis += 1;
        }
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let mut local = Vector3::new(
            rng.random_range(-h.x..=h.x),
            rng.random_range(-h.y..=h.y),
            rng.random_range(-h.z..=h.z),
        );
        local[axis] = sign * h[axis];
        let mut normal = Vector3::zeros();
        normal[axis] = sign;
        s.points.push(center + local);
        s.normals.push(normal);
    }
    Ok(s)
}

/// `n` points uniformly on the surface of a cylinder with a vertical (z) axis, `radius`
/// and `height`, centred at `center` (side and caps in proportion to their area).
pub fn sample_cylinder_surface(
    center: Point3<f64>,
    radius: f64,
    height: f64,
    n: usize,
    seed: u64,
) -> Result<SurfaceSamples, CloudError> {
    check_positive("radius", radius)?;
    check_positive("height", height)?;
    let side = 2.0 * std::f64::consts::PI * radius * height;
    let cap = std::f64::consts::PI * radius * radius;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s = SurfaceSamples::default();
    for _ in 0..n {
        let u = rng.random::<f64>() * (side + 2.0 * cap);
        let phi = rng.random::<f64>() * std::f64::consts::TAU;
        let (c, sn) = (phi.cos(), phi.sin());
        if u < side {
            let z = rng.random_range(-height / 2.0..=height / 2.0);
            s.points
                .push(center + Vector3::new(radius * c, radius * sn, z));
            s.normals.push(Vector3::new(c, sn, 0.0));
        } else {
            // Uniform on the disc: r = R sqrt(v).
            let r = radius * rng.random::<f64>().sqrt();
            let top = u < side + cap;
            let z = if top { height / 2.0 } else { -height / 2.0 };
            s.points.push(center + Vector3::new(r * c, r * sn, z));
            s.normals
                .push(Vector3::new(0.0, 0.0, if top { 1.0 } else { -1.0 }));
        }
    }
    Ok(s)
}

/// The points of `surface` visible from a camera at `camera` (`n . (camera - p) > 0`),
/// each displaced by Gaussian noise of standard deviation `sigma` (m; 0 for none).
pub fn partial_view(
    surface: &SurfaceSamples,
    camera: Point3<f64>,
    sigma: f64,
    seed: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    if surface.points.len() != surface.normals.len() {
        return Err(CloudError::BadParameter {
            name: "normals",
            detail: format!(
                "{} normals for {} points",
                surface.normals.len(),
                surface.points.len()
            ),
        });
    }
    if !camera.coords.iter().all(|v| v.is_finite()) {
        return Err(CloudError::BadParameter {
            name: "camera",
            detail: "camera position is not finite".into(),
        });
    }
    let bad_sigma = || CloudError::BadParameter {
        name: "sigma",
        detail: format!("{sigma} must be finite and non-negative"),
    };
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(bad_sigma());
    }
    let noise = Normal::new(0.0, sigma).map_err(|_| bad_sigma())?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Ok(surface
        .points
        .iter()
        .zip(&surface.normals)
        .filter(|(p, n)| n.dot(&(camera - *p)) > 0.0)
        .map(|(p, _)| {
            let e = Vector3::new(
                noise.sample(&mut rng),
                noise.sample(&mut rng),
                noise.sample(&mut rng),
            );
            p + e
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_samples_lie_on_the_faces_with_matching_normals() {
        let c = Point3::new(0.1, 0.2, 0.3);
        let h = Vector3::new(0.03, 0.02, 0.01);
        let s = sample_box_surface(c, h, 500, 1).unwrap();
        assert_eq!(s.points.len(), 500);
        for (p, n) in s.points.iter().zip(&s.normals) {
            let l = p - c;
            let axis = n.iamax();
            assert!((l[axis] - n[axis] * h[axis]).abs() < 1e-12);
            for a in 0..3 {
                assert!(l[a].abs() <= h[a] + 1e-12);
            }
        }
        // Area-proportional: the x faces (0.02*0.01) get ~2/11 of the samples.
        let nx = s.normals.iter().filter(|n| n.x != 0.0).count() as f64 / 500.0;
        assert!((nx - 2.0 / 11.0).abs() < 0.06, "{nx}");
        assert!(sample_box_surface(c, Vector3::new(0.0, 1.0, 1.0), 5, 1).is_err());
    }

    #[test]
    fn camera_above_sees_top_and_not_bottom() {
        let s = sample_cylinder_surface(Point3::origin(), 0.03, 0.08, 2000, 3).unwrap();
        let v = partial_view(&s, Point3::new(0.0, 0.0, 1.0), 0.0, 0).unwrap();
        // Only the top cap faces a camera straight above.
        assert!(!v.is_empty());
        assert!(v.iter().all(|p| (p.z - 0.04).abs() < 1e-12));
        // A camera to the side along +x sees about half of the side, no caps.
        let v = partial_view(&s, Point3::new(10.0, 0.0, 0.0), 0.0, 0).unwrap();
        assert!(v.iter().all(|p| p.x > -1e-12 && p.z.abs() < 0.04 + 1e-12));
    }

    #[test]
    fn noise_has_the_requested_sigma_and_is_seeded() {
        let s = SurfaceSamples {
            points: vec![Point3::origin(); 4000],
            normals: vec![Vector3::z(); 4000],
        };
        let cam = Point3::new(0.0, 0.0, 1.0);
        let a = partial_view(&s, cam, 0.002, 7).unwrap();
        assert_eq!(a, partial_view(&s, cam, 0.002, 7).unwrap());
        assert_ne!(a, partial_view(&s, cam, 0.002, 8).unwrap());
        let var = a.iter().map(|p| p.coords.norm_squared()).sum::<f64>() / (3.0 * a.len() as f64);
        assert!((var.sqrt() - 0.002).abs() < 0.0001, "{}", var.sqrt());
        assert!(partial_view(&s, cam, -1.0, 0).is_err());
    }
}
