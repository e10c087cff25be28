//! A convex polyhedron's contact with the table's top face: one manifold of at most four
//! of its vertices.

use super::Manifold;
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::TrackedContact;
use rapier3d::parry::shape::{ConvexPolyhedron, Cuboid, PackedFeatureId};

/// How far (m) above the deepest of a hull's vertices near the table a vertex still
/// counts as touching ([`table_hull_manifold`]). Measured on the 80 built-in objects
/// resting 3 s (tests/objects_in_sim.rs): with 0.5 mm egad_c0_d0 still rocked in the last
/// second (0.78 mm, 0.008 rad), with 2 mm it rolled 0.13 rad onto another facet; with 1 mm
/// every object rests (at most 2.3 mm and 0.097 rad of settling, the egg).
pub const TABLE_TOUCH_BAND: Real = 1.0e-3;

/// Most points of a hull's manifold with the table: rapier's solver takes at most four
/// points of a manifold (and would choose them itself from more).
const TABLE_POINTS: usize = 4;

/// A fixed direction in the hull's frame that picks the first corner of each group of
/// points (any direction no face of an object is normal to: it only breaks ties).
const FIRST_CORNER: Vector = Vector::new(0.581, 0.492, 0.648);

/// The contact manifold of a convex polyhedron (the object's hull) and the table's top
/// face: at most four of the hull's vertices within `prediction` of the face. A convex
/// object's contact with a plane is at its vertices, and a non-convex object (a union of
/// convex parts) touches a plane only where its convex hull does, so the hull meets the
/// table as the parts would, without the points each part adds where it touches beside
/// its neighbours (an object resting on its parts had about 15 manifolds and 56 points
/// with the table per step; see docs/simulator.md). The vertices within
/// [`TABLE_TOUCH_BAND`] of the deepest are the touching ones; up to four of them span
/// their polygon (the one farthest along a fixed direction of the hull, the one farthest
/// from it, and the farthest on each side of the line through both), and the places left
/// go to the others, chosen alike: the speculative contacts where the hull may touch
/// next.
/// Each point is known by its vertex, so it keeps its warm start while that vertex stays
/// chosen.
pub fn table_hull_manifold(
    pos12: &Pose,
    hull: &ConvexPolyhedron,
    table: &Cuboid,
    hull_first: bool,
    prediction: Real,
    manifold: &mut Manifold,
) {
    let table_from_hull = if hull_first { pos12.inverse() } else { *pos12 };
    let he = table.half_extents;
    // The vertices within the prediction distance over the top face, each transformed
    // once.
    let near: Vec<TableVertex> = hull
        .points()
        .iter()
        .enumerate()
        .filter_map(|(index, v)| {
            let at = table_from_hull * *v;
            let height = at.z - he.z;
            (height <= prediction && at.x.abs() <= he.x && at.y.abs() <= he.y).then_some(
                TableVertex {
                    index,
                    hull: *v,
                    at,
                    height,
                },
            )
        })
        .collect();
    let deepest = near
        .iter()
        .map(|v| v.height)
        .fold(Real::INFINITY, Real::min);
    let old = std::mem::take(&mut manifold.points);
    let down_in_hull = table_from_hull.rotation.inverse() * -Vector::Z;
    if hull_first {
        manifold.local_n1 = down_in_hull;
        manifold.local_n2 = Vector::Z;
    } else {
        manifold.local_n1 = Vector::Z;
        manifold.local_n2 = down_in_hull;
    }
    if deepest.is_finite() {
        let limit = deepest + TABLE_TOUCH_BAND;
        for touching in [true, false] {
            let group: Vec<TableVertex> = near
                .iter()
                .filter(|v| (v.height <= limit) == touching)
                .copied()
                .collect();
            let room = TABLE_POINTS - manifold.points.len();
            for k in polygon_corners(&group).take(room) {
                let v = &group[k];
                let on_table = Vector::new(v.at.x, v.at.y, he.z);
                let (fid_hull, fid_table) = (
                    PackedFeatureId::vertex(v.index as u32),
                    PackedFeatureId::face(0),
                );
                manifold.points.push(TrackedContact::flipped(
                    on_table, v.hull, fid_table, fid_hull, v.height, hull_first,
                ));
            }
        }
    }
    manifold.match_contacts(&old);
}

/// A hull vertex near the table's top face ([`table_hull_manifold`]).
#[derive(Debug, Clone, Copy)]
struct TableVertex {
    /// Its index among the hull's points.
    index: usize,
    /// Its position in the hull's frame.
    hull: Vector,
    /// Its position in the table's frame.
    at: Vector,
    /// Its height over the top face (negative: below).
    height: Real,
}

/// Up to four corners of the polygon `group` spans in the table's plane: positions in
/// `group` (see [`table_hull_manifold`]).
fn polygon_corners(group: &[TableVertex]) -> impl Iterator<Item = usize> {
    // The position maximising `score` over the group (the first on ties).
    let best = |score: &dyn Fn(&TableVertex) -> Real| {
        let mut found: Option<(usize, Real)> = None;
        for (k, v) in group.iter().enumerate() {
            let s = score(v);
            if found.is_none_or(|(_, b)| s > b) {
                found = Some((k, s));
            }
        }
        found
    };
    let mut corners = [None; 4];
    if let Some((a, _)) = best(&|v| v.hull.dot(FIRST_CORNER)) {
        corners[0] = Some(a);
        let pa = group[a].at;
        let planar = |p: Vector| Vector::new(p.x - pa.x, p.y - pa.y, 0.0);
        if let Some((b, far)) = best(&|v| planar(v.at).length_squared()) {
            if far > 0.0 {
                corners[1] = Some(b);
                let ab = planar(group[b].at);
                let side = |p: Vector| ab.x * planar(p).y - ab.y * planar(p).x;
                corners[2] = best(&|v| side(v.at)).filter(|(_, s)| *s > 0.0).map(|c| c.0);
                corners[3] = best(&|v| -side(v.at))
                    .filter(|(_, s)| *s > 0.0)
                    .map(|c| c.0);
            }
        }
    }
    corners.into_iter().flatten()
}

#[cfg(test)]
mod tests {
    use super::super::test_shapes::cube;
    use super::super::HullContactDispatcher;
    use super::*;
    use rapier3d::parry::query::PersistentQueryDispatcher;
    use rapier3d::parry::shape::Shape;

    /// A table as the simulator has it (top face at z = 0.05 in its frame) and a cube of
    /// side 1 above it: the cube's pose in the table's frame for a bottom `gap` above the
    /// top face (negative: sunk in), turned by `tilt` about x.
    fn cube_over_table(gap: Real, tilt: Real) -> (Cuboid, ConvexPolyhedron, Pose) {
        let table = Cuboid::new(Vector::new(5.0, 5.0, 0.05));
        let rot = rapier3d::math::Rotation::from_axis_angle(Vector::X, tilt);
        // The lowest point of the turned cube is 0.5 (cos + |sin|) below its centre.
        let drop = 0.5 * (tilt.cos() + tilt.sin().abs());
        let pose = Pose::from_parts(Vector::new(0.0, 0.0, 0.05 + gap + drop), rot);
        (table, cube(), pose)
    }

    fn dispatch_table(
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        table: &dyn Shape,
    ) -> Vec<Manifold> {
        let d = HullContactDispatcher::new(true, Some((table, 4.0)));
        let mut ms = Vec::new();
        d.contact_manifolds(pos12, g1, g2, 0.01, &mut ms, &mut None)
            .unwrap();
        ms
    }

    #[test]
    fn hull_resting_on_the_table_gets_its_face_corners_in_one_stiff_manifold() {
        let (table, hull, table_from_hull) = cube_over_table(-0.001, 0.0);
        // The hull first: pos12 is the table's pose in the hull's frame.
        let ms = dispatch_table(&table_from_hull.inverse(), &hull, &table, &table);
        assert_eq!(ms.len(), 1);
        let m = &ms[0];
        assert_eq!(m.data.stiffness, 4.0);
        assert_eq!(m.points.len(), 4);
        assert!(
            (m.local_n1 + Vector::Z).length() < 1e-6 && (m.local_n2 - Vector::Z).length() < 1e-6
        );
        for p in &m.points {
            assert!((p.dist + 0.001).abs() < 1e-5, "{}", p.dist);
            // The bottom face's corners, each on the table top below it.
            assert!((p.local_p1.z + 0.5).abs() < 1e-6 && (p.local_p1.x.abs() - 0.5).abs() < 1e-6);
            assert!((p.local_p2 - Vector::new(p.local_p1.x, p.local_p1.y, 0.05)).length() < 1e-5);
        }
        // The table first: the same points, the normals swapped.
        let flipped = dispatch_table(&table_from_hull, &table, &hull, &table);
        let f = &flipped[0];
        assert!(
            (f.local_n1 - Vector::Z).length() < 1e-6 && (f.local_n2 + Vector::Z).length() < 1e-6
        );
        for (a, b) in m.points.iter().zip(&f.points) {
            assert!((a.local_p1 - b.local_p2).length() < 1e-6 && (a.dist - b.dist).abs() < 1e-9);
        }
        // A shape that is not the table (another box of the same size) is parry's.
        let other = table;
        let ms = dispatch_table(&table_from_hull.inverse(), &hull, &other, &table);
        assert!(ms.iter().all(|m| m.data.stiffness == 1.0));
    }

    #[test]
    fn tilted_hull_gets_its_touching_edge_then_where_it_may_touch_next() {
        // Turned 0.05 rad about x: one bottom edge 0.5 mm deep, the opposite one about
        // 5 cm up (beyond the 1 cm prediction), the top face far above.
        let (table, hull, table_from_hull) = cube_over_table(-0.0005, 0.05);
        let ms = dispatch_table(&table_from_hull.inverse(), &hull, &table, &table);
        let m = &ms[0];
        assert_eq!(m.points.len(), 2, "{:?}", m.points);
        assert!(m.points.iter().all(|p| (p.dist + 0.0005).abs() < 1e-5));
        // Turned 0.005 rad: the far edge 4.5 mm up, within the prediction distance: two
        // touching corners and two speculative ones.
        let (table, hull, table_from_hull) = cube_over_table(-0.0005, 0.005);
        let ms = dispatch_table(&table_from_hull.inverse(), &hull, &table, &table);
        let m = &ms[0];
        assert_eq!(m.points.len(), 4);
        let touching = m.points.iter().filter(|p| p.dist < 0.0).count();
        assert_eq!(touching, 2, "{:?}", m.points);
        // The touching ones come first, the speculative ones are 4-5 mm up.
        assert!(m.points[..2].iter().all(|p| p.dist < 0.0));
        assert!(
            m.points[2..]
                .iter()
                .all(|p| p.dist > 0.004 && p.dist < 0.0051),
            "{:?}",
            m.points
        );
    }

    #[test]
    fn table_manifold_keeps_warm_starts_and_empties_beyond_the_prediction() {
        let (table, hull, table_from_hull) = cube_over_table(-0.001, 0.0);
        let pos12 = table_from_hull.inverse();
        let d = HullContactDispatcher::new(true, Some((&table as &dyn Shape, 1.0)));
        let mut ms = Vec::new();
        d.contact_manifolds(&pos12, &hull, &table, 0.01, &mut ms, &mut None)
            .unwrap();
        for (k, p) in ms[0].points.iter_mut().enumerate() {
            p.data.warmstart_impulse = k as Real + 1.0;
        }
        let before: Vec<_> = ms[0]
            .points
            .iter()
            .map(|p| (p.fid1, p.data.warmstart_impulse))
            .collect();
        // Sunk 0.1 mm deeper: the same vertices, their impulses kept.
        let deeper = Pose::from_translation(Vector::new(0.0, 0.0, 1e-4)) * pos12;
        d.contact_manifolds(&deeper, &hull, &table, 0.01, &mut ms, &mut None)
            .unwrap();
        let after: Vec<_> = ms[0]
            .points
            .iter()
            .map(|p| (p.fid1, p.data.warmstart_impulse))
            .collect();
        assert_eq!(before, after);
        // 2 cm above the table: no point.
        let (_, _, far) = cube_over_table(0.02, 0.0);
        d.contact_manifolds(&far.inverse(), &hull, &table, 0.01, &mut ms, &mut None)
            .unwrap();
        assert!(ms[0].points.is_empty());
    }

    #[test]
    fn corners_of_a_many_sided_face_span_most_of_it() {
        // A 48-sided disc (a can's bottom), radius 1: four corners of area near the
        // inscribed square's 2 (any four of its vertices span at most that).
        let disc: Vec<Vector> = (0..48)
            .map(|k| {
                let a = k as Real * std::f32::consts::TAU / 48.0;
                Vector::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let group = |points: &[Vector]| -> Vec<TableVertex> {
            points
                .iter()
                .enumerate()
                .map(|(index, v)| TableVertex {
                    index,
                    hull: *v,
                    at: *v,
                    height: 0.0,
                })
                .collect()
        };
        let corners: Vec<usize> = polygon_corners(&group(&disc)).collect();
        assert_eq!(corners.len(), 4);
        let p: Vec<Vector> = corners.iter().map(|i| disc[*i]).collect();
        // a, b, then c and d on either side of ab: the quadrilateral a c b d.
        let tri = |a: Vector, b: Vector, c: Vector| 0.5 * ((b - a).cross(c - a)).length();
        let area = tri(p[0], p[1], p[2]) + tri(p[0], p[1], p[3]);
        assert!(area > 1.95, "{area}");
        // No point: no corner; one point: one.
        assert_eq!(polygon_corners(&[]).count(), 0);
        assert_eq!(polygon_corners(&group(&disc[..1])).count(), 1);
    }
}
