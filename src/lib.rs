//! `grasp`: multifingered grasping with multimodal reinforcement learning.
//!
//! A Shadow dexterous hand on a UR10e arm learns to grasp unseen objects. The crate is laid
//! out so the design can be read from the tree; dependencies flow one way:
//!
//! - [`robot`]: URDF loading, the joint table, coupling, limits, forward kinematics and the
//!   UR10e kinematics.
//! - [`synergy`]: pose datasets and PCA hand synergies (P and P^-1 of eq. 2).
//! - [`objects`]: primitives, meshes, procedural shapes, object sets.
//! - [`sim`]: the Rapier simulation of hand, table and object, with tactile and torque sensing.
//! - [`util`]: small shared helpers (atomic file writes, TOML configs).

pub mod objects;
pub mod robot;
pub mod sim;
pub mod synergy;
pub mod util;
