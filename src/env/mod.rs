//! Environments: the gymnasium-style API the learner trains on, the grasping MDP of
//! Sec. IV, and a textbook control task to prove the learner.
//!
//! - [`api`]: the `Env` trait and the parallel `VecEnv`.
//! - [`bench`](mod@bench): the random-agent throughput of a `VecEnv`.
//! - [`action`]: decoding and scaling of the policy output.
//! - [`obs`]: the observation frame `<a_{k-1}, phi, tau, theta>`, modalities, history.
//! - [`reward`]: eq. 4 and eq. 5.
//! - [`closing`]: the stage-1 closing trajectory T, in joint or synergy space.
//! - [`curriculum`]: eq. 6.
//! - [`randomize`]: per-episode domain randomisation (object and sensor noise).
//! - [`stream`]: training on the procedural object stream.
//! - [`placement`]: where an episode's hand starts: the top-down default, the antipodal
//!   pre-grasp ([`crate::perception::pregrasp`]) and their mix and perturbations in
//!   training (`[env.placement]`).
//! - [`grasp`]: the grasping environment (stages 1 and 2, lift) and the scripted baselines.
//! - [`cartpole`]: continuous CartPole, the learner's textbook check.

pub mod action;
pub mod api;
pub mod bench;
pub mod cartpole;
pub mod closing;
pub mod curriculum;
pub mod grasp;
pub mod object_curriculum;
pub mod obs;
pub mod phases;
pub mod placement;
pub mod randomize;
pub mod reward;
pub mod stream;
