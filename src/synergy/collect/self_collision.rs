//! The geometric self-collision check of the finger links ([`SelfCollision`]): the
//! simulator disables hand self-collisions, so collected postures are filtered here.

use super::SELF_COLLISION_TOLERANCE;
use crate::robot::model::Geometry;
use crate::robot::Robot;
use nalgebra::{Point3, Vector3};
use serde::Serialize;

/// A capsule of the self-collision check: a segment in a link frame and a radius.
#[derive(Debug, Clone, PartialEq)]
struct Capsule {
    link: usize,
    finger: usize,
    segment: usize,
    a: Point3<f64>,
    b: Point3<f64>,
    radius: f64,
}

/// Geometric self-collision test of the finger links: each phalanx's collision cylinders
/// become capsules (and spheres zero-length capsules); two capsules of different fingers,
/// or of the same finger but not adjacent phalanges, collide when they overlap by more than
/// [`SELF_COLLISION_TOLERANCE`]. Box geometry (palm, LF metacarpal) is not checked.
#[derive(Debug, Clone)]
pub struct SelfCollision {
    capsules: Vec<Capsule>,
    names: Vec<String>,
    pub(super) robot: Robot,
}

/// A self-collision found by [`SelfCollision::check`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Collision {
    /// First link.
    pub link_a: String,
    /// Second link.
    pub link_b: String,
    /// Overlap depth (m).
    pub depth: f64,
}

impl SelfCollision {
    /// The capsules of `robot`'s finger phalanges (proximal, middle, distal of the five
    /// fingers).
    pub fn new(robot: &Robot) -> SelfCollision {
        let mut capsules = Vec::new();
        let mut names = Vec::new();
        for (finger, prefix) in ["ff", "mf", "rf", "lf", "th"].iter().enumerate() {
            for (segment, part) in ["proximal", "middle", "distal"].iter().enumerate() {
                let Some(link) = robot.hand_link(&format!("{prefix}{part}")) else {
                    continue;
                };
                for c in &robot.links[link].collisions {
                    let (half, radius) = match c.geometry {
                        Geometry::Cylinder { radius, length } => (length / 2.0, radius),
                        Geometry::Capsule { radius, length } => (length / 2.0, radius),
                        Geometry::Sphere { radius } => (0.0, radius),
                        _ => continue,
                    };
                    capsules.push(Capsule {
                        link,
                        finger,
                        segment,
                        a: c.origin * Point3::new(0.0, 0.0, -half),
                        b: c.origin * Point3::new(0.0, 0.0, half),
                        radius,
                    });
                }
            }
        }
        for l in &robot.links {
            names.push(l.name.clone());
        }
        SelfCollision {
            capsules,
            names,
            robot: robot.clone(),
        }
    }

    /// Number of capsules checked.
    pub fn n_capsules(&self) -> usize {
        self.capsules.len()
    }

    /// The deepest self-collision of posture `q` (24 hand angles, paper order), if any.
    pub fn check(&self, q: &[f64; 24]) -> Option<Collision> {
        let poses = self.robot.hand_fk_palm(q);
        let world: Vec<(Point3<f64>, Point3<f64>)> = self
            .capsules
            .iter()
            .map(|c| (poses[c.link] * c.a, poses[c.link] * c.b))
            .collect();
        let mut worst: Option<Collision> = None;
        for i in 0..self.capsules.len() {
            for j in i + 1..self.capsules.len() {
                let (ci, cj) = (&self.capsules[i], &self.capsules[j]);
                if ci.finger == cj.finger && ci.segment.abs_diff(cj.segment) <= 1 {
                    continue;
                }
                let d = segment_distance(&world[i].0, &world[i].1, &world[j].0, &world[j].1);
                let depth = ci.radius + cj.radius - d;
                if depth > SELF_COLLISION_TOLERANCE
                    && worst.as_ref().is_none_or(|w| depth > w.depth)
                {
                    worst = Some(Collision {
                        link_a: self.names[ci.link].clone(),
                        link_b: self.names[cj.link].clone(),
                        depth,
                    });
                }
            }
        }
        worst
    }
}

/// Shortest distance between segments `p1 q1` and `p2 q2` (degenerate segments allowed).
pub fn segment_distance(
    p1: &Point3<f64>,
    q1: &Point3<f64>,
    p2: &Point3<f64>,
    q2: &Point3<f64>,
) -> f64 {
    let d1: Vector3<f64> = q1 - p1;
    let d2: Vector3<f64> = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    const EPS: f64 = 1e-18;
    let (s, t) = if a <= EPS && e <= EPS {
        (0.0, 0.0)
    } else if a <= EPS {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= EPS {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > EPS {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::joints::hand_index;
    use crate::robot::Side;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    #[test]
    fn segment_distances_hand_computed() {
        // Parallel segments 1 apart.
        let d = segment_distance(
            &p(0., 0., 0.),
            &p(1., 0., 0.),
            &p(0., 1., 0.),
            &p(1., 1., 0.),
        );
        assert!((d - 1.0).abs() < 1e-12);
        // Crossing skew segments: x axis and a segment along y at z = 2.
        let d = segment_distance(
            &p(-1., 0., 0.),
            &p(1., 0., 0.),
            &p(0., -1., 2.),
            &p(0., 1., 2.),
        );
        assert!((d - 2.0).abs() < 1e-12);
        // End to end: (1,0,0) to (2,1,0) -> sqrt 2.
        let d = segment_distance(
            &p(0., 0., 0.),
            &p(1., 0., 0.),
            &p(2., 1., 0.),
            &p(3., 1., 0.),
        );
        assert!((d - 2f64.sqrt()).abs() < 1e-12);
        // Point to segment: (0.5, 3, 0) to the x-axis unit segment -> 3.
        let d = segment_distance(
            &p(0.5, 3., 0.),
            &p(0.5, 3., 0.),
            &p(0., 0., 0.),
            &p(1., 0., 0.),
        );
        assert!((d - 3.0).abs() < 1e-12);
        // Two points: 3-4-5.
        let d = segment_distance(
            &p(0., 0., 0.),
            &p(0., 0., 0.),
            &p(3., 4., 0.),
            &p(3., 4., 0.),
        );
        assert!((d - 5.0).abs() < 1e-12);
        // Intersecting segments.
        let d = segment_distance(
            &p(-1., 0., 0.),
            &p(1., 0., 0.),
            &p(0., -1., 0.),
            &p(0., 1., 0.),
        );
        assert!(d.abs() < 1e-12);
    }

    #[test]
    fn self_collision_rejects_crossed_fingers_and_accepts_open_hands() {
        let r = Robot::builtin(Side::Left);
        let c = SelfCollision::new(&r);
        // 3 phalanges x 5 fingers, distal ones with a cylinder and a sphere.
        assert_eq!(c.n_capsules(), 20);
        assert!(c.check(&crate::robot::Posture::Open.angles()).is_none());
        assert!(c.check(&[0.0; 24]).is_none());
        // FF turned toward MF, MF turned toward RF would be apart; FF toward MF and MF
        // toward FF cross: positive FFJ4 moves FF toward MF, negative MFJ4 moves MF toward FF.
        let mut q = [0.0; 24];
        q[hand_index("FFJ4").unwrap_or(0)] = 0.349;
        q[hand_index("MFJ4").unwrap_or(0)] = -0.349;
        let hit = c.check(&q).expect("crossed fingers collide");
        assert!(hit.depth > 0.001, "{hit:?}");
        assert!(
            hit.link_a.contains("ff") && hit.link_b.contains("mf"),
            "{hit:?}"
        );
        // Spread apart: no collision.
        q[hand_index("FFJ4").unwrap_or(0)] = -0.349;
        q[hand_index("MFJ4").unwrap_or(0)] = 0.0;
        assert!(c.check(&q).is_none());
    }
}
