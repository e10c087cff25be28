//! Small helpers shared across the crate: atomic writes, TOML configuration loading, the
//! torque levels, thread counts and numbers in messages.

pub mod config;
pub mod fsx;
pub mod levels;
pub mod num;
pub mod threads;
