//! Small helpers shared across the crate: where a default naming a shipped file lies
//! ([`assets`]), atomic writes, TOML configuration loading, a stable hash, the torque
//! levels, thread counts, numbers in messages, repeats in lists, stopping on a signal,
//! the statistics of measurements and a failed step's context ([`step`]).

pub mod assets;
pub mod config;
pub mod fsx;
pub mod hash;
pub mod levels;
pub mod num;
pub mod seq;
pub mod signal;
pub mod stats;
pub mod step;
pub mod threads;
