//! The simulator's health checks after each physics step (`check_physics`: the solver's
//! quarantine, non-finite or too fast bodies, an object carried off, deep penetrations,
//! with the limits of the sim config's `[failure]`) and the deepest object contact they
//! measure and report.

use super::*;

impl HandSim {
    pub(super) fn check_physics(&mut self) -> Option<PhysicsFailure> {
        if !self.pipeline.quarantine().is_empty() {
            return Some(PhysicsFailure::NonFinite);
        }
        let f = &self.cfg.failure;
        for h in self
            .hand_bodies
            .iter()
            .chain(std::iter::once(&self.object_body))
        {
            let Some(rb) = self.sets.bodies.get(*h) else {
                continue;
            };
            let t = rb.translation();
            let v = rb.linvel();
            if !(t.is_finite() && v.is_finite() && rb.angvel().is_finite()) {
                return Some(PhysicsFailure::NonFinite);
            }
            let speed = v.length() as f64;
            if speed > f.max_speed {
                return Some(PhysicsFailure::TooFast { speed });
            }
        }
        let p = self.object_position();
        let distance = (p - self.object_start).norm();
        if distance > f.max_object_travel {
            return Some(PhysicsFailure::ObjectLost { distance });
        }
        let max_penetration = f.max_penetration;
        // Named (an allocation) only when it is the deepest so far or a failure.
        let (depth, other, sub) = self.deepest_object_pair()?;
        let deeper = self.deepest.as_ref().is_none_or(|d| depth > d.depth);
        if !deeper && depth <= max_penetration {
            return None;
        }
        let c = self.object_contact(depth, other, sub);
        if deeper {
            self.deepest = Some(c.clone());
        }
        (c.depth > max_penetration).then_some(PhysicsFailure::DeepPenetration {
            depth: c.depth,
            with: c.with,
            part: c.part,
        })
    }

    /// The object's deepest penetrating contact in the current step, with what it touched.
    #[cfg(test)]
    pub(super) fn deepest_object_contact(&self) -> Option<ObjectContact> {
        let (depth, other, sub) = self.deepest_object_pair()?;
        Some(self.object_contact(depth, other, sub))
    }

    /// The object's deepest penetrating contact in the current step, unnamed: its depth,
    /// the collider the object touched and the object's part (see
    /// [`HandSim::object_contact`]).
    fn deepest_object_pair(&self) -> Option<(f64, ColliderHandle, Option<u32>)> {
        let mut best: Option<(f64, ColliderHandle, Option<u32>)> = None;
        let pairs = self
            .narrow_phase
            .contact_pairs_with(self.object_collider)
            .chain(self.narrow_phase.contact_pairs_with(self.object_hull));
        for pair in pairs {
            let Some((m, depth)) = self.pair_depth(pair) else {
                continue;
            };
            if depth <= 0.0 || best.is_some_and(|b| b.0 >= depth) {
                continue;
            }
            // The part of a compound object; none for the hull that meets the table.
            let part = |c: ColliderHandle, sub: u32| (c == self.object_collider).then_some(sub);
            best = Some(
                if pair.collider1 == self.object_collider || pair.collider1 == self.object_hull {
                    (depth, pair.collider2, part(pair.collider1, m.subshape1))
                } else {
                    (depth, pair.collider1, part(pair.collider2, m.subshape2))
                },
            );
        }
        best
    }

    /// The object's contact of `depth` with collider `other` on its part `sub`, named.
    fn object_contact(&self, depth: f64, other: ColliderHandle, sub: Option<u32>) -> ObjectContact {
        ObjectContact {
            depth,
            with: self.collider_name(other),
            part: sub
                .filter(|_| self.object.shape.part_count() > 1)
                .map(|s| s as usize),
            step: self.physics_steps,
        }
    }

    /// The deepest penetration (m) of a contact pair's manifolds at the current poses
    /// (negative when none touches): each contact point's two body-attached points
    /// measured along its manifold's normal, as the solver measures them. rapier keeps a
    /// manifold whose pair barely moved since it was computed (its contact recycling), and
    /// the separations stored in its points are then those of the step it was computed in.
    fn pair_depth<'a>(&self, pair: &'a ContactPair) -> Option<(&'a ContactManifold, f64)> {
        let colliders = &self.sets.colliders;
        let (co1, co2) = (&colliders[pair.collider1], &colliders[pair.collider2]);
        let at =
            |co: &Collider, sub: Option<&Pose>| sub.map_or(*co.position(), |p| *co.position() * *p);
        let mut best: Option<(&ContactManifold, f64)> = None;
        for m in pair.manifolds().iter().filter(|m| !m.points.is_empty()) {
            let pos12 = at(co1, m.subshape_pos1()).inverse() * at(co2, m.subshape_pos2());
            let depth = m
                .points
                .iter()
                .map(|p| (p.local_p1 - pos12 * p.local_p2).dot(m.local_n1))
                .fold(Real::NEG_INFINITY, Real::max) as f64;
            if depth.is_finite() && best.is_none_or(|(_, d)| depth > d) {
                best = Some((m, depth));
            }
        }
        best
    }

    /// A collider's name for reports: the hand link it belongs to, or `table`.
    fn collider_name(&self, h: ColliderHandle) -> String {
        if h == self.table {
            return "table".into();
        }
        self.collider_links
            .iter()
            .find(|(c, _)| *c == h)
            .map_or_else(|| "unknown".into(), |(_, n)| n.clone())
    }
}
