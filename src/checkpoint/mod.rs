//! The checkpoint folder: what `grasp train` writes beside every checkpoint and what
//! evaluation, `grasp run`, experiments and the Python module read back.
//!
//! ```text
//! <run>/checkpoints/latest/          (also best/ and step_<transitions>/)
//!     checkpoint.safetensors         the policy's weights (crate::ppo)
//!     config.toml                    the resolved training config ([`TrainConfig`])
//!     synergy.json                   the synergy model the policy acts in
//! ```
//!
//! The file names live in [`files`], the training config's schema in [`config`]. A
//! checkpoint's setup ([`checkpoint_setup`]) is its grasping MDP, synergy components and
//! simulator config file. [`TrainedAgent`] is the one loader of a
//! trained agent: weights, setup and synergy model, checked to fit.

pub mod agent;
pub mod config;
pub mod files;

pub use agent::{Assumed, TrainedAgent};
pub use config::{EnvKind, TrainConfig, TrainConfigError, TrainEnvConfig};

use crate::env::grasp::EnvConfig;
use std::path::{Path, PathBuf};

/// The latest checkpoint folder of run folder `dir`.
pub fn latest_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoints").join("latest")
}

/// The best checkpoint folder of run folder `dir`.
pub fn best_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoints").join("best")
}

/// The milestone checkpoint folder of run folder `dir` after `transitions`
/// (`milestone_every`).
pub fn milestone_dir(dir: &Path, transitions: u64) -> PathBuf {
    dir.join("checkpoints").join(format!("step_{transitions}"))
}

/// A checkpoint folder's file that is unreadable or does not fit the request.
#[derive(Debug, thiserror::Error)]
#[error("checkpoint {path}: {message}")]
pub struct CheckpointError {
    /// The file (config.toml or synergy.json).
    pub path: PathBuf,
    /// What is wrong.
    pub message: String,
}

/// The training config saved beside the checkpoint in `dir` (its `config.toml`), as
/// written; `Ok(None)` when the folder has none (a checkpoint not written by
/// `grasp train`).
pub fn saved_config(dir: &Path) -> Result<Option<TrainConfig>, CheckpointError> {
    let path = dir.join(files::CONFIG);
    if !path.is_file() {
        return Ok(None);
    }
    let text = crate::util::fsx::read_to_string_bounded(&path, crate::util::fsx::limits::CONFIG)
        .map_err(|e| CheckpointError {
            path: path.clone(),
            message: e.to_string(),
        })?;
    TrainConfig::parse(&path, &text)
        .map(Some)
        .map_err(|e| CheckpointError {
            path,
            message: e.to_string(),
        })
}

/// What a checkpoint was trained with, read from the `config.toml` that `grasp train`
/// saves beside every checkpoint.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckpointSetup {
    /// The grasping MDP's settings (modality, history, action scales, closing, ...), with
    /// domain randomisation turned off.
    pub env: EnvConfig,
    /// Synergy components the policy acts in.
    pub n_components: usize,
    /// The simulator config file the run was trained with (`None`: the built-in one).
    pub sim_config: Option<PathBuf>,
}

/// Reads the training config beside the checkpoint in `dir`. `Ok(None)` when the folder
/// has no `config.toml` (a checkpoint not written by `grasp train`); an error when the
/// file is malformed or describes another environment than the grasping MDP.
pub fn checkpoint_setup(dir: &Path) -> Result<Option<CheckpointSetup>, CheckpointError> {
    let path = dir.join(files::CONFIG);
    let Some(cfg) = saved_config(dir)? else {
        return Ok(None);
    };
    if cfg.env.kind != EnvKind::Grasp {
        return Err(CheckpointError {
            path,
            message: format!(
                "the checkpoint was trained on {:?}, not the grasping environment",
                cfg.env.kind
            ),
        });
    }
    let mut env = cfg.env.grasp;
    // Every agent is judged on the same, unrandomised objects and sensors, each object
    // in turn.
    env.randomization.enabled = false;
    env.object_curriculum.enabled = false;
    // Placement is the evaluation's choice (`--pregrasp`), the same for every agent.
    env.placement = Default::default();
    Ok(Some(CheckpointSetup {
        env,
        n_components: cfg.n_components,
        sim_config: cfg.sim_config,
    }))
}
