//! Small helpers shared across the crate: atomic writes and TOML configuration loading.

pub mod config;
pub mod fsx;
