//! A fingertip's contact with a convex hull, computed exactly from the hull's faces
//! (parry's GJK puts the closest points millimetres to centimetres off on the object hulls).

use super::Manifold;
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::TrackedContact;
use rapier3d::parry::shape::{ConvexPolyhedron, PackedFeatureId, Shape, TypedShape};

/// Half length (m) under which a capsule is a ball for contact generation: the simulated
/// fingertips are balls stood in for by 0.2 mm capsules (see `HandSim::new`).
const BALL_LIKE_HALF_LENGTH: Real = 5.0e-4;

/// A ball, or a capsule short enough to be one: its centre (shape frame) and radius.
pub(super) fn ball_like(shape: &dyn Shape) -> Option<(Vector, Real)> {
    match shape.as_typed_shape() {
        TypedShape::Ball(b) => Some((Vector::ZERO, b.radius)),
        TypedShape::Capsule(c) if c.half_height() < BALL_LIKE_HALF_LENGTH => {
            Some((c.center(), c.radius))
        }
        _ => None,
    }
}

/// Which of a pair's two shapes is the ball: its centre (in its own frame) and radius.
#[derive(Debug, Clone, Copy)]
pub(super) enum BallSide {
    First((Vector, Real)),
    Second((Vector, Real)),
}

/// The signed distance of a point `c` from a convex polyhedron (in its frame), the
/// outward normal there and the nearest surface point, computed exactly from the faces.
/// Inside, the nearest surface point is on the face whose plane the point is least far
/// behind. Outside, it is on one of the faces the point is in front of: its projection
/// onto the face's plane when that falls within the face, else the nearest point of the
/// face's border. (parry's point projection runs GJK, which was traced returning a
/// fingertip centre 14 mm from an apple hull whose nearest vertex was 4 mm away.)
fn point_hull_distance(hull: &ConvexPolyhedron, c: Vector) -> (Real, Vector, Vector) {
    let points = hull.points();
    let adj = hull.vertices_adj_to_face();
    // One pass over the faces: the deepest face plane (the answer inside) and, over the
    // faces the point is in front of, the nearest face point (the answer outside). A
    // face's plane distance bounds its points' distance from below, so faces no nearer
    // than the best so far are skipped.
    let (mut deepest, mut n) = (Real::NEG_INFINITY, Vector::Z);
    let mut best = (Real::MAX, c);
    for f in hull.faces() {
        let first = f.first_vertex_or_edge as usize;
        let ids = &adj[first..first + f.num_vertices_or_edges as usize];
        let s = f.normal.dot(c - points[ids[0] as usize]);
        if s > deepest {
            (deepest, n) = (s, f.normal);
        }
        if s <= 0.0 || s >= best.0 {
            continue;
        }
        let p = c - f.normal * s;
        let mut inside = true;
        let mut nearest = (Real::MAX, p);
        for (k, &i) in ids.iter().enumerate() {
            let a = points[i as usize];
            let b = points[ids[(k + 1) % ids.len()] as usize];
            let ab = b - a;
            if ab.cross(p - a).dot(f.normal) < 0.0 {
                inside = false;
            }
            let t = ((c - a).dot(ab) / ab.length_squared().max(Real::MIN_POSITIVE)).clamp(0.0, 1.0);
            let q = a + ab * t;
            let d = (c - q).length();
            if d < nearest.0 {
                nearest = (d, q);
            }
        }
        let candidate = if inside { (s, p) } else { nearest };
        if candidate.0 < best.0 {
            best = candidate;
        }
    }
    if deepest <= 0.0 {
        return (deepest, n, c - n * deepest);
    }
    let (dist, on_hull) = best;
    let normal = (c - on_hull).try_normalize().unwrap_or(n);
    (dist, normal, on_hull)
}

/// The contact manifold of a ball and a convex hull, computed exactly: one point, at the
/// ball's centre's nearest hull point, with the hull's outward normal there (see
/// [`point_hull_distance`]). parry builds it with GJK, whose closest points on an object
/// hull are millimetres to centimetres off (up to 17 mm on the apple's hull, unit test
/// below): traced, `grasp --seed 1 sim --object apple --close --lift --noise 0.015` sank
/// the ring fingertip 10.1 mm into the apple, its manifold claiming 0.3 mm where the shapes
/// overlapped by 5 mm along its own normal; with this manifold, 1.1 mm. The point keeps the
/// previous one's solver data (warm-start impulses).
pub(super) fn ball_hull_manifold(
    pos12: &Pose,
    ball: BallSide,
    hull: &ConvexPolyhedron,
    prediction: Real,
    manifold: &mut Manifold,
) {
    // The ball's centre in the hull's frame, and the map of hull directions to the
    // ball's frame.
    let ((centre, radius), to_hull) = match ball {
        BallSide::First(b) => (b, pos12.inverse()),
        BallSide::Second(b) => (b, *pos12),
    };
    let c = to_hull * centre;
    let (dist, n_hull, on_hull) = point_hull_distance(hull, c);
    let dist = dist - radius;
    // The normal (hull outward) and the ball's surface point toward the hull, in the
    // ball's frame.
    let n_ball = to_hull.rotation.inverse() * n_hull;
    let on_ball = centre - n_ball * radius;
    let data = manifold.points.first().map(|p| p.data);
    manifold.points.clear();
    let (n1, n2, p1, p2) = match ball {
        BallSide::First(_) => (-n_ball, n_hull, on_ball, on_hull),
        BallSide::Second(_) => (n_hull, -n_ball, on_hull, on_ball),
    };
    manifold.local_n1 = n1;
    manifold.local_n2 = n2;
    if dist > prediction {
        return;
    }
    let mut point = TrackedContact::new(
        p1,
        p2,
        PackedFeatureId::UNKNOWN,
        PackedFeatureId::UNKNOWN,
        dist,
    );
    if let Some(data) = data {
        point.data = data;
    }
    manifold.points.push(point);
}

#[cfg(test)]
mod tests {
    use super::super::test_shapes::cube;
    use super::super::HullContactDispatcher;
    use super::*;
    use rapier3d::parry::query::ContactManifold;
    use rapier3d::parry::query::PersistentQueryDispatcher;

    #[test]
    fn point_hull_distance_hand_computed() {
        let hull = cube();
        let close = |a: Vector, b: Vector| (a - b).length() < 1e-5;
        // Above the top face's centre: the plane distance, straight down.
        let (d, n, p) = point_hull_distance(&hull, Vector::new(0.1, 0.2, 2.0));
        assert!((d - 1.5).abs() < 1e-5, "{d}");
        assert!(
            close(n, Vector::Z) && close(p, Vector::new(0.1, 0.2, 0.5)),
            "{n} {p}"
        );
        // Inside, nearest the top face: minus the depth under it.
        let (d, n, p) = point_hull_distance(&hull, Vector::new(0.0, 0.1, 0.3));
        assert!((d + 0.2).abs() < 1e-5, "{d}");
        assert!(
            close(n, Vector::Z) && close(p, Vector::new(0.0, 0.1, 0.5)),
            "{n} {p}"
        );
        // Beside an edge: the edge's nearest point, 0.5 sqrt(2) away.
        let (d, n, p) = point_hull_distance(&hull, Vector::new(1.0, 1.0, 0.1));
        assert!((d - 0.5 * 2f32.sqrt()).abs() < 1e-5, "{d}");
        let diag = Vector::new(1.0, 1.0, 0.0).normalize();
        assert!(
            close(n, diag) && close(p, Vector::new(0.5, 0.5, 0.1)),
            "{n} {p}"
        );
        // Beyond a corner: the corner.
        let (d, _, p) = point_hull_distance(&hull, Vector::splat(1.0));
        assert!((d - 0.5 * 3f32.sqrt()).abs() < 1e-5, "{d}");
        assert!(close(p, Vector::splat(0.5)), "{p}");
    }

    /// The built-in apple's hull (one convex piece) and query points around it, from 5 mm
    /// inside its surface to 2 cm outside, along random directions from its centre.
    fn apple_hull_and_queries() -> (ConvexPolyhedron, Vec<Vector>) {
        use rand::{Rng, SeedableRng};
        let ctx = crate::objects::BuildContext::uncached();
        let apple = crate::objects::load_objects("apple", &ctx)
            .unwrap()
            .remove(0);
        let hull = apple
            .collider_parts()
            .unwrap()
            .into_iter()
            .find_map(|(pose, s)| {
                let points: Vec<Vector> = s
                    .as_convex_polyhedron()?
                    .points()
                    .iter()
                    .map(|p| pose * *p)
                    .collect();
                ConvexPolyhedron::from_convex_hull(&points)
            })
            .unwrap();
        let n = hull.points().len() as f32;
        let centre = hull.points().iter().fold(Vector::ZERO, |a, p| a + *p) / n;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let queries = (0..400)
            .map(|_| {
                let d = loop {
                    let v = Vector::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    if let Some(v) = v.try_normalize().filter(|_| v.length() <= 1.0) {
                        break v;
                    }
                };
                let reach = hull
                    .points()
                    .iter()
                    .map(|p| (*p - centre).dot(d))
                    .fold(Real::MIN, Real::max);
                centre + d * (reach + rng.random_range(-0.005..0.02))
            })
            .collect();
        (hull, queries)
    }

    /// The distance from `c` to the hull's nearest vertex.
    fn nearest_vertex(hull: &ConvexPolyhedron, c: Vector) -> Real {
        hull.points()
            .iter()
            .map(|v| (c - *v).length())
            .fold(Real::MAX, Real::min)
    }

    #[test]
    fn point_hull_distance_is_bracketed_by_the_faces_and_the_vertices() {
        // Outside a convex hull, a point is no nearer than its farthest face plane and no
        // farther than its nearest vertex; inside, its depth is the nearest plane's.
        let (hull, queries) = apple_hull_and_queries();
        let mut outside = 0;
        for c in queries {
            let (d, n, p) = point_hull_distance(&hull, c);
            let plane = hull
                .faces()
                .iter()
                .map(|f| {
                    let v = hull.points()
                        [hull.vertices_adj_to_face()[f.first_vertex_or_edge as usize] as usize];
                    f.normal.dot(c - v)
                })
                .fold(Real::NEG_INFINITY, Real::max);
            let vertex = nearest_vertex(&hull, c);
            if plane > 0.0 {
                outside += 1;
                assert!(
                    d >= plane - 1e-4 && d <= vertex + 1e-6,
                    "{plane} <= {d} <= {vertex}"
                );
                assert!(((c - p).length() - d).abs() < 1e-5 && n.dot(c - p) > 0.0);
            } else {
                assert!((d - plane).abs() < 1e-6, "{d} vs {plane}");
            }
        }
        assert!(outside > 300, "{outside}");
    }

    #[test]
    fn parry_point_projection_on_the_apple_hull_is_millimetres_off() {
        // The defect behind the exact fingertip contact, as parry 0.31 has it: its GJK
        // projection puts some points outside this hull farther than their nearest vertex
        // (traced on the apple: 14 mm against 4 mm).
        use rapier3d::parry::query::PointQuery;
        let (hull, queries) = apple_hull_and_queries();
        let worst = queries
            .iter()
            .map(|&c| {
                let proj = hull.project_local_point(c, true);
                let vertex = nearest_vertex(&hull, c);
                (c - proj.point).length() - vertex
            })
            .fold(Real::NEG_INFINITY, Real::max);
        assert!(worst > 0.005, "{worst}");
    }

    #[test]
    fn ball_hull_manifold_is_the_exact_contact_and_keeps_its_warm_start() {
        let hull = cube();
        let tip = rapier3d::parry::shape::Capsule::new_z(1.0e-4, 0.1);
        // The ball's centre 0.55 above the cube's centre: 0.05 deep.
        let pos12 = Pose::from_translation(Vector::new(0.1, 0.0, -0.55));
        let mut m: Manifold = ContactManifold::new();
        HullContactDispatcher::CHECKED
            .contact_manifold_convex_convex(&pos12, &tip, &hull, None, None, 0.01, &mut m)
            .unwrap();
        assert_eq!(m.points.len(), 1);
        let pt = m.points[0];
        assert!((pt.dist + 0.05).abs() < 1e-5, "{}", pt.dist);
        assert!((m.local_n1 + Vector::Z).length() < 1e-5, "{}", m.local_n1);
        assert!((pt.local_p1 - Vector::new(0.0, 0.0, -0.1)).length() < 1e-5);
        assert!((pt.local_p2 - Vector::new(-0.1, 0.0, 0.5)).length() < 1e-5);
        // The other order: the hull first, its normal up.
        let mut r: Manifold = ContactManifold::new();
        HullContactDispatcher::CHECKED
            .contact_manifold_convex_convex(&pos12.inverse(), &hull, &tip, None, None, 0.01, &mut r)
            .unwrap();
        assert!((r.points[0].dist + 0.05).abs() < 1e-5 && (r.local_n1 - Vector::Z).length() < 1e-5);
        // The next step's point keeps the solver's warm start; beyond the prediction
        // distance there is none.
        m.points[0].data.warmstart_impulse = 3.0;
        HullContactDispatcher::CHECKED
            .contact_manifold_convex_convex(&pos12, &tip, &hull, None, None, 0.01, &mut m)
            .unwrap();
        assert_eq!(m.points[0].data.warmstart_impulse, 3.0);
        let far = Pose::from_translation(Vector::new(0.0, 0.0, -0.7));
        HullContactDispatcher::CHECKED
            .contact_manifold_convex_convex(&far, &tip, &hull, None, None, 0.01, &mut m)
            .unwrap();
        assert!(m.points.is_empty());
    }
}
