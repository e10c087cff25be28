//! The Python module `grasp_rl._core` (feature `python`): a thin PyO3 layer over
//! [`crate::env`] that the `grasp_rl` package (`python/grasp_rl/`) wraps as a
//! `gymnasium.Env` and a `gymnasium.vector.VectorEnv`.
//!
//! - [`config`]: training configs resolved as `grasp train` resolves them, with the
//!   Python-side overrides (objects, environments, threads, seed, difficulty).
//! - [`actions`]: flat `float32` action buffers decoded into [`crate::env::api::Action`]s,
//!   with errors naming the bad component.
//! - [`env`](mod@env): one grasping environment (gymnasium.Env) and the scripted baselines.
//! - [`vec_env`]: the rayon [`crate::env::api::VecEnv`] of a config (gymnasium VectorEnv).
//! - [`policy`]: a trained checkpoint acting on observations.
//! - [`error`]: library errors as Python exceptions.
//!
//! Arrays cross the boundary as `bytes` of native-endian `float32` (and `uint8` flags),
//! which the Python side views with `numpy.frombuffer`: no numpy dependency here. The
//! stepping itself runs with the GIL released. No panic crosses into Python: a panic
//! while stepping is caught and raised as `RuntimeError`.

pub mod actions;
pub mod config;
pub mod env;
pub mod error;
pub mod policy;
pub mod vec_env;

use pyo3::prelude::*;

/// The extension module `grasp_rl._core`.
#[pymodule]
#[pyo3(name = "_core")]
fn core_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<env::CoreEnv>()?;
    m.add_class::<vec_env::CoreVecEnv>()?;
    m.add_class::<policy::CorePolicy>()?;
    m.add_function(wrap_pyfunction!(config::builtin_config_toml, m)?)?;
    m.add_function(wrap_pyfunction!(config::resolved_config_toml, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
