//! Training runs: the `grasp train` pipeline as a library.
//!
//! A run is described by a [`TrainConfig`] (TOML, with `base = "..."` inheritance), lives in
//! a run folder (`runs/<name>` by default) and writes, after every PPO update:
//!
//! - `config.toml`: the resolved configuration (written once per start);
//! - `metrics.csv`: one [`MetricsRow`] per update ([`metrics`]);
//! - `events.out.tfevents.<t0>.grasp`: the same scalars for TensorBoard ([`tfevents`]);
//! - `checkpoints/latest` and `checkpoints/best`: PPO checkpoints with the synergy model and
//!   the config beside them;
//! - `learning_curve.svg`: success rate and return against transitions ([`plot`]).
//!
//! [`envs`] builds a config's environments (the Python module builds its own there too);
//! [`files`](crate::checkpoint::files) names the files of a run folder and of a checkpoint folder.
//!
//! Every file is replaced atomically, so a run killed at any moment (even `kill -9`) can be
//! continued with [`TrainSession::open`]`(.., resume = true)`: the metrics rows after the
//! latest checkpoint's update are dropped and training continues from that checkpoint.
//!
//! ```no_run
//! use grasp::train::{TrainConfig, TrainSession};
//! use std::path::Path;
//!
//! let cfg = TrainConfig::load(Path::new("configs/cartpole.toml"))?;
//! let mut session = TrainSession::open(cfg, Path::new("runs/cartpole"), false)?;
//! let summary = session.run(&mut |p| println!("update {}", p.row.update))?;
//! println!("{} transitions", summary.global_step);
//! # Ok::<(), grasp::train::TrainError>(())
//! ```

pub mod envs;
pub mod metrics;
pub mod objects;
pub mod plot;
pub mod session;
pub mod tfevents;

pub use crate::checkpoint::{EnvKind, TrainConfig, TrainConfigError, TrainEnvConfig};
pub use metrics::MetricsRow;
pub use session::{OpenOptions, Progress, StopReason, TrainSession, TrainSummary};

use std::path::PathBuf;

/// Errors of a training run.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// A config file could not be read or does not match the schema.
    #[error(transparent)]
    ConfigFile(#[from] crate::util::config::ConfigError),
    /// A training config that cannot be used.
    #[error(transparent)]
    Config(#[from] TrainConfigError),
    /// A config value is out of range or inconsistent.
    #[error("invalid config {path}: `{field}`: {message}")]
    ConfigValue {
        /// The config file (or the run's resolved config).
        path: PathBuf,
        /// The field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The training objects cannot be built (a folder's broken mesh, an object the
    /// simulator refuses).
    #[error("cannot train on objects `{objects}`: {message}")]
    Objects {
        /// The object set as given (`objects`, `--objects`).
        objects: String,
        /// What is wrong, naming the object.
        message: String,
    },
    /// The synergy model file does not exist.
    #[error(
        "synergy model {path} does not exist: set `synergy` in the config to a model JSON \
         (fit one with `grasp pca fit poses.csv --out {path}`)"
    )]
    SynergyMissing {
        /// The missing file.
        path: PathBuf,
    },
    /// The synergy model could not be loaded.
    #[error(transparent)]
    Synergy(#[from] crate::synergy::SynergyError),
    /// The synergy model has fewer components than the config asks for.
    #[error(
        "synergy model {path} has {found} components but the config asks for \
         n_components = {wanted}: fit a model with at least {wanted} components"
    )]
    SynergyComponents {
        /// The model file.
        path: PathBuf,
        /// Components in the model.
        found: usize,
        /// Components requested.
        wanted: usize,
    },
    /// The simulator config is invalid.
    #[error(transparent)]
    SimConfig(#[from] crate::sim::config::SimConfigError),
    /// The grasping environment could not be built.
    #[error(transparent)]
    Env(#[from] crate::env::grasp::GraspEnvError),
    /// The learner failed.
    #[error(transparent)]
    Ppo(#[from] crate::ppo::PpoError),
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] crate::util::fsx::WriteError),
    /// A folder or file could not be created.
    #[error("cannot create {path}: {source}")]
    Create {
        /// The folder or file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A stale file could not be removed.
    #[error("cannot remove {path}: {source}")]
    Remove {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file or folder could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A metrics file of the run is malformed.
    #[error("invalid metrics file {path}, line {line}: {message}")]
    Metrics {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A new run would overwrite an existing one.
    #[error(
        "run folder {dir} already holds a run: pass --resume to continue it or --out for a \
         new folder"
    )]
    RunExists {
        /// The run folder.
        dir: PathBuf,
    },
    /// The folder is no run folder (a checkpoint folder, a folder of other files).
    #[error("--out {dir} {why}: train into a new folder (or a run folder to --resume)")]
    NotARunFolder {
        /// The folder.
        dir: PathBuf,
        /// What it is instead.
        why: String,
    },
    /// Another process holds the run folder's lock.
    #[error(
        "run folder {dir} is in use by another process (it holds {dir}/.lock): wait for \
         it to end, or train into another --out folder"
    )]
    RunInUse {
        /// The run folder.
        dir: PathBuf,
    },
    /// The run recorded metrics or a best checkpoint but has no latest checkpoint.
    #[error("run folder {dir} has no {latest} but holds {detail}")]
    LatestMissing {
        /// The run folder.
        dir: PathBuf,
        /// The missing latest checkpoint folder.
        latest: PathBuf,
        /// What the folder holds, and what the user can do.
        detail: String,
    },
    /// `--resume` with an `[env]` table that differs from the checkpoint's.
    #[error(
        "cannot resume from {checkpoint}: the environment differs from the one it was \
         trained under in {keys}; restore those settings, or pass --allow-env-change to \
         continue under the new ones"
    )]
    EnvChanged {
        /// The checkpoint folder.
        checkpoint: PathBuf,
        /// The differing keys, comma-separated.
        keys: String,
    },
    /// `--resume` without the metrics file while a best checkpoint exists: the best
    /// score so far is unknown, so the best checkpoint would be overwritten by a worse one.
    #[error(
        "cannot resume: {metrics} is missing, so the best score so far is unknown and {best} \
         would be overwritten by a worse checkpoint; restore {metrics}, or move {best} away \
         to resume without it"
    )]
    MetricsMissing {
        /// The metrics file looked for.
        metrics: PathBuf,
        /// The best checkpoint folder.
        best: PathBuf,
    },
    /// The learning-curve plot could not be drawn.
    #[error("cannot draw {path}: {message}")]
    Plot {
        /// The SVG file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}
