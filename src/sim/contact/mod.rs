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
//! manifolds; compound shapes dispatch their parts back to it. The check is in
//! `verify.rs`, the fingertips' contacts in `fingertip.rs`, the table's in `table.rs`.

use rapier3d::geometry::{ContactData, ContactManifoldData};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::details::{
    contact_manifolds_composite_shape_composite_shape, contact_manifolds_composite_shape_shape,
    NormalConstraints,
};
use rapier3d::parry::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    NonlinearRigidMotion, PersistentQueryDispatcher, QueryDispatcher, ShapeCastHit,
    ShapeCastOptions, ShapeDistance, ShapeIntersection, Unsupported,
};
use rapier3d::parry::shape::{ConvexPolyhedron, Cuboid, PolygonalFeatureMap, Shape, ShapeType};

mod fingertip;
mod table;
mod verify;

use fingertip::{ball_hull_manifold, ball_like, BallSide};
pub use table::{table_hull_manifold, TABLE_TOUCH_BAND};
use verify::verified_manifold;
pub use verify::{rejection_counts, separation_along, NORMAL_TOLERANCE};

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

/// Shapes the submodules' tests share.
#[cfg(test)]
mod test_shapes {
    use rapier3d::math::Vector;
    use rapier3d::parry::shape::ConvexPolyhedron;

    /// A unit cube's hull (half extent 0.5).
    pub(super) fn cube() -> ConvexPolyhedron {
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
}
