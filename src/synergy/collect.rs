//! Collecting human-like grasp postures in simulation (`grasp pca collect`, issue 5).
//!
//! The paper's synergy dataset covers the 33 grasp types of the GRASP taxonomy (Feix et
//! al., "The GRASP Taxonomy of Human Grasp Types", IEEE THMS 2016). This module makes such
//! a dataset with the project's own simulator: for each sample it picks a grasp type of
//! [`grasp_types`], an object of a size that suits it, places the hand above the object in
//! the type's PRESHAPE, closes it toward the type's CLOSED posture along a smooth
//! trajectory (each joint stops at its target or its torque limit, like the paper's
//! baseline 1), and records the 22 finger angles once the hand holds the object in stable
//! contact.
//!
//! # Procedure, per sample
//! 1. The grasp type is the sample index modulo the number of types (every type gets the
//!    same share). Seeded draw (`ChaCha8Rng`, one stream per sample and attempt, so the
//!    result does not depend on the number of threads): object of the type's
//!    [`SizeClass`] (box or upright cylinder, sizes 2-10 cm, mass 50-500 g, friction 0.8),
//!    a jitter of the type's closed posture (up to [`CLOSED_JITTER`] rad per parameter),
//!    hand yaw in `[-pi, pi)` and a height offset.
//! 2. [`Scene::above`] with the preshape as start posture. The height puts the palm
//!    surface 5 to 20 mm above the object's top ([`z_offset_for`]).
//! 3. Closing over [`CLOSE_PERIODS`] periods of 0.1 s with a smoothstep profile from the
//!    preshape to the closed posture; after each period, every joint whose actuator's torque
//!    level reached 0 or the top level stops where its target is.
//! 4. Hold for up to [`HOLD_PERIODS`] periods of 0.1 s. The posture is recorded at the
//!    first hold period that ends in stable contact: at least two fingertips touch the
//!    object (the simulator's binary tactile sensors), or the total hand-object normal
//!    force is above [`MIN_HOLD_FORCE`] and changed by at most 10 % (+ 0.05 N) over the
//!    last 0.1 s.
//! 5. Checks: no physics failure; every simulated angle within its joint limits widened
//!    by [`LIMIT_SLACK`] (the solver's slack); no self-collision ([`SelfCollision`]; the
//!    simulator disables hand self-collisions, so this filter matters).
//! 6. Per-joint uniform noise in `[-NOISE, +NOISE]` ([`NOISE`] = 0.02 rad) mimics the
//!    variability of human demonstrations; the result is clamped to the joint limits (so
//!    every recorded angle lies within them).
//!
//! A rejected attempt is redrawn (another attempt of the same sample) up to
//! [`CollectOptions::max_attempts`] times.

use crate::robot::joints::hand_index;
use crate::robot::model::Geometry;
use crate::robot::{Robot, Side};
use crate::sim::{HandSim, ObjectShape, ObjectSpec, Scene, SimConfig, SimError};
use crate::synergy::{finger_limits, Dataset, N_FINGER_JOINTS};
use crate::util::fsx::{write_atomic, WriteError};
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::path::Path;

/// Largest per-joint noise added to a recorded posture (rad).
pub const NOISE: f64 = 0.02;
/// How far (rad) a simulated angle may exceed its joint limit (solver slack) before the
/// posture is rejected; smaller excursions are clamped.
pub const LIMIT_SLACK: f64 = 0.02;
/// Largest random change (rad) of each closed-posture parameter of a grasp type.
pub const CLOSED_JITTER: f64 = 0.1;
/// Closing periods of 0.1 s (the trajectory lasts 1 s).
pub const CLOSE_PERIODS: usize = 10;
/// Hold periods of 0.1 s in which stable contact is looked for.
pub const HOLD_PERIODS: usize = 4;
/// Smallest total hand-object normal force (N) of a stable one-tip or palm grasp.
pub const MIN_HOLD_FORCE: f64 = 0.2;
/// Penetration (m) two finger capsules may have before they count as a self-collision.
pub const SELF_COLLISION_TOLERANCE: f64 = 0.001;

/// Error of the collection.
#[derive(Debug, thiserror::Error)]
pub enum CollectError {
    /// An option is out of range.
    #[error("collect: {what} = {value}: {message}")]
    Option {
        /// The option.
        what: &'static str,
        /// The value given.
        value: String,
        /// The allowed range.
        message: &'static str,
    },
    /// The simulator rejected its inputs.
    #[error("collect: simulator: {0}")]
    Sim(#[from] SimError),
    /// A sample failed every attempt.
    #[error(
        "collect: sample {sample} found no acceptable posture in {attempts} attempts \
         (raise --max-attempts)"
    )]
    Exhausted {
        /// The sample index.
        sample: usize,
        /// Attempts made.
        attempts: usize,
    },
    /// The CSV could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

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
    fn jittered(&self, rng: &mut ChaCha8Rng, amp: f64) -> HandShape {
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

/// Height of the grasp point above the object centre for a preshape: the palm surface
/// `clearance` m above the object's top, and the grasp point at least 1 cm above the table.
pub fn z_offset_for(
    robot: &Robot,
    preshape: &[f64; 24],
    object: &ObjectSpec,
    clearance: f64,
) -> f64 {
    let tips = robot.fingertips_palm(preshape);
    let (th, lf) = (tips[4], tips[3]);
    let gp_y = (th.y + lf.y) / 2.0;
    // The palm's contact surface faces -y at y = PALM_SURFACE_Y (palm frame).
    let h_palm = PALM_SURFACE_Y - gp_y;
    let half_h = object.shape.rest_height();
    (half_h + clearance - h_palm).max(-half_h + 0.01)
}

/// The y (palm frame) of the palm's front face (the -y face of the palm boxes).
const PALM_SURFACE_Y: f64 = -0.012;

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
    robot: Robot,
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

/// Options of [`collect`].
#[derive(Debug, Clone, PartialEq)]
pub struct CollectOptions {
    /// Postures to record.
    pub samples: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Attempts per sample before the collection fails.
    pub max_attempts: usize,
}

impl Default for CollectOptions {
    /// 3000 samples, seed 0, 50 attempts per sample.
    fn default() -> Self {
        CollectOptions {
            samples: 3000,
            seed: 0,
            max_attempts: 50,
        }
    }
}

/// One recorded posture.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CollectedPose {
    /// The 22 finger angles (rad, [`FINGER_JOINTS`](crate::robot::joints::FINGER_JOINTS) order).
    pub joints: [f64; N_FINGER_JOINTS],
    /// The grasp type's name.
    pub grasp_type: &'static str,
}

/// Why attempts were rejected, and how many.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CollectStats {
    /// Attempts made in all.
    pub attempts: usize,
    /// Attempts whose physics failed.
    pub physics_failure: usize,
    /// Attempts that found no stable contact.
    pub no_stable_contact: usize,
    /// Attempts whose posture left the joint limits by more than [`LIMIT_SLACK`].
    pub outside_limits: usize,
    /// Attempts whose posture collided with itself.
    pub self_collision: usize,
    /// Per grasp type, in [`grasp_types`] order: name, recorded postures, attempts.
    pub per_type: Vec<(String, usize, usize)>,
}

/// The result of [`collect`].
#[derive(Debug, Clone, PartialEq)]
pub struct Collection {
    /// The postures, in sample order.
    pub poses: Vec<CollectedPose>,
    /// Rejection statistics.
    pub stats: CollectStats,
}

impl Collection {
    /// The postures as a [`Dataset`] (extras empty; `path` is the given path).
    pub fn dataset(&self, path: &Path) -> Dataset {
        Dataset {
            rows: self.poses.iter().map(|p| p.joints).collect(),
            extras: Vec::new(),
            path: path.to_path_buf(),
        }
    }

    /// CSV text: [`Dataset::to_csv_string`] (22 prefixed joint columns) plus a last column
    /// `grasp_type`.
    pub fn to_csv_string(&self, side: Side) -> String {
        let base = self.dataset(Path::new("")).to_csv_string(side);
        let mut out = String::with_capacity(base.len() + self.poses.len() * 24);
        for (k, line) in base.lines().enumerate() {
            out.push_str(line);
            out.push(',');
            match k {
                0 => out.push_str("grasp_type"),
                _ => out.push_str(self.poses[k - 1].grasp_type),
            }
            out.push('\n');
        }
        out
    }

    /// Writes [`Collection::to_csv_string`] to `path` atomically.
    pub fn write_csv(&self, path: &Path, side: Side) -> Result<(), CollectError> {
        write_atomic(path, self.to_csv_string(side).as_bytes())?;
        Ok(())
    }
}

/// A finished sample: grasp type index, posture, its attempts.
type SampleResult = (usize, [f64; N_FINGER_JOINTS], CollectStats);

/// Outcome of one attempt.
enum Attempt {
    Pose([f64; N_FINGER_JOINTS]),
    PhysicsFailure,
    NoContact,
    Limits,
    SelfCollision,
}

/// The seed of attempt `attempt` of sample `sample` (SplitMix64 mixing).
fn sample_seed(seed: u64, sample: usize, attempt: usize) -> u64 {
    let mut z = seed
        ^ (sample as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (attempt as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// True when the hand holds the object stably: >= 2 fingertips touch it, or the total
/// hand-object force is at least [`MIN_HOLD_FORCE`] and changed by at most 10 % + 0.05 N.
pub fn is_stable(tactile: &[u8; 5], force: f64, previous_force: f64) -> bool {
    let tips = tactile.iter().filter(|t| **t > 0).count();
    tips >= 2 || (force >= MIN_HOLD_FORCE && (force - previous_force).abs() <= 0.1 * force + 0.05)
}

/// Runs one attempt; `Err` only for invalid simulator inputs.
fn attempt(
    robot: &Robot,
    cfg: &SimConfig,
    types: &[GraspType],
    checker: &SelfCollision,
    ti: usize,
    seed: u64,
) -> Result<(usize, Attempt), CollectError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let gt = &types[ti];
    let object = gt.size.draw(&mut rng);
    let closed = gt.closed.jittered(&mut rng, CLOSED_JITTER).angles();
    let pre = gt.preshape.angles();
    let yaw = rng.random_range(-PI..PI);
    let clearance = rng.random_range(0.005..0.02);
    let z = z_offset_for(robot, &pre, &object, clearance);
    let mut sim = HandSim::new(robot, object.clone(), cfg.clone())?;
    sim.reset(&Scene::above(&object, pre, z, yaw))?;
    let start = sim.targets();
    let per = (0.1 / cfg.dt).round().max(1.0) as usize;
    let act = crate::sim::script::actuator_of_joint();
    let top = cfg.sensors.torque_thresholds.len() as u8;
    let mut targets = start;
    let mut stopped = [false; 24];
    let mut previous_force = 0.0;
    for k in 0..CLOSE_PERIODS + HOLD_PERIODS {
        if k < CLOSE_PERIODS {
            let s = (k + 1) as f64 / CLOSE_PERIODS as f64;
            let s = s * s * (3.0 - 2.0 * s);
            for j in 2..24 {
                if !stopped[j] {
                    targets[j] = start[j] + (closed[j] - start[j]) * s;
                }
            }
            sim.set_targets(&targets)?;
        }
        for _ in 0..per {
            if !sim.step_physics() {
                return Ok((ti, Attempt::PhysicsFailure));
            }
        }
        let sensors = sim.sensors();
        for j in 2..24 {
            let lvl = sensors.torque_level[act[j]];
            if lvl == 0 || lvl == top {
                stopped[j] = true;
            }
        }
        let force = sim.hand_object_force();
        if k >= CLOSE_PERIODS && is_stable(&sensors.tactile, force, previous_force) {
            return Ok((ti, finish(&sensors.q, checker, &mut rng)));
        }
        previous_force = force;
    }
    Ok((ti, Attempt::NoContact))
}

/// Limit check, self-collision check, noise.
fn finish(q: &[f64; 24], checker: &SelfCollision, rng: &mut ChaCha8Rng) -> Attempt {
    let limits = finger_limits(checker.robot.hand.side);
    let mut row = [0.0; N_FINGER_JOINTS];
    for (j, v) in row.iter_mut().enumerate() {
        let (lo, hi) = limits[j];
        let x = q[j + 2];
        if !x.is_finite() || x < lo - LIMIT_SLACK || x > hi + LIMIT_SLACK {
            return Attempt::Limits;
        }
        *v = x.clamp(lo, hi);
    }
    let mut full = *q;
    full[0] = 0.0;
    full[1] = 0.0;
    for (j, v) in row.iter().enumerate() {
        full[j + 2] = *v;
    }
    if checker.check(&full).is_some() {
        return Attempt::SelfCollision;
    }
    for (j, v) in row.iter_mut().enumerate() {
        let (lo, hi) = limits[j];
        *v = (*v + rng.random_range(-NOISE..=NOISE)).clamp(lo, hi);
    }
    Attempt::Pose(row)
}

/// Collects `opts.samples` postures with `robot`'s hand in simulators configured by `cfg`,
/// in parallel on the current rayon pool (results do not depend on the thread count).
/// `on_sample` is called once per finished sample (for a progress bar).
pub fn collect(
    robot: &Robot,
    cfg: &SimConfig,
    opts: &CollectOptions,
    on_sample: &(dyn Fn() + Sync),
) -> Result<Collection, CollectError> {
    if opts.samples == 0 {
        return Err(CollectError::Option {
            what: "samples",
            value: "0".into(),
            message: "must be at least 1",
        });
    }
    if opts.max_attempts == 0 {
        return Err(CollectError::Option {
            what: "max_attempts",
            value: "0".into(),
            message: "must be at least 1",
        });
    }
    cfg.validate().map_err(SimError::from)?;
    let types = grasp_types();
    let checker = SelfCollision::new(robot);
    let results: Vec<Result<SampleResult, CollectError>> = (0..opts.samples)
        .into_par_iter()
        .map(|i| {
            let mut st = CollectStats::default();
            for a in 0..opts.max_attempts {
                st.attempts += 1;
                let ti = i % types.len();
                let seed = sample_seed(opts.seed, i, a);
                let (ti, out) = attempt(robot, cfg, &types, &checker, ti, seed)?;
                match out {
                    Attempt::Pose(row) => {
                        on_sample();
                        return Ok((ti, row, st));
                    }
                    Attempt::PhysicsFailure => st.physics_failure += 1,
                    Attempt::NoContact => st.no_stable_contact += 1,
                    Attempt::Limits => st.outside_limits += 1,
                    Attempt::SelfCollision => st.self_collision += 1,
                }
            }
            Err(CollectError::Exhausted {
                sample: i,
                attempts: opts.max_attempts,
            })
        })
        .collect();
    let mut stats = CollectStats {
        per_type: types.iter().map(|t| (t.name.to_string(), 0, 0)).collect(),
        ..Default::default()
    };
    let mut poses = Vec::with_capacity(opts.samples);
    for r in results {
        let (ti, joints, st) = r?;
        stats.attempts += st.attempts;
        stats.physics_failure += st.physics_failure;
        stats.no_stable_contact += st.no_stable_contact;
        stats.outside_limits += st.outside_limits;
        stats.self_collision += st.self_collision;
        stats.per_type[ti].1 += 1;
        stats.per_type[ti].2 += st.attempts;
        poses.push(CollectedPose {
            joints,
            grasp_type: types[ti].name,
        });
    }
    Ok(Collection { poses, stats })
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn stability_rule_hand_computed() {
        assert!(is_stable(&[1, 0, 0, 0, 1], 0.0, 0.0));
        assert!(!is_stable(&[1, 0, 0, 0, 0], 0.1, 0.1));
        // 1.0 N vs 0.9 N: |0.1| <= 0.1 + 0.05.
        assert!(is_stable(&[0; 5], 1.0, 0.9));
        // 1.0 N vs 0.8 N: 0.2 > 0.15.
        assert!(!is_stable(&[0; 5], 1.0, 0.8));
    }

    #[test]
    fn seeds_differ_per_sample_and_attempt() {
        let a = sample_seed(1, 0, 0);
        assert_ne!(a, sample_seed(1, 1, 0));
        assert_ne!(a, sample_seed(1, 0, 1));
        assert_ne!(a, sample_seed(2, 0, 0));
        assert_eq!(a, sample_seed(1, 0, 0));
    }

    #[test]
    fn options_are_checked() {
        let r = Robot::builtin(Side::Left);
        let cfg = SimConfig::default();
        let bad = CollectOptions {
            samples: 0,
            ..Default::default()
        };
        assert!(matches!(
            collect(&r, &cfg, &bad, &|| {}),
            Err(CollectError::Option {
                what: "samples",
                ..
            })
        ));
    }

    #[test]
    fn objects_fit_their_size_class() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            for c in [
                SizeClass::Large,
                SizeClass::Tiny,
                SizeClass::Flat,
                SizeClass::Disk,
            ] {
                let o = c.draw(&mut rng);
                o.validate().unwrap();
                assert!((0.05 - 1e-9..=0.5 + 1e-9).contains(&o.mass), "{o:?}");
                assert_eq!(o.friction, 0.8);
            }
        }
    }
}
