//! Stable rest poses: which face of its convex hull an object should stand on.
//!
//! A rigid body resting on a flat table touches it with one face of its convex hull (the
//! support polygon). It stays put under gravity when the vertical through its centre of
//! mass passes inside that polygon, and the margin of that stability is the **tipping
//! angle**: the angle it must be tilted about the nearest polygon edge before its centre
//! of mass passes over that edge,
//!
//! ```text
//! tipping angle = atan2(d, h)
//! ```
//!
//! with `d` the distance from the centre of mass's projection to the nearest edge
//! (negative when the projection lies outside, i.e. the face is not a rest pose) and `h`
//! the height of the centre of mass above the face.
//!
//! Generated shapes (a pear standing on its round end, a blob, a banana) and user meshes
//! are not always made in a pose they can rest in, and a pose that is stable by a fraction
//! of a degree is upset by the first contact. [`rest_rotation`] keeps the object's own
//! orientation when its bottom face is stable by at least [`KEEP_TIPPING_ANGLE`], and
//! otherwise turns it onto the stable face (positive tipping angle) with the lowest centre
//! of mass: the bottom of its potential well, where a rounded shape (a tessellated blob,
//! whose every facet is stable by a fraction of a degree) comes to rest.

use nalgebra::{Rotation3, Unit, Vector2, Vector3};

/// The tipping angle (rad) above which an object keeps the orientation it was made in
/// (about 8.6 degrees; a standing bottle has about 20).
pub const KEEP_TIPPING_ANGLE: f64 = 0.15;

/// Points within this distance (m) of a face's plane touch the table with it.
const COPLANAR_TOL: f64 = 1e-4;

/// One candidate rest face of a convex hull.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestFace {
    /// Outward unit normal of the face (it points down, into the table, at rest).
    pub normal: [f64; 3],
    /// Tipping angle in radians (negative: the object falls off this face).
    pub tipping_angle: f64,
    /// Height of the centre of mass above the table when resting on this face (m).
    pub com_height: f64,
}

/// The tipping angle of the face of the convex hull of `points` whose outward normal is
/// `normal`, for a centre of mass `com`. `None` if fewer than three points touch the
/// plane or the centre of mass is not above it.
pub fn tipping_angle(points: &[[f64; 3]], com: [f64; 3], normal: [f64; 3]) -> Option<f64> {
    face_stability(points, com, normal).map(|(angle, _)| angle)
}

/// The tipping angle and the centre of mass's height of one face (see [`tipping_angle`]).
fn face_stability(points: &[[f64; 3]], com: [f64; 3], normal: [f64; 3]) -> Option<(f64, f64)> {
    let n = Unit::try_new(Vector3::from(normal), 1e-12)?;
    let c = Vector3::from(com);
    let offset = points
        .iter()
        .map(|p| n.dot(&Vector3::from(*p)))
        .fold(f64::NEG_INFINITY, f64::max);
    let h = offset - n.dot(&c);
    if h.is_nan() || h <= 0.0 {
        return None;
    }
    // An orthonormal basis (u, v) of the plane.
    let u = Unit::new_normalize(n.cross(&if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    }));
    let v = n.cross(&u);
    let flat = |p: &Vector3<f64>| Vector2::new(u.dot(p), v.dot(p));
    let touching: Vec<Vector2<f64>> = points
        .iter()
        .map(|p| Vector3::from(*p))
        .filter(|p| n.dot(p) >= offset - COPLANAR_TOL)
        .map(|p| flat(&p))
        .collect();
    let polygon = convex_hull_2d(touching);
    if polygon.len() < 3 {
        return None;
    }
    Some((signed_distance_inside(&polygon, flat(&c)).atan2(h), h))
}

/// Every distinct face of the convex hull given by `hull` (an outward-oriented closed
/// triangle mesh), with its tipping angle for `com`, most stable first.
pub fn rest_faces(hull: &super::TriMesh, com: [f64; 3]) -> Vec<RestFace> {
    let mut normals: Vec<Vector3<f64>> = Vec::new();
    for t in &hull.triangles {
        let [a, b, c] = t.map(|i| Vector3::from(hull.vertices[i as usize]));
        let Some(n) = Unit::try_new((b - a).cross(&(c - a)), 1e-18) else {
            continue;
        };
        if !normals.iter().any(|m| m.dot(&n) > 1.0 - 1e-6) {
            normals.push(n.into_inner());
        }
    }
    let mut faces: Vec<RestFace> = normals
        .into_iter()
        .filter_map(|n| {
            let normal = [n.x, n.y, n.z];
            face_stability(&hull.vertices, com, normal).map(|(tipping_angle, com_height)| {
                RestFace {
                    normal,
                    tipping_angle,
                    com_height,
                }
            })
        })
        .collect();
    faces.sort_by(|a, b| b.tipping_angle.total_cmp(&a.tipping_angle));
    faces
}

/// The rotation to apply to an object (about its frame's origin) so that it rests on a
/// stable face, or `None` to keep it as made (see the module docs). `hull` is the convex
/// hull of its collision geometry, `com` its centre of mass.
pub fn rest_rotation(hull: &super::TriMesh, com: [f64; 3]) -> Option<Rotation3<f64>> {
    let faces = rest_faces(hull, com);
    let down = Vector3::new(0.0, 0.0, -1.0);
    // The face the object stands on as made (normal straight down).
    let is_bottom = |f: &RestFace| Vector3::from(f.normal).dot(&down) > 1.0 - 1e-6;
    let own = faces
        .iter()
        .find(|f| is_bottom(f))
        .map_or(f64::NEG_INFINITY, |f| f.tipping_angle);
    if own >= KEEP_TIPPING_ANGLE {
        return None;
    }
    let lowest = faces
        .iter()
        .filter(|f| f.tipping_angle > 0.0)
        .min_by(|a, b| a.com_height.total_cmp(&b.com_height))?;
    if own > 0.0 && is_bottom(lowest) {
        return None;
    }
    let n = Vector3::from(lowest.normal);
    Some(
        Rotation3::rotation_between(&n, &down).unwrap_or_else(|| {
            Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
        }),
    )
}

/// Andrew's monotone chain: the convex hull of `pts`, counter-clockwise, without
/// collinear points.
fn convex_hull_2d(mut pts: Vec<Vector2<f64>>) -> Vec<Vector2<f64>> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup_by(|a, b| (*a - *b).norm() < 1e-12);
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| {
        (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
    };
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vector2<f64>>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], *p) <= 1e-18
            {
                hull.pop();
            }
            hull.push(*p);
        }
        hull.pop();
    }
    hull
}

/// Distance from `p` to the boundary of the counter-clockwise convex `polygon`: positive
/// inside, negative outside.
fn signed_distance_inside(polygon: &[Vector2<f64>], p: Vector2<f64>) -> f64 {
    let mut inside = f64::INFINITY;
    let mut outside: f64 = 0.0;
    for i in 0..polygon.len() {
        let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        let e = b - a;
        let len = e.norm();
        // Signed distance to the edge's line, positive on the inner (left) side.
        let line = (e.x * (p.y - a.y) - e.y * (p.x - a.x)) / len;
        inside = inside.min(line);
        if line < 0.0 {
            let t = ((p - a).dot(&e) / (len * len)).clamp(0.0, 1.0);
            outside = outside.max((p - (a + e * t)).norm());
        }
    }
    if inside >= 0.0 {
        inside
    } else {
        -outside
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::convex_hull_mesh;
    use approx::assert_relative_eq;

    fn box_points(hx: f64, hy: f64, hz: f64) -> Vec<[f64; 3]> {
        let mut v = Vec::new();
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [0.0, 2.0] {
                    v.push([sx * hx, sy * hy, sz * hz]);
                }
            }
        }
        v
    }

    #[test]
    fn box_bottom_face_tipping_angle_is_atan_of_half_width_over_com_height() {
        // A 4 x 6 x 10 cm box standing on its 4 x 6 face, centre of mass at its centre:
        // nearest edge 2 cm away, centre of mass 5 cm up: atan(2 / 5).
        let pts = box_points(0.02, 0.03, 0.05);
        let a = tipping_angle(&pts, [0.0, 0.0, 0.05], [0.0, 0.0, -1.0]).unwrap();
        assert_relative_eq!(a, (0.02f64).atan2(0.05), epsilon = 1e-9);
        // Lying on its 6 x 10 side (normal -x): half-width 3 cm... the nearest edge of the
        // 6 x 10 face is 3 cm away, the centre of mass 2 cm above: atan(3 / 2).
        let s = tipping_angle(&pts, [0.0, 0.0, 0.05], [-1.0, 0.0, 0.0]).unwrap();
        assert_relative_eq!(s, (0.03f64).atan2(0.02), epsilon = 1e-9);
    }

    #[test]
    fn off_centre_mass_outside_the_face_gives_a_negative_angle() {
        // A 2 x 2 cm footprint with the centre of mass 3 cm sideways and 4 cm up: 2 cm
        // outside the nearest edge: atan2(-2, 4).
        let pts = box_points(0.01, 0.01, 0.05);
        let a = tipping_angle(&pts, [0.03, 0.0, 0.04], [0.0, 0.0, -1.0]).unwrap();
        assert_relative_eq!(a, (-0.02f64).atan2(0.04), epsilon = 1e-9);
        // A centre of mass below the face's plane is not a rest pose at all.
        assert!(tipping_angle(&pts, [0.0, 0.0, -0.01], [0.0, 0.0, -1.0]).is_none());
    }

    #[test]
    fn polygon_distance_inside_and_outside() {
        let sq = convex_hull_2d(vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(0.0, 1.0),
            Vector2::new(0.5, 0.0), // collinear, dropped
            Vector2::new(0.5, 0.5), // interior, dropped
        ]);
        assert_eq!(sq.len(), 4);
        assert_relative_eq!(signed_distance_inside(&sq, Vector2::new(0.25, 0.5)), 0.25);
        assert_relative_eq!(signed_distance_inside(&sq, Vector2::new(2.0, 0.5)), -1.0);
        // Outside past a corner: the distance to the corner.
        assert_relative_eq!(
            signed_distance_inside(&sq, Vector2::new(4.0, 5.0)),
            -5.0,
            epsilon = 1e-12
        );
    }

    #[test]
    fn a_standing_box_keeps_its_pose_and_a_toppling_one_is_turned() {
        // Upright 4 x 6 x 10 cm: stable by atan(2/5) = 0.38 rad > 0.15: kept.
        let upright = convex_hull_mesh(&box_points(0.02, 0.03, 0.05)).unwrap();
        assert!(rest_rotation(&upright, [0.0, 0.0, 0.05]).is_none());
        // A 1 x 1 cm footprint 20 cm tall with its mass 4 mm off-centre at 15 cm: stable
        // by atan(1 / 150) only, so it is laid on the side nearest its centre of mass
        // (normal +x: 5 mm to the nearest edge, the centre of mass 1 mm high: the lowest,
        // and the most stable, atan(5) rad).
        let stick = convex_hull_mesh(&box_points(0.005, 0.005, 0.1)).unwrap();
        let com = [0.004, 0.0, 0.15];
        let faces = rest_faces(&stick, com);
        assert_relative_eq!(faces[0].tipping_angle, 5.0f64.atan(), epsilon = 1e-6);
        assert_relative_eq!(faces[0].com_height, 0.001, epsilon = 1e-9);
        assert_relative_eq!(faces[0].normal[0], 1.0, epsilon = 1e-9);
        let r = rest_rotation(&stick, com).expect("turned");
        let down = r * Vector3::from(faces[0].normal);
        assert_relative_eq!(down, Vector3::new(0.0, 0.0, -1.0), epsilon = 1e-9);
        // An ellipsoid (semi-axes 5, 3, 1.5 cm) made standing on its long axis: every
        // facet is barely stable, so it is laid on its flattest side, the centre of mass
        // about 1.5 cm high (the tessellation flattens it slightly).
        let mut egg = crate::objects::shape_kit::icosphere(3);
        egg.scale([0.015, 0.03, 0.05]);
        let hull = convex_hull_mesh(&egg.vertices).unwrap();
        let r = rest_rotation(&hull, [0.0; 3]).expect("turned");
        let low = egg
            .vertices
            .iter()
            .map(|p| (r * Vector3::from(*p)).z)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (-low - 0.015).abs() < 1e-3,
            "centre of mass {} m high",
            -low
        );
        // A wide plate stays as it is.
        let flat = convex_hull_mesh(&box_points(0.05, 0.05, 0.005)).unwrap();
        assert!(rest_rotation(&flat, [0.0, 0.0, 0.005]).is_none());
    }
}
