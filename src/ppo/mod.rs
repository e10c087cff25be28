//! Proximal policy optimisation for any [`crate::env::api::Env`]: configuration, rollout
//! buffer, GAE, normalisers, Adam, the [`Trainer`] and checkpoints.
//!
//! ```no_run
//! use grasp::env::api::Env;
//! use grasp::env::cartpole::CartPole;
//! use grasp::ppo::{PpoConfig, Trainer};
//!
//! let cfg = PpoConfig { num_envs: 4, ..PpoConfig::default() };
//! let envs: Vec<Box<dyn Env>> = (0..4).map(|_| Box::new(CartPole::default()) as Box<dyn Env>).collect();
//! let mut trainer = Trainer::new(cfg, envs)?;
//! let m = trainer.train_update()?;
//! println!("update {} mean return {:?}", m.update, m.stats.episode_return);
//! trainer.save_checkpoint(std::path::Path::new("runs/demo"))?;
//! # Ok::<(), grasp::ppo::PpoError>(())
//! ```

pub mod buffer;
pub mod checkpoint;
pub mod config;
pub mod gae;
pub mod normalize;
pub mod optim;
pub mod trainer;

pub use checkpoint::{load_policy, read_checkpoint_config, LoadedPolicy, CHECKPOINT_FILE};
pub use config::PpoConfig;
pub use trainer::{Trainer, UpdateMetrics, UpdateStats};

use std::path::PathBuf;

/// Errors of the learner.
#[derive(Debug, thiserror::Error)]
pub enum PpoError {
    /// A hyperparameter is out of range.
    #[error("invalid PPO setting `{field}`: {message}")]
    Config {
        /// The offending field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The config file could not be loaded.
    #[error(transparent)]
    ConfigFile(#[from] crate::util::config::ConfigError),
    /// The policy could not be built or run.
    #[error(transparent)]
    Policy(#[from] crate::policy::PolicyError),
    /// An environment misbehaved.
    #[error(transparent)]
    Env(#[from] crate::env::api::EnvError),
    /// A tensor operation failed.
    #[error("tensor operation failed: {0}")]
    Candle(#[from] candle_core::Error),
    /// Training produced non-finite numbers.
    #[error("non-finite {what}")]
    NonFinite {
        /// What became non-finite.
        what: String,
    },
    /// A checkpoint could not be written.
    #[error(transparent)]
    Write(#[from] crate::util::fsx::WriteError),
    /// A checkpoint file could not be read.
    #[error("cannot read checkpoint {path}: {source}")]
    CheckpointIo {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A checkpoint file is corrupt or not a PPO checkpoint.
    #[error("invalid checkpoint {path}: {message}")]
    CheckpointFormat {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A tensor in a checkpoint has the wrong shape.
    #[error("checkpoint {path}: tensor `{name}` has shape {found:?}, expected {expected:?}")]
    CheckpointShape {
        /// The file.
        path: PathBuf,
        /// The tensor.
        name: String,
        /// The shape the model needs.
        expected: Vec<usize>,
        /// The shape in the file.
        found: Vec<usize>,
    },
    /// A checkpoint does not fit this trainer (other network or environment).
    #[error("checkpoint {path} does not fit: {message}")]
    CheckpointMismatch {
        /// The file.
        path: PathBuf,
        /// What differs.
        message: String,
    },
}
