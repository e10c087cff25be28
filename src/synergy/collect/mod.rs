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

use crate::robot::{Robot, Side};
use crate::sim::{HandSim, ObjectSpec, Scene, SimConfig, SimError};
use crate::synergy::{finger_limits, Dataset, N_FINGER_JOINTS};
use crate::util::fsx::{write_atomic, WriteError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;
use std::path::Path;

mod self_collision;
mod taxonomy;

pub use self_collision::{segment_distance, Collision, SelfCollision};
pub use taxonomy::*;

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
