//! The robot model: the Shadow hand's joint table, URDF loading, forward kinematics and
//! the UR10e arm.

pub mod joints;

pub use joints::Side;
