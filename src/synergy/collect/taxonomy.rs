//! The grasp types collected ([`grasp_types`]): the GRASP taxonomy's types (Feix et al.)
//! that a Shadow hand can form above an object on a table, each with its category,
//! opposition, thumb position, object size class, preshape and closed posture, and the
//! types left out with the reason ([`EXCLUDED_TYPES`]).

use crate::robot::joints::hand_index;
use crate::sim::{ObjectShape, ObjectSpec};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// The power / intermediate / precision class of a grasp type (Feix et al.).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Category {
    /// Power grasp.
    Power,
    /// Intermediate grasp.
    Intermediate,
    /// Precision grasp.
    Precision,
}

/// The opposition type of a grasp (Feix et al.).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Opposition {
    /// Palm opposition.
    Palm,
    /// Pad opposition.
    Pad,
    /// Side opposition.
    Side,
}

/// The thumb position of a grasp (Feix et al.).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ThumbPosition {
    /// Thumb abducted (opposed to the fingers).
    Abducted,
    /// Thumb adducted (alongside the index finger).
    Adducted,
}

/// The objects a grasp type is tried on (sizes are full extents).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SizeClass {
    /// Cylinders of 7-10 cm diameter or boxes of 7-10 cm.
    Large,
    /// Cylinders of 5-7 cm diameter or boxes of 5-7 cm.
    Medium,
    /// Cylinders of 3-5 cm diameter or boxes of 3-5 cm.
    Small,
    /// Cylinders and boxes of 2-3 cm.
    Tiny,
    /// Flat standing boxes: 2-3 cm thick, 6-10 cm wide and high.
    Flat,
    /// Flat cylinders: 7-10 cm diameter, 2-4 cm high.
    Disk,
}

impl SizeClass {
    /// Draws an object of this class: shape, mass uniform in 50-500 g, friction 0.8.
    pub fn draw(self, rng: &mut ChaCha8Rng) -> ObjectSpec {
        let mut u = |lo: f64, hi: f64| rng.random_range(lo..hi);
        let cylinder = u(0.0, 1.0) < 0.5;
        let shape = match self {
            SizeClass::Flat => ObjectShape::Box {
                half: [u(0.03, 0.05), u(0.01, 0.015), u(0.03, 0.05)],
            },
            SizeClass::Disk => ObjectShape::Cylinder {
                radius: u(0.035, 0.05),
                half_height: u(0.01, 0.02),
            },
            _ => {
                let (lo, hi): (f64, f64) = match self {
                    SizeClass::Large => (0.035, 0.05),
                    SizeClass::Medium => (0.025, 0.035),
                    SizeClass::Small => (0.015, 0.025),
                    _ => (0.01, 0.015),
                };
                let h = u(lo.max(0.02), 0.05);
                if cylinder {
                    ObjectShape::Cylinder {
                        radius: u(lo, hi),
                        half_height: h,
                    }
                } else {
                    ObjectShape::Box {
                        half: [u(lo, hi), u(lo, hi), u(lo, hi).max(h * 0.8)],
                    }
                }
            }
        };
        let mass = u(0.05, 0.5);
        let volume = shape.volume();
        ObjectSpec::with_density(shape, mass / volume, 0.8)
    }
}

/// The pose of one of the four long fingers: J4 (toward the middle finger positive on both
/// hands), J3 and the coupled J0 = J1 + J2 (split evenly).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FingerPose {
    /// J4 (rad).
    pub j4: f64,
    /// J3 (rad).
    pub j3: f64,
    /// J0 = J1 + J2 (rad).
    pub j0: f64,
}

/// A hand posture from a few per-finger parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HandShape {
    /// FF, MF, RF, LF.
    pub fingers: [FingerPose; 4],
    /// LFJ5, the little finger's metacarpal cupping (rad).
    pub lf_j5: f64,
    /// THJ5, THJ4, THJ3, THJ2, THJ1 (rad).
    pub thumb: [f64; 5],
}

impl HandShape {
    /// The 24 hand angles (paper order; wrist 0). Not clamped.
    pub fn angles(&self) -> [f64; 24] {
        let mut q = [0.0; 24];
        let mut set = |n: &str, v: f64| {
            if let Some(i) = hand_index(n) {
                q[i] = v;
            }
        };
        for (f, p) in ["FF", "MF", "RF", "LF"].iter().zip(&self.fingers) {
            set(&format!("{f}J4"), p.j4);
            set(&format!("{f}J3"), p.j3);
            set(&format!("{f}J2"), p.j0 / 2.0);
            set(&format!("{f}J1"), p.j0 / 2.0);
        }
        set("LFJ5", self.lf_j5);
        for (k, v) in self.thumb.iter().enumerate() {
            set(&format!("THJ{}", 5 - k), *v);
        }
        q
    }

    /// This shape with every parameter moved by a uniform amount in `[-amp, amp]`.
    pub(super) fn jittered(&self, rng: &mut ChaCha8Rng, amp: f64) -> HandShape {
        let mut s = *self;
        let mut u = || rng.random_range(-amp..=amp);
        for f in &mut s.fingers {
            f.j4 += 0.5 * u();
            f.j3 += u();
            f.j0 += 2.0 * u();
        }
        s.lf_j5 += u();
        for t in &mut s.thumb {
            *t += u();
        }
        s
    }
}

/// One grasp type of the GRASP taxonomy as the Shadow hand forms it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraspType {
    /// Number in Feix et al. (1-33).
    pub feix: u8,
    /// Name (snake case; the CSV's `grasp_type` column).
    pub name: &'static str,
    /// Power, intermediate or precision.
    pub category: Category,
    /// Palm, pad or side opposition.
    pub opposition: Opposition,
    /// Thumb abducted or adducted.
    pub thumb: ThumbPosition,
    /// Participating fingers, FF, MF, RF, LF, TH.
    pub fingers: [bool; 5],
    /// The objects it is tried on.
    pub size: SizeClass,
    /// Open posture the hand starts from.
    pub preshape: HandShape,
    /// Closed target posture (past the object: the joints stop at contact).
    pub closed: HandShape,
}

const fn fp(j4: f64, j3: f64, j0: f64) -> FingerPose {
    FingerPose { j4, j3, j0 }
}

/// A finger kept straight.
const EXT: FingerPose = fp(0.0, 0.05, 0.05);
/// A finger curled fully into the palm (not participating).
const CURL: FingerPose = fp(0.0, 1.45, 2.6);
/// Thumb open and abducted under the palm (the `open` start posture).
const TH_OPEN: [f64; 5] = [0.0, 1.15, 0.0, 0.0, 0.0];
/// Thumb open and adducted beside the index finger.
const TH_ADD_OPEN: [f64; 5] = [0.0, 0.15, 0.0, 0.0, 0.0];

/// Spread fingers (all participating) with J4 apart by `s`, J3 and J0.
fn spread(s: f64, j3: f64, j0: f64) -> [FingerPose; 4] {
    [
        fp(-s, j3, j0),
        fp(0.0, j3, j0),
        fp(-0.5 * s, j3, j0),
        fp(-s, j3, j0),
    ]
}

/// Fingers with `n` participating (FF first) at `p`, the others at `rest`.
fn first(n: usize, p: FingerPose, rest: FingerPose) -> [FingerPose; 4] {
    std::array::from_fn(|k| if k < n { p } else { rest })
}

fn shape(fingers: [FingerPose; 4], lf_j5: f64, thumb: [f64; 5]) -> HandShape {
    HandShape {
        fingers,
        lf_j5,
        thumb,
    }
}

/// The grasp types of the GRASP taxonomy the Shadow hand forms on the simulator's box and
/// cylinder objects, grasped from above (23 of 33; see [`EXCLUDED_TYPES`] for the rest).
pub fn grasp_types() -> Vec<GraspType> {
    use Category::*;
    use Opposition::*;
    use SizeClass::*;
    use ThumbPosition::*;
    let all = [true; 5];
    let fingers = |n: usize| -> [bool; 5] { std::array::from_fn(|k| k < n || k == 4) };
    let t = |feix, name, category, opposition, thumb, fingers, size, preshape, closed| GraspType {
        feix,
        name,
        category,
        opposition,
        thumb,
        fingers,
        size,
        preshape,
        closed,
    };
    let open = |s: f64| shape(spread(s, 0.1, 0.2), 0.0, TH_OPEN);
    vec![
        // Power grasps, palm opposition: fingers wrap, thumb opposed.
        t(
            1,
            "large_diameter",
            Power,
            Palm,
            Abducted,
            all,
            Large,
            open(0.1),
            shape(spread(0.1, 1.3, 2.0), 0.3, [0.55, 1.2, 0.2, 0.4, 0.8]),
        ),
        t(
            2,
            "small_diameter",
            Power,
            Palm,
            Abducted,
            all,
            Small,
            open(0.0),
            shape(spread(0.0, 1.55, 2.9), 0.5, [0.7, 1.22, 0.2, 0.6, 1.3]),
        ),
        t(
            3,
            "medium_wrap",
            Power,
            Palm,
            Abducted,
            all,
            Medium,
            open(0.05),
            shape(spread(0.05, 1.45, 2.5), 0.4, [0.65, 1.2, 0.2, 0.5, 1.1]),
        ),
        t(
            10,
            "power_disk",
            Power,
            Palm,
            Abducted,
            all,
            Disk,
            open(0.3),
            shape(spread(0.3, 1.3, 1.8), 0.5, [0.6, 1.2, 0.1, 0.4, 0.9]),
        ),
        t(
            11,
            "power_sphere",
            Power,
            Palm,
            Abducted,
            all,
            Medium,
            open(0.3),
            shape(spread(0.3, 1.35, 2.1), 0.6, [0.65, 1.2, 0.15, 0.4, 0.9]),
        ),
        // Power grasps, palm opposition, thumb adducted beside the index finger.
        t(
            4,
            "adducted_thumb",
            Power,
            Palm,
            Adducted,
            all,
            Medium,
            shape(spread(0.0, 0.1, 0.2), 0.0, TH_ADD_OPEN),
            shape(spread(0.0, 1.45, 2.5), 0.3, [0.2, 0.45, 0.1, 0.4, 0.7]),
        ),
        t(
            5,
            "light_tool",
            Power,
            Palm,
            Adducted,
            all,
            Small,
            shape(spread(0.0, 0.1, 0.2), 0.0, TH_ADD_OPEN),
            shape(spread(0.0, 1.55, 2.8), 0.4, [0.25, 0.5, 0.1, 0.5, 0.9]),
        ),
        // Power grasps, pad opposition.
        t(
            18,
            "extension_type",
            Power,
            Pad,
            Abducted,
            all,
            Flat,
            open(0.1),
            shape(spread(0.1, 1.2, 0.5), 0.2, [0.5, 1.2, 0.1, 0.2, 0.3]),
        ),
        t(
            26,
            "sphere_4_finger",
            Power,
            Pad,
            Abducted,
            all,
            Medium,
            open(0.3),
            shape(spread(0.3, 1.0, 1.4), 0.5, [0.6, 1.2, 0.1, 0.3, 0.5]),
        ),
        t(
            28,
            "sphere_3_finger",
            Power,
            Pad,
            Abducted,
            fingers(3),
            Medium,
            shape(first(3, fp(-0.2, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(3, fp(-0.2, 1.0, 1.4), CURL),
                0.3,
                [0.6, 1.2, 0.1, 0.3, 0.5],
            ),
        ),
        t(
            31,
            "ring",
            Power,
            Pad,
            Abducted,
            fingers(1),
            Medium,
            shape(first(1, fp(0.0, 0.1, 0.2), fp(0.0, 0.6, 0.8)), 0.0, TH_OPEN),
            shape(
                first(1, fp(0.0, 1.2, 2.2), fp(0.0, 0.9, 1.4)),
                0.2,
                [0.7, 1.22, 0.2, 0.5, 1.0],
            ),
        ),
        // Precision grasps, pad opposition.
        t(
            6,
            "prismatic_4_finger",
            Precision,
            Pad,
            Abducted,
            all,
            Small,
            open(0.0),
            shape(spread(0.0, 1.0, 0.9), 0.2, [0.45, 1.2, 0.1, 0.2, 0.3]),
        ),
        t(
            7,
            "prismatic_3_finger",
            Precision,
            Pad,
            Abducted,
            fingers(3),
            Small,
            shape(first(3, fp(0.0, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(3, fp(0.0, 1.0, 0.9), CURL),
                0.2,
                [0.45, 1.2, 0.1, 0.2, 0.3],
            ),
        ),
        t(
            8,
            "prismatic_2_finger",
            Precision,
            Pad,
            Abducted,
            fingers(2),
            Small,
            shape(first(2, fp(0.0, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(2, fp(0.0, 1.0, 0.9), CURL),
                0.1,
                [0.4, 1.2, 0.1, 0.2, 0.3],
            ),
        ),
        t(
            9,
            "palmar_pinch",
            Precision,
            Pad,
            Abducted,
            fingers(1),
            Tiny,
            shape(first(1, fp(0.0, 0.1, 0.2), EXT), 0.0, TH_OPEN),
            shape(
                first(1, fp(0.0, 1.1, 0.6), EXT),
                0.0,
                [0.35, 1.2, 0.1, 0.2, 0.2],
            ),
        ),
        t(
            12,
            "precision_disk",
            Precision,
            Pad,
            Abducted,
            all,
            Disk,
            open(0.3),
            shape(spread(0.3, 1.0, 0.8), 0.5, [0.5, 1.2, 0.1, 0.2, 0.3]),
        ),
        t(
            13,
            "precision_sphere",
            Precision,
            Pad,
            Abducted,
            all,
            Small,
            open(0.3),
            shape(spread(0.3, 1.0, 1.0), 0.6, [0.5, 1.2, 0.1, 0.2, 0.4]),
        ),
        t(
            14,
            "tripod",
            Precision,
            Pad,
            Abducted,
            fingers(2),
            Small,
            shape(first(2, fp(0.1, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(2, fp(0.1, 1.05, 1.0), CURL),
                0.1,
                [0.45, 1.2, 0.1, 0.2, 0.4],
            ),
        ),
        t(
            24,
            "tip_pinch",
            Precision,
            Pad,
            Abducted,
            fingers(1),
            Tiny,
            shape(first(1, fp(0.0, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(1, fp(0.0, 1.1, 1.4), CURL),
                0.0,
                [0.4, 1.2, 0.1, 0.3, 0.6],
            ),
        ),
        t(
            27,
            "quadpod",
            Precision,
            Pad,
            Abducted,
            fingers(3),
            Small,
            shape(first(3, fp(-0.1, 0.1, 0.2), CURL), 0.0, TH_OPEN),
            shape(
                first(3, fp(-0.1, 1.05, 1.1), CURL),
                0.2,
                [0.5, 1.2, 0.1, 0.2, 0.4],
            ),
        ),
        t(
            33,
            "inferior_pincer",
            Precision,
            Pad,
            Abducted,
            fingers(1),
            Tiny,
            shape(first(1, fp(0.0, 0.1, 0.2), EXT), 0.0, TH_OPEN),
            shape(
                first(1, fp(0.0, 1.0, 1.6), EXT),
                0.0,
                [0.4, 1.2, 0.1, 0.3, 0.7],
            ),
        ),
        t(
            22,
            "parallel_extension",
            Precision,
            Pad,
            Adducted,
            all,
            Flat,
            shape(spread(0.0, 0.1, 0.1), 0.0, [0.1, 0.5, 0.0, 0.0, 0.0]),
            shape(spread(0.0, 1.2, 0.3), 0.1, [0.3, 1.0, 0.1, 0.2, 0.2]),
        ),
        // Intermediate: lateral pinch, thumb pad on the side of the index finger.
        t(
            16,
            "lateral",
            Intermediate,
            Side,
            Adducted,
            fingers(1),
            Flat,
            shape(first(1, fp(0.0, 0.3, 0.6), CURL), 0.0, TH_ADD_OPEN),
            shape(
                first(1, fp(0.0, 1.3, 2.0), CURL),
                0.0,
                [0.3, 0.6, 0.1, 0.4, 0.6],
            ),
        ),
    ]
}

/// The grasp types of the GRASP taxonomy NOT collected, with the reason (Feix number,
/// name, reason).
pub const EXCLUDED_TYPES: [(u8, &str, &str); 10] = [
    (15, "fixed_hook", "holds a handle by hooked fingers without the thumb; the sim has no handle objects"),
    (17, "index_finger_extension", "a tool held with the index finger along it; needs a long tool object held from the side"),
    (19, "distal_type", "scissors-like: needs finger loops"),
    (20, "writing_tripod", "a pen resting in the thumb web; the hand model has no collision geometry there"),
    (21, "tripod_variation", "side opposition on a thin stick held between fingers; needs finger-finger contact the sim disables"),
    (23, "adduction_grip", "an object squeezed between two fingers; the sim disables finger-finger contact and J4 (+-20 deg) cannot squeeze"),
    (25, "lateral_tripod", "side opposition of the middle finger on a stick; needs thin stick objects held from the side"),
    (29, "stick", "a thin stick held across the fingers; needs finger-finger contact the sim disables"),
    (30, "palmar", "a flat object pressed by the flat palm and fingers from below; not reachable from above"),
    (32, "ventral", "a thin stick held across the index finger by the thumb side; needs finger-finger contact"),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Robot, Side};
    use crate::synergy::collect::SelfCollision;

    #[test]
    fn hand_shape_angles_follow_the_paper_order() {
        let s = shape(spread(0.2, 1.0, 1.6), 0.4, [0.1, 0.2, 0.3, 0.4, 0.5]);
        let q = s.angles();
        let at = |n: &str| q[hand_index(n).unwrap_or(0)];
        assert_eq!(at("FFJ4"), -0.2);
        assert_eq!(at("MFJ4"), 0.0);
        assert_eq!(at("RFJ4"), -0.1);
        assert_eq!(at("LFJ4"), -0.2);
        assert_eq!(at("FFJ3"), 1.0);
        assert_eq!(at("RFJ2"), 0.8);
        assert_eq!(at("LFJ1"), 0.8);
        assert_eq!(at("LFJ5"), 0.4);
        assert_eq!(at("THJ5"), 0.1);
        assert_eq!(at("THJ1"), 0.5);
        assert_eq!(q[0], 0.0);
        assert_eq!(q[1], 0.0);
    }

    #[test]
    fn the_table_covers_the_33_types_once() {
        let types = grasp_types();
        let mut all: Vec<u8> = types.iter().map(|t| t.feix).collect();
        all.extend(EXCLUDED_TYPES.iter().map(|e| e.0));
        all.sort_unstable();
        assert_eq!(all, (1..=33).collect::<Vec<u8>>());
        let limits = Robot::builtin(Side::Left).hand_limits();
        for t in &types {
            assert!(!t.name.contains(','), "{}", t.name);
            for (k, v) in t.preshape.angles().iter().enumerate() {
                assert!(
                    (limits[k].0..=limits[k].1).contains(v),
                    "{} preshape {k}",
                    t.name
                );
            }
            // The preshape is free of self-collisions.
            let c = SelfCollision::new(&Robot::builtin(Side::Left));
            assert!(c.check(&t.preshape.angles()).is_none(), "{}", t.name);
            // Non-participating fingers do not move toward the object differently from
            // the taxonomy: a participating finger flexes J3 from preshape to closed.
            for f in 0..4 {
                if t.fingers[f] {
                    assert!(
                        t.closed.fingers[f].j3 > t.preshape.fingers[f].j3,
                        "{}",
                        t.name
                    );
                }
            }
        }
    }
}
