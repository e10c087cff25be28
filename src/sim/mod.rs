//! The simulator: the Shadow hand on a Cartesian lift grasping one object on a table, in
//! Rapier, with tactile and torque sensing (issue 3).
//!
//! - [`bench`]: throughput measurement (one env and many in a rayon pool).
//! - [`config`]: [`SimConfig`], every number, with defaults and validation.
//! - [`world`]: [`HandSim`], building, reset, targets, stepping, sensors, lift and judgement.
//! - [`sensors`]: the PD effort read-back and the torque levels.
//! - [`placement`]: the top-down grasp mapping that places the hand.
//! - [`object`]: primitive objects.
//! - [`script`]: the scripted close-and-lift used by `grasp sim` and the tests.

pub mod bench;
pub mod config;
pub mod object;
pub mod placement;
pub mod script;
pub mod sensors;
pub mod world;

pub use config::SimConfig;
pub use object::{ObjectShape, ObjectSpec};
pub use sensors::Sensors;
pub use world::{HandSim, LiftOutcome, PhysicsFailure, Scene, SimError};

/// Index of a hand joint name (paper order) known to exist.
pub(crate) fn hand_index(name: &str) -> usize {
    crate::robot::joints::hand_index(name).unwrap_or(0)
}
