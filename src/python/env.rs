//! One grasping environment for `grasp_rl.GraspEnv` (a `gymnasium.Env`), built by the
//! same code as `grasp train`'s environments ([`crate::train::envs::grasp_envs`]), and the
//! scripted baselines on its scenes.

use super::actions::{decode, f32_bytes};
use super::config::load_kwargs;
use super::error::{config_error, locked, no_panic};
use crate::env::api::Env;
use crate::env::grasp::{EpisodeSummary, GraspEnv};
use crate::train::envs::grasp_envs;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::sync::Mutex;

/// Where the episode stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// No reset yet.
    New,
    /// An episode is running.
    Running,
    /// The episode ended (terminated or truncated): `reset` must come first.
    Ended,
}

struct State {
    env: GraspEnv,
    phase: Phase,
}

/// One grasping environment. Observations, actions: see `grasp_rl.GraspEnv`.
#[pyclass(module = "grasp_rl._core", frozen)]
pub struct CoreEnv {
    state: Mutex<State>,
    /// Length of the observation vector.
    #[pyo3(get)]
    obs_dim: usize,
    /// Continuous action components (synergy increments, then the two wrist increments).
    #[pyo3(get)]
    continuous: usize,
    /// The resolved training config (TOML).
    #[pyo3(get)]
    config_toml: String,
    /// Names of the objects the environment draws from (one stream object on
    /// `procedural`, replaced as the stream goes on).
    #[pyo3(get)]
    object_names: Vec<String>,
}

/// An episode summary as a dict (object, success, steps, episode_return, lifted,
/// physics_failure, touched_in_stage1, thumb_contact_at_lift, grip_effort, object_height,
/// in_hand, object_turn).
pub fn summary_dict<'py>(py: Python<'py>, s: &EpisodeSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("object", &s.object)?;
    d.set_item("success", s.success)?;
    d.set_item("steps", s.steps)?;
    d.set_item("episode_return", s.episode_return)?;
    d.set_item("lifted", s.lifted)?;
    d.set_item("physics_failure", s.physics_failure)?;
    d.set_item("touched_in_stage1", s.touched_in_stage1)?;
    d.set_item("thumb_contact_at_lift", s.thumb_contact_at_lift)?;
    d.set_item("grip_effort", s.grip_effort)?;
    d.set_item("object_height", s.object_height)?;
    d.set_item("in_hand", s.in_hand)?;
    d.set_item("object_turn", s.object_turn)?;
    Ok(d)
}

#[pymethods]
impl CoreEnv {
    /// Builds the environment of `config` (a training config file; None: the built-in
    /// defaults, configs/base.toml) with the overrides given.
    /// Keywords: `config`, `objects`, `difficulty`, `config_toml`.
    #[new]
    #[pyo3(signature = (**kwargs))]
    fn new(py: Python<'_>, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let (cfg, config_toml) = load_kwargs(kwargs, &["objects", "difficulty"])?;
        let (mut envs, _) = py
            .detach(|| no_panic("building the environment", || grasp_envs(&cfg, 1)))?
            .map_err(config_error)?;
        let env = envs
            .pop()
            .ok_or_else(|| PyRuntimeError::new_err("no environment was built"))?;
        Ok(CoreEnv {
            obs_dim: env.obs_dim(),
            continuous: env.action_spec().continuous,
            object_names: env.objects().iter().map(|o| o.0.clone()).collect(),
            config_toml,
            state: Mutex::new(State {
                env,
                phase: Phase::New,
            }),
        })
    }

    /// Starts the episode of `seed` (object, start pose, stage 1) and returns its first
    /// observation as float32 bytes. With `restart_curriculum` the curriculum window is
    /// emptied first, as in a new environment.
    fn reset<'py>(
        &self,
        py: Python<'py>,
        seed: u64,
        restart_curriculum: bool,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let obs = locked(py, &self.state, "environment", "reset", |st| {
            if restart_curriculum {
                st.env.restart_curriculum();
            }
            let obs = st.env.reset(seed);
            st.phase = Phase::Running;
            Ok(obs)
        })?;
        Ok(PyBytes::new(py, &f32_bytes(&obs)))
    }

    /// Applies one action (float32 bytes: the continuous components, then the lift entry,
    /// which lifts when > 0). Returns (obs bytes, reward, terminated, truncated, success
    /// or None, physics_failure, summary dict when the episode ended or None).
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &self,
        py: Python<'py>,
        action: &[u8],
    ) -> PyResult<(
        Bound<'py, PyBytes>,
        f32,
        bool,
        bool,
        Option<bool>,
        bool,
        Option<Bound<'py, PyDict>>,
    )> {
        let mut a = decode(action, 1, self.continuous)?;
        let a = a
            .pop()
            .ok_or_else(|| PyValueError::new_err("empty action"))?;
        let (s, summary) = locked(py, &self.state, "environment", "step", |st| {
            match st.phase {
                Phase::New => {
                    return Err(PyRuntimeError::new_err(
                        "step() before reset(): call reset() to start an episode",
                    ))
                }
                Phase::Ended => {
                    return Err(PyRuntimeError::new_err(
                        "step() after the episode ended (terminated or truncated): call \
                         reset() to start the next one",
                    ))
                }
                Phase::Running => {}
            }
            let s = st.env.step(&a);
            let summary = if s.terminated || s.truncated {
                st.phase = Phase::Ended;
                st.env.last_episode().cloned()
            } else {
                None
            };
            Ok((s, summary))
        })?;
        let summary = match summary {
            Some(e) => Some(summary_dict(py, &e)?),
            None => None,
        };
        Ok((
            PyBytes::new(py, &f32_bytes(&s.obs)),
            s.reward,
            s.terminated,
            s.truncated,
            s.info.success,
            s.info.physics_failure,
            summary,
        ))
    }

    /// The curriculum level `r_s` (eq. 6) that sets the next start poses.
    #[getter]
    fn curriculum_level(&self, py: Python<'_>) -> PyResult<f64> {
        locked(py, &self.state, "environment", "curriculum_level", |st| {
            Ok(st.env.curriculum_rate())
        })
    }

    /// The current (or last) episode's object.
    #[getter]
    fn episode_object(&self, py: Python<'_>) -> PyResult<String> {
        locked(py, &self.state, "environment", "episode_object", |st| {
            Ok(st.env.episode_object().to_string())
        })
    }

    /// Runs scripted baseline `which` (1: close all fingers; 2: FF, MF, RF stop at
    /// contact) on the scene of `seed` (the scene `reset(seed)` gives the policy) and
    /// returns its episode summary. The current episode, if any, is abandoned.
    fn run_baseline<'py>(
        &self,
        py: Python<'py>,
        which: u8,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let stop_on_touch = match which {
            1 => false,
            2 => true,
            other => {
                return Err(PyValueError::new_err(format!(
                    "unknown baseline {other}: expected 1 or 2"
                )))
            }
        };
        let s = locked(py, &self.state, "environment", "baseline", |st| {
            st.phase = Phase::Ended;
            st.env
                .run_baseline(stop_on_touch, seed)
                .map_err(|e| PyRuntimeError::new_err(format!("baseline {which}: {e}")))
        })?;
        summary_dict(py, &s)
    }
}
