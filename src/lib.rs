//! `grasp`: multifingered grasping with multimodal reinforcement learning.
//!
//! A Shadow dexterous hand on a UR10e arm learns to grasp unseen objects. The crate is laid
//! out so the design can be read from the tree; dependencies flow one way:
//!
//! - [`robot`]: URDF loading, the joint table, coupling, limits, forward kinematics and the
//!   UR10e kinematics.
//! - [`synergy`]: pose datasets and PCA hand synergies (P and P^-1 of eq. 2).
//! - [`objects`]: primitives, meshes, procedural shapes, object sets.
//! - [`hardware`]: the robot interface, sensor mapping, safety layer, logs.
//! - [`perception`]: point clouds, the simulated depth cameras and the antipodal pre-grasp
//!   planner (used by the environment and by `grasp run`).
//! - [`sim`]: the Rapier simulation of hand, table and object, with tactile and torque sensing.
//! - [`util`]: small shared helpers (atomic file writes, TOML configs, where a default
//!   naming a shipped file lies from any working directory).
//! - [`env`](mod@env): the gymnasium-style environment API, a parallel vector of environments and a
//!   textbook control task.
//! - [`eval`]: per-object success rates with Wilson intervals, Table-I layout; episode
//!   recordings with a 3D replay page.
//! - [`experiment`]: grids of training runs (the paper's ablations), summaries and Fig.-5
//!   style plots.
//! - [`policy`]: GRU and MLP actor-critics on candle and their action distribution.
//! - [`ppo`]: the PPO learner: rollouts, GAE, losses, checkpoints.
//! - [`checkpoint`]: the checkpoint folder: its file names, the training config's schema
//!   and [`checkpoint::TrainedAgent`], the one loader of a trained agent (weights, MDP,
//!   synergy model, simulator config) for evaluation, `grasp run`, experiments, the
//!   regression check and the Python module.
//! - [`train`]: training runs (`grasp train` as a library): the run folder, metrics,
//!   TensorBoard events, the learning-curve plot and the environments of a config.
//! - [`run`]: grasp attempts on a hand-arm system: the simulator behind the hardware
//!   interface, tactile calibration, the grasp pipeline of Sec. V-B and `grasp run` as one
//!   request ([`run::request`]: checked, loaded and carried out here; the command prints).
//! - `python` (feature `python`): the PyO3 module `grasp_rl._core`, a thin layer over
//!   [`env`](mod@env) that the `grasp_rl` package (`python/`) exposes to gymnasium.

pub mod checkpoint;
pub mod env;
pub mod eval;
pub mod experiment;
pub mod hardware;
pub mod objects;
pub mod perception;
pub mod policy;
pub mod ppo;
#[cfg(feature = "python")]
pub mod python;
pub mod robot;
pub mod run;
pub mod sim;
pub mod synergy;
pub mod train;
pub mod util;
