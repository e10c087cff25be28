//! Small helpers shared across the crate: atomic writes, TOML configuration loading and
//! the torque levels.

pub mod config;
pub mod fsx;
pub mod levels;
