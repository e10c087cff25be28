//! Simulated depth cameras: the point cloud a robot's cameras would see of the
//! simulator's object where it rests. `grasp run --backend sim` plans on it, and so does
//! the antipodal pre-grasp ([`super::pregrasp`]) in evaluation and training.

use super::partial_view::{partial_view, SurfaceSamples};
use super::pointcloud::CloudError;
use crate::sim::HandSim;
use nalgebra::{Point3, Vector3};
use rapier3d::math::Pose;
use rapier3d::parry::query::Ray;

/// Simulated depth cameras looking at the object: each casts a square grid of rays
/// toward the object's centre against its collision shape (so self-occlusion is exact),
/// and the hits get Gaussian noise ([`partial_view`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Camera positions relative to the object's centre (m). The default is four views, one
    /// from each side (+x, -x, +y, -y), 45 degrees above the table, as a wrist camera
    /// scanning the object from around it would take: a single view of a box shows no pair
    /// of opposite faces, which the antipodal sampler needs, and two views from +-x see the
    /// +-y sides only at grazing angles, so that a flat or thin object lying along x (the
    /// spatula, the wedge) offers no pair across its width (two views until 2026-12-05
    /// evening: docs/results.md, "The planner's views").
    pub positions: Vec<[f64; 3]>,
    /// Rays per side of each camera's square grid.
    pub resolution: usize,
    /// Depth noise, standard deviation (m).
    pub noise_sigma: f64,
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            positions: vec![
                [0.35, 0.0, 0.35],
                [-0.35, 0.0, 0.35],
                [0.0, 0.35, 0.35],
                [0.0, -0.35, 0.35],
            ],
            resolution: 48,
            noise_sigma: super::partial_view::DEFAULT_NOISE_SIGMA,
        }
    }
}

/// The point cloud the depth cameras of `cam` see of the simulator's object in its current
/// pose (world frame, m), with noise drawn from `seed` (see [`CameraConfig`]).
pub fn camera_cloud(
    sim: &HandSim,
    cam: &CameraConfig,
    seed: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    let [px, py, pz, qx, qy, qz, qw] = sim.object_pose_raw();
    let body = Pose::from_parts(
        rapier3d::math::Vector::new(px, py, pz),
        rapier3d::math::Rotation::from_xyzw(qx, qy, qz, qw),
    );
    camera_cloud_at(sim.object(), &body, cam, seed)
}

/// The point cloud the depth cameras of `cam` see of `object` with its body at `body`
/// (world frame): [`camera_cloud`] for an object another engine moved.
pub fn camera_cloud_at(
    object: &crate::sim::ObjectSpec,
    body: &Pose,
    cam: &CameraConfig,
    seed: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    if cam.positions.is_empty() || cam.resolution < 2 {
        return Err(CloudError::BadParameter {
            name: "cameras",
            detail: "need at least one camera and a resolution of at least 2".into(),
        });
    }
    let builder = object.shape.collider();
    let shape_pose = *body * builder.position;
    let shape = builder.shape;
    let t = body.translation;
    let centre = Point3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z));
    let h = object.shape.half_extents();
    let radius = 1.1 * Vector3::from(h).norm();
    let mut cloud = Vec::new();
    for (k, rel) in cam.positions.iter().enumerate() {
        let rel = Vector3::from(*rel);
        let dist = rel.norm();
        if !(dist.is_finite() && dist > radius) {
            return Err(CloudError::BadParameter {
                name: "cameras.positions",
                detail: format!("camera {k} is not outside the object's bounding sphere"),
            });
        }
        let origin = centre + rel;
        let f = -rel / dist;
        let r = f
            .cross(&Vector3::z())
            .try_normalize(1e-9)
            .unwrap_or_else(Vector3::x);
        let u = r.cross(&f);
        let spread = radius / (dist * dist - radius * radius).sqrt();
        let n = cam.resolution;
        let mut surf = SurfaceSamples::default();
        for i in 0..n {
            for j in 0..n {
                let s = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
                let t = -1.0 + 2.0 * j as f64 / (n - 1) as f64;
                let d = (f + spread * (s * r + t * u)).normalize();
                let ray = Ray::new(
                    rapier3d::math::Vector::new(origin.x as f32, origin.y as f32, origin.z as f32),
                    rapier3d::math::Vector::new(d.x as f32, d.y as f32, d.z as f32),
                );
                if let Some(hit) =
                    shape.cast_ray_and_get_normal(&shape_pose, &ray, (2.0 * dist) as f32, true)
                {
                    let toi = f64::from(hit.time_of_impact);
                    let nrm = hit.normal;
                    surf.points.push(origin + d * toi);
                    surf.normals.push(Vector3::new(
                        f64::from(nrm.x),
                        f64::from(nrm.y),
                        f64::from(nrm.z),
                    ));
                }
            }
        }
        cloud.extend(partial_view(
            &surf,
            origin,
            cam.noise_sigma,
            seed.wrapping_add(k as u64),
        )?);
    }
    Ok(cloud)
}
