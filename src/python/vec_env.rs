//! The vector of grasping environments for `grasp_rl.GraspVectorEnv` (a
//! `gymnasium.vector.VectorEnv`): the config's `num_envs` environments, built as `grasp
//! train` builds them ([`crate::train::envs::build_envs`]), stepped in parallel by the rayon
//! [`VecEnv`] with the GIL released, resetting finished episodes on the same step.

use super::actions::{decode, f32_bytes};
use super::config::load_kwargs;
use super::error::{config_error, env_error, locked, no_panic};
use crate::env::api::VecEnv;
use crate::env::grasp::{EpisodeSummary, GraspEnv};
use crate::train::envs::{build_envs, CurriculumLevels, TrainEnvs};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::sync::Mutex;

/// The environments of a config stepped together.
#[pyclass(module = "grasp_rl._core", frozen)]
pub struct CoreVecEnv {
    venv: Mutex<VecEnv>,
    levels: CurriculumLevels,
    /// Environments.
    #[pyo3(get)]
    num_envs: usize,
    /// Length of one observation.
    #[pyo3(get)]
    obs_dim: usize,
    /// Continuous action components per environment.
    #[pyo3(get)]
    continuous: usize,
    /// Threads of the environment pool.
    #[pyo3(get)]
    threads: usize,
    /// The config's seed.
    #[pyo3(get)]
    seed: u64,
    /// The resolved training config (TOML).
    #[pyo3(get)]
    config_toml: String,
}

/// One step of all environments, as bytes for `numpy.frombuffer`.
type StepOut<'py> = (
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyList>,
);

/// Environment `i` of `venv` as a grasping environment (every environment of a
/// `CoreVecEnv` is one).
fn grasp_env(venv: &VecEnv, i: usize) -> Option<&GraspEnv> {
    venv.env(i)?.as_any()?.downcast_ref::<GraspEnv>()
}

/// The object of each environment's episode in progress.
fn objects_of(venv: &VecEnv) -> Vec<String> {
    (0..venv.num_envs())
        .map(|i| grasp_env(venv, i).map_or_else(String::new, |g| g.episode_object().to_string()))
        .collect()
}

impl CoreVecEnv {
    fn levels_bytes(&self) -> Vec<u8> {
        (0..self.num_envs)
            .flat_map(|i| self.levels.level(i).to_ne_bytes())
            .collect()
    }
}

#[pymethods]
impl CoreVecEnv {
    /// Builds the environments of `config` (a training config file; None: the built-in
    /// defaults, configs/base.toml) with the overrides given.
    /// Keywords: `config`, `objects`, `num_envs`, `threads`, `seed`, `difficulty`,
    /// `config_toml`.
    #[new]
    #[pyo3(signature = (**kwargs))]
    fn new(py: Python<'_>, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let keys = ["objects", "num_envs", "threads", "seed", "difficulty"];
        let (cfg, config_toml) = load_kwargs(kwargs, &keys)?;
        let threads = cfg.env_threads();
        let TrainEnvs { envs, levels, .. } = py
            .detach(|| no_panic("building the environments", || build_envs(&cfg)))?
            .map_err(config_error)?;
        let levels = levels.ok_or_else(|| {
            PyRuntimeError::new_err("the config's environment is not the grasping environment")
        })?;
        let venv = VecEnv::new(envs, threads, cfg.seed).map_err(env_error)?;
        Ok(CoreVecEnv {
            num_envs: venv.num_envs(),
            obs_dim: venv.obs_dim(),
            continuous: venv.action_spec().continuous,
            venv: Mutex::new(venv),
            levels,
            threads,
            seed: cfg.seed,
            config_toml,
        })
    }

    /// Restarts every environment with base seed `seed` (episode k of environment i gets
    /// `episode_seed(seed, i, k)`); returns the observations (num_envs x obs_dim float32
    /// bytes). With `restart_curriculum` the curriculum windows are emptied first.
    fn reset<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
        restart_curriculum: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        if restart_curriculum {
            self.levels.restart();
        }
        let obs = locked(py, &self.venv, "vector environment", "reset", |venv| {
            venv.reset(seed).map_err(env_error)
        })?;
        Ok(PyBytes::new(py, &f32_bytes(&obs)))
    }

    /// Steps every environment (actions: num_envs x (continuous + 1) float32 bytes, the
    /// last entry of a row lifts when > 0). Returns bytes of: observations (float32, the
    /// next episode's first for environments that ended), rewards (float32), terminated,
    /// truncated (uint8), success (int8: -1 none, 0, 1), physics failure (uint8),
    /// curriculum levels (float64), and a list of (index, final observation bytes,
    /// dict of episode_return, steps and summary) for the environments whose episode
    /// ended.
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: &[u8],
    ) -> PyResult<(StepOut<'py>, Bound<'py, PyBytes>)> {
        let actions = decode(actions, self.num_envs, self.continuous)?;
        let (s, records, summaries) =
            locked(py, &self.venv, "vector environment", "step", |venv| {
                let s = venv.step(&actions).map_err(env_error)?;
                // The summaries of the episodes that ended (each environment has already
                // started its next episode; its last summary is the ended one's).
                let summaries: Vec<Option<EpisodeSummary>> = s
                    .final_obs
                    .iter()
                    .enumerate()
                    .map(|(i, last)| {
                        last.as_ref()
                            .and_then(|_| grasp_env(venv, i)?.last_episode().cloned())
                    })
                    .collect();
                Ok((s, venv.drain_finished(), summaries))
            })?;
        let ended = PyList::empty(py);
        for (i, last) in s.final_obs.iter().enumerate() {
            if let Some(last) = last {
                let rec = records.iter().find(|r| r.env_index == i);
                let d = PyDict::new(py);
                if let Some(r) = rec {
                    d.set_item("episode_return", r.ret)?;
                    d.set_item("steps", r.length)?;
                }
                if let Some(summary) = &summaries[i] {
                    d.set_item("summary", super::env::summary_dict(py, summary)?)?;
                }
                ended.append((i, PyBytes::new(py, &f32_bytes(last)), d))?;
            }
        }
        let flags = |v: &[bool]| v.iter().map(|&b| u8::from(b)).collect::<Vec<u8>>();
        let success: Vec<u8> = s
            .infos
            .iter()
            .map(|i| match i.success {
                None => (-1i8) as u8,
                Some(b) => u8::from(b),
            })
            .collect();
        let failure: Vec<u8> = s
            .infos
            .iter()
            .map(|i| u8::from(i.physics_failure))
            .collect();
        Ok((
            (
                PyBytes::new(py, &f32_bytes(&s.obs)),
                PyBytes::new(py, &f32_bytes(&s.rewards)),
                PyBytes::new(py, &flags(&s.terminated)),
                PyBytes::new(py, &flags(&s.truncated)),
                PyBytes::new(py, &success),
                PyBytes::new(py, &failure),
                ended,
            ),
            PyBytes::new(py, &self.levels_bytes()),
        ))
    }

    /// The object of each environment's episode in progress (after a step: the next
    /// episode's for the environments whose episode ended).
    fn episode_objects(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        locked(
            py,
            &self.venv,
            "vector environment",
            "episode_objects",
            |venv| Ok(objects_of(venv)),
        )
    }

    /// The curriculum levels (float64 bytes, one per environment).
    fn curriculum_levels<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.levels_bytes())
    }
}
