//! Environments: the gymnasium-style API the learner trains on, and a textbook control task
//! to prove the learner.

pub mod api;
pub mod cartpole;
