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
//! checkpoint's setup ([`checkpoint_setup`]) is its grasping MDP, synergy components,
//! synergy model and simulator config; [`CheckpointSetup::sim_config`] reads the latter by
//! [`SimConfig::load_or_default`]'s one rule.

pub mod config;
pub mod files;

pub use config::{EnvKind, TrainConfig, TrainConfigError, TrainEnvConfig};

use crate::env::grasp::EnvConfig;
use crate::env::obs::Modality;
use crate::sim::config::SimConfigError;
use crate::sim::SimConfig;
use crate::synergy::SynergyModel;
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
    /// The synergy model saved beside the checkpoint (`synergy.json`), when present.
    pub synergy: Option<PathBuf>,
    /// The simulator config file the run was trained with (`None`: the built-in one).
    pub sim_config: Option<PathBuf>,
}

impl CheckpointSetup {
    /// The synergy model the policy acts in: the one beside the checkpoint, else the
    /// shipped model, with `n_components` components.
    pub fn synergy_model(&self) -> Result<SynergyModel, CheckpointError> {
        let model = match &self.synergy {
            Some(p) => SynergyModel::load(p).map_err(|e| CheckpointError {
                path: p.clone(),
                message: e.to_string(),
            })?,
            None => {
                tracing::warn!(
                    "a checkpoint without synergy.json: its policy acts in the shipped \
                     synergy model"
                );
                crate::synergy::default_model()
            }
        };
        model
            .truncated(self.n_components)
            .map_err(|e| CheckpointError {
                path: self.synergy.clone().unwrap_or_default(),
                message: e.to_string(),
            })
    }

    /// The simulator config the run was trained with, by
    /// [`SimConfig::load_or_default`]'s rule.
    pub fn sim_config(&self) -> Result<SimConfig, SimConfigError> {
        SimConfig::load_or_default(self.sim_config.as_deref())
    }

    /// Checks the user's `--modality` / `--components` against the checkpoint: a value
    /// that differs is an error naming both.
    pub fn check_flags(
        &self,
        dir: &Path,
        modality: Option<Modality>,
        components: Option<usize>,
    ) -> Result<(), CheckpointError> {
        if let Some(m) = modality.filter(|m| *m != self.env.modality) {
            return Err(CheckpointError {
                path: dir.join(files::CONFIG),
                message: format!(
                    "the checkpoint was trained with modality {:?}, not {m:?}: drop --modality",
                    self.env.modality
                ),
            });
        }
        if let Some(n) = components.filter(|n| *n != self.n_components) {
            return Err(CheckpointError {
                path: dir.join(files::CONFIG),
                message: format!(
                    "the checkpoint was trained with {} synergy components, not {n}: drop \
                     --components",
                    self.n_components
                ),
            });
        }
        Ok(())
    }
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
    let synergy = dir.join(files::SYNERGY);
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
        synergy: synergy.is_file().then_some(synergy),
        sim_config: cfg.sim_config,
    }))
}
