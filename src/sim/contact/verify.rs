//! The check of parry's convex contact manifolds against the geometry (see the module
//! docs of [`contact`](super)): the exact separation of two shapes along a normal, and the
//! manifold computed again, or kept, when GJK/EPA's normal does not pass.

use super::{Features, Manifold};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::details::contact_manifold_pfm_pfm;
use rapier3d::parry::shape::{PackedFeatureId, SupportMap};

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
pub(super) fn verified_manifold(
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
    use super::super::HullContactDispatcher;
    use super::*;
    use rapier3d::parry::query::ContactManifold;
    use rapier3d::parry::query::PersistentQueryDispatcher;
    use rapier3d::parry::shape::Cylinder;
    use rapier3d::parry::shape::{ConvexPolyhedron, Shape};

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
}
