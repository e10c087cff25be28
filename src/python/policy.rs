//! A trained checkpoint acting on observations, for `grasp_rl.Policy`: the agent `grasp
//! eval` runs ([`PolicyAgent`]: observations normalised as in training, the GRU state
//! carried across steps, the distribution's mode or a seeded sample).

use super::actions::f32_bytes;
use super::error::{locked, no_panic};
use crate::checkpoint::TrainedAgent;
use crate::env::grasp::Agent;
use crate::eval::PolicyAgent;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A checkpoint folder's policy (`checkpoint.safetensors`, with the `config.toml` and
/// `synergy.json` that `grasp train` saves beside it).
#[pyclass(module = "grasp_rl._core", frozen)]
pub struct CorePolicy {
    agent: Mutex<PolicyAgent>,
    /// The training config saved beside the checkpoint (TOML): build the environment the
    /// policy expects with `config_toml=`.
    #[pyo3(get)]
    config_toml: String,
    /// Observation length the policy reads.
    #[pyo3(get)]
    obs_dim: usize,
    /// Continuous action components it outputs.
    #[pyo3(get)]
    continuous: usize,
    /// The checkpoint folder.
    #[pyo3(get)]
    dir: PathBuf,
}

/// The shipped policy, `grasp run`'s default ([`crate::run::DEFAULT_POLICY`]), embedded:
/// the files a checkpoint folder needs.
const SHIPPED: [(&str, &[u8]); 3] = [
    (
        "checkpoint.safetensors",
        include_bytes!(concat!(
            "../../",
            crate::default_policy!(),
            "/checkpoint.safetensors"
        )),
    ),
    (
        "config.toml",
        include_bytes!(concat!("../../", crate::default_policy!(), "/config.toml")),
    ),
    (
        "synergy.json",
        include_bytes!(concat!("../../", crate::default_policy!(), "/synergy.json")),
    ),
];

/// The shipped policy's folder in the repository.
pub const SHIPPED_DIR: &str = crate::run::DEFAULT_POLICY;

impl CorePolicy {
    fn load(dir: PathBuf, stochastic: bool, seed: u64) -> PyResult<Self> {
        let trained = no_panic("loading the checkpoint", || TrainedAgent::load(&dir))?
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let config_path = dir.join(crate::checkpoint::files::CONFIG);
        let config_toml = std::fs::read_to_string(&config_path).map_err(|e| {
            PyValueError::new_err(format!("cannot read {}: {e}", config_path.display()))
        })?;
        let agent = PolicyAgent::new(trained.network().clone(), stochastic, seed);
        let (obs_dim, continuous) = agent.dims();
        Ok(CorePolicy {
            agent: Mutex::new(agent),
            config_toml,
            obs_dim,
            continuous,
            dir,
        })
    }
}

#[pymethods]
impl CorePolicy {
    /// Loads the checkpoint in `dir`; `stochastic` samples actions (seeded by `seed`)
    /// instead of taking the distribution's mode.
    #[new]
    #[pyo3(signature = (dir, stochastic=false, seed=0))]
    fn new(dir: PathBuf, stochastic: bool, seed: u64) -> PyResult<Self> {
        Self::load(dir, stochastic, seed)
    }

    /// The shipped policy (`grasp run`'s default, embedded in the module),
    /// unpacked into a temporary folder that is removed once it is loaded.
    #[staticmethod]
    #[pyo3(signature = (stochastic=false, seed=0))]
    fn shipped(stochastic: bool, seed: u64) -> PyResult<Self> {
        let tmp = tempfile::tempdir()
            .map_err(|e| PyRuntimeError::new_err(format!("temporary folder: {e}")))?;
        let name = Path::new(SHIPPED_DIR)
            .file_name()
            .ok_or_else(|| PyRuntimeError::new_err("the shipped policy's folder has no name"))?;
        let dir = tmp.path().join(name);
        for (name, bytes) in SHIPPED {
            crate::util::fsx::write_atomic(&dir.join(name), bytes)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        }
        let mut p = Self::load(dir, stochastic, seed)?;
        p.dir = PathBuf::from(SHIPPED_DIR);
        Ok(p)
    }

    /// Forgets the recurrent state: call at the start of each episode.
    fn reset(&self, py: Python<'_>) -> PyResult<()> {
        locked(py, &self.agent, "policy", "reset", |a| {
            a.reset();
            Ok(())
        })
    }

    /// The action for one observation (float32 bytes): float32 bytes of the continuous
    /// components (unclipped, as the environment takes them) and the lift entry (1.0 to
    /// lift, -1.0 not to).
    fn act<'py>(&self, py: Python<'py>, obs: &[u8]) -> PyResult<Bound<'py, PyBytes>> {
        if obs.len() != self.obs_dim * 4 {
            return Err(PyValueError::new_err(format!(
                "the observation holds {} float32 values, the policy reads {}",
                obs.len() / 4,
                self.obs_dim
            )));
        }
        let x: Vec<f32> = obs
            .chunks_exact(4)
            .map(|c| f32::from_ne_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if let Some(j) = x.iter().position(|v| !v.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "observation entry {j} is {} (observations must be finite)",
                x[j]
            )));
        }
        let a = locked(py, &self.agent, "policy", "the policy", |agent| {
            agent
                .try_act(&x)
                .map_err(|e| PyRuntimeError::new_err(format!("the policy failed: {e}")))
        })?;
        let mut out = a.cont;
        out.push(if a.lift { 1.0 } else { -1.0 });
        Ok(PyBytes::new(py, &f32_bytes(&out)))
    }
}
