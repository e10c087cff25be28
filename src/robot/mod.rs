//! The robot model: the Shadow hand's joint table, URDF generation and loading, forward
//! kinematics and the UR10e arm.
//!
//! - [`joints`]: names, the paper's joint order, coupling, published kinematic facts.
//! - [`urdf_gen`]: writes the project's URDF files from those facts.
//! - [`model`]: loads any URDF (ours or the maker's) into a validated [`Robot`].
//! - [`kinematics`]: forward kinematics and named postures.
//! - [`ur10e`]: DH forward and inverse kinematics of the arm.
//! - [`grasp_map`]: the two-finger-to-hand grasp mapping (Sec. V-B).

pub mod grasp_map;
pub mod joints;
pub mod kinematics;
pub mod model;
pub mod ur10e;
pub mod urdf_gen;

pub use joints::Side;
pub use kinematics::Posture;
pub use model::{MeshPolicy, Robot, RobotError};
