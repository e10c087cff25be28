//! The grasping MDP of Sec. IV: observations, actions, reward, curriculum.
//!
//! - [`action`]: decoding and scaling of the policy output.
//! - [`obs`]: the observation frame `<a_{k-1}, phi, tau, theta>`, modalities, history.
//! - [`reward`]: eq. 4 and eq. 5.
//! - [`curriculum`]: eq. 6.

pub mod action;
pub mod curriculum;
pub mod obs;
pub mod reward;
