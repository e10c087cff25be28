//! Contact generation checked against the geometry: a query dispatcher for rapier's
//! narrow phase that rejects contact normals parry's GJK/EPA got wrong.
//!
//! # The defect
//! parry 0.31 builds the contact manifold of two convex shapes (`contact_manifold_pfm_pfm`:
//! a convex hull against a capsule, a cylinder, a box or another hull) from a normal `n`
//! found by GJK, warm-started from the previous step's normal, with EPA when the cores
//! overlap; the two shapes' support features toward `n` are clipped against each other
//! and each point's depth is measured along `n`. When `n` is wrong the points are too.
//! Traced on the unseen prism_tri (baseline 1, seed 0, trial 1, physics step 476): the
//! thumb's proximal phalanx touched the prism's top edge (0.04 mm deep by parry's own cold
//! query), but GJK, started from the previous normal, returned "closest points" 2.2 mm
//! deep along a normal through the prism's bottom; the clipped points lay 93-100 mm deep,
//! the solver pushed on them at its maximum corrective velocity, and the episode ended as
//! a deep-penetration physics failure. Another (trial 2, step 232): a fingertip 0.1 mm
//! from the prism along its previous normal got an EPA normal through the far side, 45 mm
//! deep.
//!
//! # The check
//! For convex shapes, the true contact normal maximises the gap between the two shapes'
//! supporting planes normal to it, [`separation_along`] (the distance when separated,
//! minus the penetration depth when overlapping), and along it the gap equals what GJK/EPA
//! claims; along any normal no pair of surface points is closer than that gap. A manifold
//! is accepted when no point is deeper than its exact gap along its normal (traced: a
//! phalanx's manifold with a normal 3.4 mm separating and a point 44 mm deep), when a
//! separated one's points claim no more room than that gap, and when a penetrating one's
//! gap is no smaller than its claimed separation nor than the gap along the previous
//! normal (each within [`NORMAL_TOLERANCE`]); otherwise it is computed again from a cold
//! start, and when that fails too (traced: a fingertip 1.2 mm from a pyramid's apex along
//! the previous normal got 44 mm deep EPA normals from both starts) the previous manifold
//! is kept, its separations measured at the current pose. Up to four support-point queries
//! per pair and step.
//!
//! # Fingertips
//! A ball (or the 0.2 mm capsule a fingertip is simulated as) against a convex hull gets
//! its contact computed exactly from the hull's faces instead (`point_hull_distance`):
//! parry's GJK puts points up to 17 mm from where they are on the object hulls.
//!
//! # The table
//! Given the table's shape (`contacts.table_hull`), a convex polyhedron against it (the
//! object's convex hull, which then meets the table in place of its parts) gets one
//! manifold of at most four of its vertices ([`table_hull_manifold`]).
//!
//! [`HullContactDispatcher`] is parry's [`DefaultQueryDispatcher`] except for these
//! manifolds; compound shapes dispatch their parts back to it.

use rapier3d::geometry::{ContactData, ContactManifoldData};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::details::{
    contact_manifold_pfm_pfm, contact_manifolds_composite_shape_composite_shape,
    contact_manifolds_composite_shape_shape, NormalConstraints,
};
use rapier3d::parry::query::TrackedContact;
use rapier3d::parry::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    NonlinearRigidMotion, PersistentQueryDispatcher, QueryDispatcher, ShapeCastHit,
    ShapeCastOptions, ShapeDistance, ShapeIntersection, Unsupported,
};
use rapier3d::parry::shape::{
    ConvexPolyhedron, Cuboid, PackedFeatureId, PolygonalFeatureMap, Shape, ShapeType, SupportMap,
    TypedShape,
};

/// parry's [`DefaultQueryDispatcher`], with the contact manifolds of convex shapes checked
/// (see the module docs) and, when given the table's shape, a convex polyhedron's contact
/// with the table computed as one small manifold ([`table_hull_manifold`]).
#[derive(Debug, Clone, Copy)]
pub struct HullContactDispatcher {
    check_normals: bool,
    /// The table's shape (its address: the shape is known by identity, not by kind).
    table: Option<usize>,
    /// The stiffness of a hull's manifold with the table (rapier's
    /// `ContactManifoldData::stiffness`).
    table_stiffness: Real,
}

/// The address of a shape, which identifies it while its collider lives.
fn shape_address(shape: &dyn Shape) -> usize {
    shape as *const dyn Shape as *const () as usize
}

impl HullContactDispatcher {
    /// Manifolds checked, no table.
    pub const CHECKED: HullContactDispatcher = HullContactDispatcher {
        check_normals: true,
        table: None,
        table_stiffness: 1.0,
    };

    /// A dispatcher that checks convex manifolds when `check_normals` is set (parry's
    /// manifolds as they are otherwise) and computes a convex polyhedron's contact with
    /// `table` (a cuboid, top face up) itself, its manifold of the given `stiffness`.
    pub fn new(check_normals: bool, table: Option<(&dyn Shape, Real)>) -> Self {
        HullContactDispatcher {
            check_normals,
            table: table.map(|t| shape_address(t.0)),
            table_stiffness: table.map_or(1.0, |t| t.1),
        }
    }

    /// A pair of a convex polyhedron and the table: the polyhedron, the table's box and
    /// whether the polyhedron is the pair's first shape.
    fn hull_on_table<'a>(
        &self,
        g1: &'a dyn Shape,
        g2: &'a dyn Shape,
    ) -> Option<(&'a ConvexPolyhedron, &'a Cuboid, bool)> {
        let table = self.table?;
        let (hull, table_shape, hull_first) = if shape_address(g2) == table {
            (g1, g2, true)
        } else if shape_address(g1) == table {
            (g2, g1, false)
        } else {
            return None;
        };
        Some((
            hull.as_convex_polyhedron()?,
            table_shape.as_cuboid()?,
            hull_first,
        ))
    }
}

/// A shape as a polygonal feature map with its border radius (`None` for balls and
/// half-spaces, which have manifolds of their own in parry, and non-convex shapes).
type Features<'a> = (&'a dyn PolygonalFeatureMap, Real);

fn features(shape: &dyn Shape) -> Option<Features<'_>> {
    if matches!(shape.shape_type(), ShapeType::Ball | ShapeType::HalfSpace) {
        return None;
    }
    shape.as_polygonal_feature_map()
}

impl QueryDispatcher for HullContactDispatcher {
    fn intersection_test(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeIntersection, Unsupported> {
        DefaultQueryDispatcher.intersection_test(pos12, g1, g2)
    }

    fn distance(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        DefaultQueryDispatcher.distance(pos12, g1, g2)
    }

    fn contact(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
    ) -> Result<Option<Contact>, Unsupported> {
        DefaultQueryDispatcher.contact(pos12, g1, g2, prediction)
    }

    fn closest_points(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        max_dist: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        DefaultQueryDispatcher.closest_points(pos12, g1, g2, max_dist)
    }

    fn cast_shapes(
        &self,
        pos12: &Pose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes(pos12, local_vel12, g1, g2, options)
    }

    fn cast_shapes_nonlinear(
        &self,
        motion1: &NonlinearRigidMotion,
        g1: &dyn Shape,
        motion2: &NonlinearRigidMotion,
        g2: &dyn Shape,
        start_time: Real,
        end_time: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes_nonlinear(
            motion1,
            g1,
            motion2,
            g2,
            start_time,
            end_time,
            stop_at_penetration,
        )
    }
}

type Manifold = ContactManifold<ContactManifoldData, ContactData>;

impl PersistentQueryDispatcher<ContactManifoldData, ContactData> for HullContactDispatcher {
    fn contact_manifolds(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
        manifolds: &mut Vec<Manifold>,
        workspace: &mut Option<ContactManifoldsWorkspace>,
    ) -> Result<(), Unsupported> {
        if let Some((hull, table, hull_first)) = self.hull_on_table(g1, g2) {
            if manifolds.is_empty() {
                manifolds.push(ContactManifold::new());
            }
            manifolds.truncate(1);
            table_hull_manifold(
                pos12,
                hull,
                table,
                hull_first,
                prediction,
                &mut manifolds[0],
            );
            manifolds[0].data.stiffness = self.table_stiffness;
            return Ok(());
        }
        if !self.check_normals {
            return DefaultQueryDispatcher
                .contact_manifolds(pos12, g1, g2, prediction, manifolds, workspace);
        }
        // Compounds dispatch their parts back here; other composites (meshes, height
        // fields, voxels), which the simulator does not use, go to parry's dispatcher.
        let c1 = g1
            .as_composite_shape()
            .filter(|_| g1.as_compound().is_some());
        let c2 = g2
            .as_composite_shape()
            .filter(|_| g2.as_compound().is_some());
        match (c1, c2) {
            (Some(a), Some(b)) => contact_manifolds_composite_shape_composite_shape(
                self, pos12, a, b, prediction, manifolds, workspace,
            ),
            (Some(a), None) if g2.is_convex() => contact_manifolds_composite_shape_shape(
                self, pos12, a, g2, prediction, manifolds, workspace, false,
            ),
            (None, Some(b)) if g1.is_convex() => contact_manifolds_composite_shape_shape(
                self,
                &pos12.inverse(),
                b,
                g1,
                prediction,
                manifolds,
                workspace,
                true,
            ),
            (None, None) if g1.is_convex() && g2.is_convex() => {
                if manifolds.is_empty() {
                    manifolds.push(ContactManifold::new());
                }
                return self.contact_manifold_convex_convex(
                    pos12,
                    g1,
                    g2,
                    None,
                    None,
                    prediction,
                    &mut manifolds[0],
                );
            }
            _ => {
                return DefaultQueryDispatcher
                    .contact_manifolds(pos12, g1, g2, prediction, manifolds, workspace)
            }
        }
        Ok(())
    }

    fn contact_manifold_convex_convex(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        normal_constraints1: Option<&dyn NormalConstraints>,
        normal_constraints2: Option<&dyn NormalConstraints>,
        prediction: Real,
        manifold: &mut Manifold,
    ) -> Result<(), Unsupported> {
        let plain = normal_constraints1.is_none() && normal_constraints2.is_none();
        if self.check_normals && checked_convex_manifold(pos12, g1, g2, plain, prediction, manifold)
        {
            return Ok(());
        }
        DefaultQueryDispatcher.contact_manifold_convex_convex(
            pos12,
            g1,
            g2,
            normal_constraints1,
            normal_constraints2,
            prediction,
            manifold,
        )
    }
}

/// The checked manifold of two convex shapes (see the module docs): a fingertip against a
/// hull exactly, other pairs of polygonal feature maps verified; false for the pairs left
/// to parry (those with a manifold of their own, and pairs with normal constraints, i.e.
/// not `plain`).
fn checked_convex_manifold(
    pos12: &Pose,
    g1: &dyn Shape,
    g2: &dyn Shape,
    plain: bool,
    prediction: Real,
    manifold: &mut Manifold,
) -> bool {
    // A fingertip (a ball, or the 0.2 mm capsule that stands for one) against a hull:
    // its contact computed exactly (see [`ball_hull_manifold`]).
    if let (Some(ball), Some(hull)) = (ball_like(g1), g2.as_convex_polyhedron()) {
        ball_hull_manifold(pos12, BallSide::First(ball), hull, prediction, manifold);
        return true;
    }
    if let (Some(hull), Some(ball)) = (g1.as_convex_polyhedron(), ball_like(g2)) {
        ball_hull_manifold(pos12, BallSide::Second(ball), hull, prediction, manifold);
        return true;
    }
    // Pairs with a manifold of their own in parry (ball, half-space, box-box,
    // capsule-capsule) and pairs with normal constraints (meshes) stay parry's.
    let own = matches!(
        (g1.shape_type(), g2.shape_type()),
        (ShapeType::Cuboid, ShapeType::Cuboid) | (ShapeType::Capsule, ShapeType::Capsule)
    );
    if !own && plain {
        if let (Some(f1), Some(f2)) = (features(g1), features(g2)) {
            verified_manifold(pos12, &f1, &f2, prediction, manifold);
            return true;
        }
    }
    false
}

/// Half length (m) under which a capsule is a ball for contact generation: the simulated
/// fingertips are balls stood in for by 0.2 mm capsules (see `HandSim::new`).
const BALL_LIKE_HALF_LENGTH: Real = 5.0e-4;

/// A ball, or a capsule short enough to be one: its centre (shape frame) and radius.
fn ball_like(shape: &dyn Shape) -> Option<(Vector, Real)> {
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
enum BallSide {
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
fn ball_hull_manifold(
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

/// parry's polygonal-feature manifold of `f1` and `f2`.
fn pfm_manifold(
    pos12: &Pose,
    f1: &Features,
    f2: &Features,
    prediction: Real,
    manifold: &mut Manifold,
) {
    let ((p1, r1), (p2, r2)) = (*f1, *f2);
    contact_manifold_pfm_pfm(pos12, p1, r1, None, p2, r2, None, prediction, manifold);
}

/// The signed separation of the two (border-dilated) shapes along `n1` (shape 1's frame,
/// pointing from shape 1 toward shape 2): the gap between their supporting planes normal
/// to `n1`, negative when they overlap along it. For the true contact normal it equals
/// the shapes' distance (separated) or minus their penetration depth (overlapping); along
/// any other direction it is smaller.
pub fn separation_along(
    pos12: &Pose,
    s1: &dyn SupportMap,
    r1: Real,
    s2: &dyn SupportMap,
    r2: Real,
    n1: Vector,
) -> Real {
    let a = s1.local_support_point(n1);
    let n2 = pos12.rotation.inverse() * -n1;
    let b = *pos12 * s2.local_support_point(n2);
    (b - a).dot(n1) - r1 - r2
}

/// How far (m) GJK/EPA's claimed separation may exceed the exact separation along its
/// normal, or the exact separation along the previous normal may exceed it, before the
/// normal is rejected. GJK's closest points in f32 are approximate by a few millimetres
/// near contact; the defects it catches are centimetres.
pub const NORMAL_TOLERANCE: Real = 5.0e-3;

/// The signed separation a manifold claims: that of its GJK/EPA point (the last point,
/// whose features are unknown); `None` for a manifold without that point.
fn claimed(manifold: &Manifold) -> Option<Real> {
    let last = manifold.points.last()?;
    (last.fid1 == PackedFeatureId::UNKNOWN && last.fid2 == PackedFeatureId::UNKNOWN)
        .then_some(last.dist)
}

/// The exact separation of the two shapes along `n1` (see [`separation_along`]).
fn exact_along(pos12: &Pose, f1: &Features, f2: &Features, n1: Vector) -> Real {
    let ((p1, r1), (p2, r2)) = (*f1, *f2);
    separation_along(pos12, p1, r1, p2, r2, n1)
}

/// Whether `manifold` is a contact manifold of the two shapes:
/// - no point is deeper than the shapes overlap along its normal (its exact separation:
///   every point of either shape lies behind its supporting plane, so no pair of surface
///   points is closer along the normal than the planes are; traced: a phalanx whose
///   manifold had a separating normal, 3.4 mm, and a point 44 mm deep);
/// - for a manifold with a penetrating point, its exact separation is no smaller than
///   the separation its GJK/EPA point claims, nor than `bound()` (the separation along
///   the previous normal: the true contact normal maximises the separation along it over
///   all directions, for separated and penetrating shapes alike); one whose GJK/EPA point
///   was not kept is judged by the bound alone;
/// - a separated or touching manifold (a speculative contact, whose normal GJK leaves
///   approximate near the prediction distance) only must not claim more room than the
///   shapes leave along its normal (traced: the novel pyramid, 4.7 cm deep contacts in 4
///   of baseline 1's and the policy's 40 episodes without this rule).
///
/// `bound` is evaluated only when needed.
fn acceptable(
    pos12: &Pose,
    f1: &Features,
    f2: &Features,
    manifold: &Manifold,
    bound: &dyn Fn() -> Real,
) -> bool {
    let Some(deepest) = manifold.points.iter().map(|p| p.dist).reduce(Real::min) else {
        return true;
    };
    let exact = exact_along(pos12, f1, f2, manifold.local_n1);
    if deepest < exact - NORMAL_TOLERANCE {
        return false;
    }
    if deepest >= -NORMAL_TOLERANCE {
        return exact >= deepest - NORMAL_TOLERANCE;
    }
    claimed(manifold).is_none_or(|c| exact >= c - NORMAL_TOLERANCE)
        && exact >= bound() - NORMAL_TOLERANCE
}

/// parry's manifold, checked (see [`acceptable`]): GJK, warm-started from the previous
/// normal, can return a normal whose claimed separation is not the shapes' separation
/// along it (traced: a phalanx 0.04 mm into a prism got a normal through the prism's far
/// side and contact points 9 cm deep), and EPA can settle on a direction of far deeper
/// overlap than another (traced: a fingertip touching a prism, 0.1 mm along the previous
/// normal, got a 45 mm deep normal through the other side). Such a manifold is computed
/// again from a cold start; when that fails too, the previous manifold is kept with its
/// separations brought to the current pose (or, without one, the better of the two runs).
fn verified_manifold(
    pos12: &Pose,
    f1: &Features,
    f2: &Features,
    prediction: Real,
    manifold: &mut Manifold,
) {
    let old = manifold.points.clone();
    let (old_n1, old_n2) = (manifold.local_n1, manifold.local_n2);
    // The separation along the previous normal, computed once and only when needed.
    let bound_cell = std::cell::OnceCell::new();
    let bound = || {
        *bound_cell.get_or_init(|| {
            old_n1
                .try_normalize()
                .map_or(Real::NEG_INFINITY, |n| exact_along(pos12, f1, f2, n))
        })
    };
    pfm_manifold(pos12, f1, f2, prediction, manifold);
    if acceptable(pos12, f1, f2, manifold, &bound) {
        return;
    }
    REJECTED.with(|c| c.set(c.get() + 1));
    let first = manifold.clone();
    // A cold start: GJK begins along the line between the shapes' origins; a zero cached
    // normal also stops parry from reusing the old points.
    manifold.points.clone_from(&old);
    manifold.local_n1 = Vector::ZERO;
    manifold.local_n2 = Vector::ZERO;
    pfm_manifold(pos12, f1, f2, prediction, manifold);
    if acceptable(pos12, f1, f2, manifold, &bound) {
        return;
    }
    FAILED.with(|c| c.set(c.get() + 1));
    if old_n1.try_normalize().is_some() && (!old.is_empty() || bound() > 0.0) {
        // Both runs failed (traced: a fingertip 1.2 mm from a pyramid's apex along the
        // previous normal, which proves the two apart, got EPA normals 44 mm deep from a
        // warm and a cold start): the previous manifold, its points' separations measured
        // along its normal at the current pose, as parry does between steps that barely
        // move.
        manifold.points.clone_from(&old);
        manifold.local_n1 = old_n1;
        manifold.local_n2 = old_n2;
        manifold.update_separations(pos12);
        return;
    }
    let sep = |m: &Manifold| exact_along(pos12, f1, f2, m.local_n1);
    if manifold.points.is_empty() || (!first.points.is_empty() && sep(&first) > sep(manifold)) {
        *manifold = first;
    }
}

thread_local! {
    static REJECTED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    static FAILED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Manifolds whose first normal this thread rejected, and those for which no consistent
/// normal was found (diagnostics).
pub fn rejection_counts() -> (u64, u64) {
    (REJECTED.with(|c| c.get()), FAILED.with(|c| c.get()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::parry::shape::{ConvexPolyhedron, Cylinder};

    /// The unseen prism_tri's hull (its own frame, bottom face at z = 0).
    fn prism() -> ConvexPolyhedron {
        let v = [
            Vector::new(0.03375, 0.0, 0.0),
            Vector::new(-0.03375, -0.038971145, 0.0),
            Vector::new(-0.03375, 0.038971145, 0.0),
            Vector::new(0.03375, 0.0, 0.06),
            Vector::new(-0.03375, -0.038971145, 0.06),
            Vector::new(-0.03375, 0.038971145, 0.06),
        ];
        ConvexPolyhedron::from_convex_hull(&v).unwrap()
    }

    /// The thumb's proximal phalanx (a cylinder) resting on the prism's top edge, as traced
    /// in baseline 1's episode on prism_tri (seed 0, trial 1, physics step 476), with the
    /// normal its manifold had in the step before (8.8 mm apart).
    fn traced() -> (Cylinder, ConvexPolyhedron, Pose, Vector) {
        let pos12 = Pose::from_parts(
            Vector::new(0.06729979, 0.05458056, 0.010644151),
            rapier3d::math::Rotation::from_xyzw(0.7962044, -0.0049737142, -0.28565294, 0.53332615),
        );
        let previous_n1 = Vector::new(0.97502846, -1.10831486e-7, -0.22208004);
        (Cylinder::new(0.019, 0.0085), prism(), pos12, previous_n1)
    }

    fn deepest(m: &Manifold) -> Real {
        m.points.iter().map(|p| p.dist).fold(Real::MAX, Real::min)
    }

    #[test]
    fn parry_warm_started_manifold_of_the_traced_pair_is_wrong() {
        // The defect this module removes, as parry 0.31 has it: 9 cm deep points.
        let (cyl, hull, pos12, n1) = traced();
        let mut m: Manifold = ContactManifold::new();
        m.local_n1 = n1;
        let (f1, r1) = cyl.as_polygonal_feature_map().unwrap();
        let (f2, r2) = hull.as_polygonal_feature_map().unwrap();
        contact_manifold_pfm_pfm(&pos12, f1, r1, None, f2, r2, None, 0.01, &mut m);
        assert!(deepest(&m) < -0.09, "{}", deepest(&m));
        // Its GJK point claims 2.2 mm, the shapes overlap by centimetres along its normal.
        let exact = separation_along(&pos12, f1, r1, f2, r2, m.local_n1);
        assert!(exact < -0.05, "{exact}");
    }

    #[test]
    fn dispatcher_manifold_of_the_traced_pair_is_shallow() {
        let (cyl, hull, pos12, n1) = traced();
        let mut m: Manifold = ContactManifold::new();
        m.local_n1 = n1;
        HullContactDispatcher::CHECKED
            .contact_manifold_convex_convex(&pos12, &cyl, &hull, None, None, 0.01, &mut m)
            .unwrap();
        // parry's exact query (cold start): 0.04 mm deep at the cylinder's far cap.
        let c = rapier3d::parry::query::contact(&Pose::IDENTITY, &cyl, &pos12, &hull, 0.01)
            .unwrap()
            .unwrap();
        assert!(c.dist > -1e-3, "{c:?}");
        assert!(!m.points.is_empty());
        assert!(deepest(&m) > c.dist - 1e-3, "{} vs {}", deepest(&m), c.dist);
        assert!(
            m.local_n1.dot(c.normal1) > 0.99,
            "{:?} vs {:?}",
            m.local_n1,
            c.normal1
        );
    }

    #[test]
    fn separation_along_hand_computed() {
        // Two unit cubes (half extent 0.5) 1.2 apart along x: 0.2 apart along x, and along
        // the diagonal (1,1,0)/sqrt(2) the support planes overlap.
        let a = rapier3d::parry::shape::Cuboid::new(Vector::splat(0.5));
        let pos12 = Pose::from_translation(Vector::new(1.2, 0.0, 0.0));
        let s = separation_along(&pos12, &a, 0.0, &a, 0.0, Vector::X);
        assert!((s - 0.2).abs() < 1e-6, "{s}");
        let d = Vector::new(1.0, 1.0, 0.0).normalize();
        // a: max (x + y)/sqrt2 = 1/sqrt2; b: min = (1.2 - 1)/sqrt2.
        let s = separation_along(&pos12, &a, 0.0, &a, 0.0, d);
        let expect = (0.2 - 1.0) / 2f32.sqrt();
        assert!((s - expect).abs() < 1e-6, "{s} vs {expect}");
        // Border radii subtract.
        let s = separation_along(&pos12, &a, 0.05, &a, 0.1, Vector::X);
        assert!((s - 0.05).abs() < 1e-6, "{s}");
    }

    /// A unit cube's hull (half extent 0.5).
    fn cube() -> ConvexPolyhedron {
        let mut v = Vec::new();
        for x in [-0.5, 0.5] {
            for y in [-0.5, 0.5] {
                for z in [-0.5, 0.5] {
                    v.push(Vector::new(x, y, z));
                }
            }
        }
        ConvexPolyhedron::from_convex_hull(&v).unwrap()
    }

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
