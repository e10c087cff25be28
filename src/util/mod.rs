//! Small helpers shared across the crate: atomic writes, TOML configuration loading, the
//! torque levels, thread counts, numbers in messages and the statistics of measurements.

pub mod config;
pub mod fsx;
pub mod levels;
pub mod num;
pub mod stats;
pub mod threads;
