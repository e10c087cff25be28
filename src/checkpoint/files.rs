//! The names of the files in a run folder and beside each checkpoint (`config.toml`,
//! `synergy.json`, ...), shared by training, evaluation, experiments and the Python module.

/// The resolved config.
pub const CONFIG: &str = "config.toml";
/// The metrics table.
pub const METRICS: &str = "metrics.csv";
/// The learning-curve plot.
pub const PLOT: &str = "learning_curve.svg";
/// The synergy model copied beside a checkpoint.
pub const SYNERGY: &str = "synergy.json";
/// Prefix of the TensorBoard event file (`events.out.tfevents.<t0>.grasp`).
pub const EVENTS_PREFIX: &str = "events.out.tfevents.";
/// Suffix of the TensorBoard event file.
pub const EVENTS_SUFFIX: &str = ".grasp";
/// The lock file: an exclusive OS lock on it is held while a process trains in the
/// folder.
pub const LOCK: &str = ".lock";

/// The files of checkpoint folder `dir` that a command reads (the weights, `config.toml`,
/// `synergy.json`): no output may replace them.
pub fn read_by_commands(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    [crate::ppo::CHECKPOINT_FILE, CONFIG, SYNERGY]
        .map(|f| dir.join(f))
        .to_vec()
}
