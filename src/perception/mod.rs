//! What the robot's cameras see and where the hand is placed from it: point clouds (PCD and
//! PLY readers, normals, antipodal two-finger grasp candidates), synthetic partial views,
//! the simulated depth cameras, and the antipodal pre-grasp planner.
//!
//! This layer sits below the environment: the environment starts episodes from planned
//! pre-grasps in evaluation and training alike, and `grasp run` plans on the same code.
//! It reads the simulator (to cast the cameras' rays) and the robot's grasp geometry, and
//! nothing above them.
//!
//! - [`pointcloud`]: PCD/PLY readers, a PCD writer.
//! - [`antipodal`]: normals, antipodal two-finger candidates, the narrow-axis fallback.
//! - [`partial_view`]: synthetic surface samples and partial-view clouds with noise.
//! - [`camera`]: the simulated depth cameras ([`camera::camera_cloud`]).
//! - [`pregrasp`]: the planner interface and the antipodal planner on the simulated cloud.

pub mod antipodal;
pub mod camera;
pub mod partial_view;
pub mod pointcloud;
pub mod pregrasp;
