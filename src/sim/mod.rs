//! The simulator: the Shadow hand on a Cartesian lift grasping one object on a table, in
//! Rapier, with tactile and torque sensing (issue 3).
//!
//! - [`bench`](mod@bench): throughput measurement (one env and many in a rayon pool).
//! - [`config`]: [`SimConfig`], every number, with defaults and validation.
//! - [`world`]: [`HandSim`], building, reset, targets, stepping, sensors, lift and judgement.
//! - [`sensors`]: the PD effort read-back and the torque levels.
//! - [`placement`]: the hand placed by the top-down grasp mapping of
//!   [`crate::robot::grasp_map`].
//! - [`object`]: [`ObjectSpec`], any library object (or a primitive) as the simulator's
//!   body: convex parts, mass properties, friction.
//! - [`script`]: the scripted close-and-lift used by `grasp sim` and the tests.

//!
//! # Units and sensors
//! Metres, kilograms, seconds, radians, N and N m. Tactile: a finger reports 1 when the
//! normal force between its distal phalanx (tip included) and the object, the summed
//! contact impulses of the last physics step divided by `dt`, exceeds 0.05 N (the
//! calibration is tested: a resting object pushes on the table with m g). Torque: each of
//! the 20 actuators reports the effort of its PD law clamped to the URDF effort limit (N m;
//! coupled J0 = J1 + J2 efforts summed), times 100 sim units per N m, mapped to levels
//! 0..=5 by the thresholds [-20, -10, 0, 10, 20]. The wrist carries the hand's weight, so
//! its readings sit at the extreme levels even without contact.
//!
//! # Settings and the measurements behind them (this machine, 2 shared cores)
//! - `dt = 1/240 s`, 1 substep: with the scripted close-and-lift (4 seeded scenes, a 100 g
//!   box, a 0.5 kg box, a 0.05-friction box), 120 Hz x 1 substep dropped the 0.5 kg box;
//!   240 Hz with 1, 2 or 4 substeps and 480 Hz x 1 held both boxes and let the slippery one
//!   slip. 240 Hz x 1 is the cheapest that passes.
//! - Finger and thumb gains kp = 2 N m/rad, kd = 0.02 N m s/rad: a free FFJ3 step of
//!   0.95 rad reaches 97 % within one 0.2 s control period without overshoot, and a free
//!   finger's torque level stays 2..3. kp = 4 or 8 tracked to 100 % but tracking torques
//!   alone reached level 5 (torque no longer signals contact).
//! - Speed (release, criterion, load average ~4 on the 2 cores): 0.34 ms per physics step
//!   while gripping (~2900 steps/s, ~12 simulated s per wall s); `grasp bench sim`: 1 env
//!   2084 physics steps/s (8.7 simulated s/s), 20 envs on 2 threads 2020 steps/s. The
//!   profile is dominated by rapier's multibody mass matrix and its LU solves (62 %).
//!   MuJoCo reaches 55-78 simulated s/s on one core here.
//! - Reset (clone of the template world): 23 us.

pub mod bench;
pub mod config;
pub mod contact;
pub mod object;
pub mod placement;
pub mod script;
pub mod sensors;
pub mod settle;
pub mod world;

pub use config::SimConfig;
pub use object::{ConvexParts, ObjectSetError, ObjectShape, ObjectSpec};
pub use sensors::Sensors;
pub use world::{
    CriticGeometry, FailureReport, HandSim, LiftOutcome, ObjectContact, PhysicsFailure, Scene,
    SimError,
};

/// Index of a hand joint name (paper order) known to exist.
pub(crate) fn hand_index(name: &str) -> usize {
    crate::robot::joints::hand_index(name).unwrap_or(0)
}
