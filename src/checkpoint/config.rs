//! The training configuration: a TOML file with optional inheritance.
//!
//! A config file may name a parent with a top-level `base = "base.toml"` key, resolved
//! relative to the file. The parent is loaded first (recursively) and the child's tables
//! are merged into it key by key (tables merge, other values replace), so a variant file
//! only names what it changes:
//!
//! ```toml
//! base = "base.toml"
//! name = "mlp_m3_pca5"
//! [policy]
//! kind = "mlp"
//! ```
//!
//! Every file of the chain is checked against the schema on its own, so an unknown or
//! mistyped key is reported with the file, line and column where it was written.
//!
//! Top-level keys: `name`, `seed`, `total_timesteps`, `num_envs`, `threads` (environment
//! pool; default: the available cores), `checkpoint_every` (updates), `milestone_every`
//! (updates between kept copies `checkpoints/step_<transitions>`; 0, the default: none), `plot_every`
//! (updates), `best_window` (updates averaged to pick the best checkpoint),
//! `time_budget_minutes`, `objects`, `synergy` (path of a model JSON), `n_components`,
//! `sim_config` (path of a simulator TOML; built-in defaults when absent). Tables: `[ppo]`
//! ([`PpoConfig`] without `seed`, `num_envs`, `total_timesteps`, `env_threads`, `policy`,
//! which live at the top level or in `[policy]`), `[policy]` ([`PolicyConfig`]) and `[env]`
//! (`kind = "grasp" | "cartpole"`, `cartpole_max_steps`, and the fields of
//! [`EnvConfig`]). Relative paths in `synergy` and `sim_config` are taken from the current
//! directory, like paths given on the command line.

use crate::env::action::ActionConfig;
use crate::env::closing::ClosingSpace;
use crate::env::curriculum::CurriculumConfig;
use crate::env::grasp::{AtMaxSteps, EnvConfig};
use crate::env::object_curriculum::ObjectCurriculumConfig;
use crate::env::obs::Modality;
use crate::env::placement::PlacementConfig;
use crate::env::randomize::Randomization;
use crate::env::reward::RewardConfig;
use crate::env::stream::StreamConfig;
use crate::policy::PolicyConfig;
use crate::ppo::PpoConfig;
use crate::util::config::{parse_toml, ConfigError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A training config that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum TrainConfigError {
    /// A config file could not be read or does not match the schema.
    #[error(transparent)]
    File(#[from] ConfigError),
    /// A config value is out of range or inconsistent.
    #[error("invalid config {path}: `{field}`: {message}")]
    Value {
        /// The config file (or the run's resolved config).
        path: PathBuf,
        /// The field.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// Keys of [`PpoConfig`] that are set at the top level (or in `[policy]`) instead.
pub const PPO_KEYS_ELSEWHERE: [&str; 5] = [
    "seed",
    "num_envs",
    "total_timesteps",
    "env_threads",
    "policy",
];

/// Deepest chain of `base` files followed.
pub const MAX_BASE_DEPTH: usize = 8;

/// Which environment a run trains on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EnvKind {
    /// The grasping simulator ([`crate::env::grasp::GraspEnv`]).
    Grasp,
    /// The textbook continuous cart-pole ([`crate::env::cartpole::CartPole`]): a quick check
    /// that the learner works.
    Cartpole,
}

/// The `[env]` table resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainEnvConfig {
    /// The environment.
    pub kind: EnvKind,
    /// Settings of the grasping MDP (used when `kind = "grasp"`).
    pub grasp: EnvConfig,
    /// Truncation length of a cart-pole episode (500, as `CartPole-v1`).
    pub cartpole_max_steps: u32,
}

/// A resolved training configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainConfig {
    /// Name of the run; the default run folder is `runs/<name>`.
    pub name: String,
    /// Master seed.
    pub seed: u64,
    /// Environment transitions planned.
    pub total_timesteps: u64,
    /// Environments stepped in parallel.
    pub num_envs: usize,
    /// Threads of the environment pool (`None`: the available cores).
    pub threads: Option<usize>,
    /// Save `checkpoints/latest` every this many updates (and at the end).
    pub checkpoint_every: u64,
    /// Keep a copy of the checkpoint every this many updates as
    /// `checkpoints/step_<transitions>` (0: none), for choosing among a run's checkpoints
    /// on a validation set afterwards.
    pub milestone_every: u64,
    /// Redraw `learning_curve.svg` every this many updates (and at the end).
    pub plot_every: u64,
    /// Updates averaged when choosing `checkpoints/best`.
    pub best_window: usize,
    /// Stop cleanly (with a checkpoint) after this much wall time, if set.
    pub time_budget_minutes: Option<f64>,
    /// The object set: `"primitives"` ([`crate::train::objects::primitives`]), `"procedural"`
    /// (the procedural object stream: a fresh object every `env.stream.reuse` episodes,
    /// see [`crate::env::stream`]) or anything `--objects` accepts (`train`, `unseen`, a
    /// folder, a manifest, names).
    pub objects: String,
    /// The synergy model JSON (grasp runs).
    pub synergy: PathBuf,
    /// Synergy components the policy acts in; must match the model.
    pub n_components: usize,
    /// Simulator config file (`None`: the built-in defaults).
    pub sim_config: Option<PathBuf>,
    /// PPO hyperparameters; its `seed`, `num_envs`, `total_timesteps`, `env_threads` and
    /// `policy` are overwritten from the fields above by [`TrainConfig::ppo_config`].
    pub ppo: PpoConfig,
    /// The network.
    pub policy: PolicyConfig,
    /// The environment.
    pub env: TrainEnvConfig,
}

/// The `[env]` table of one file: every key optional.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvSection {
    kind: Option<EnvKind>,
    cartpole_max_steps: Option<u32>,
    modality: Option<Modality>,
    history: Option<usize>,
    max_steps: Option<usize>,
    start_posture: Option<String>,
    grasp_depth: Option<f64>,
    closing_time: Option<f64>,
    closing_period: Option<f64>,
    closing: Option<ClosingSpace>,
    at_max_steps: Option<AtMaxSteps>,
    action: Option<ActionConfig>,
    curriculum: Option<CurriculumConfig>,
    object_curriculum: Option<ObjectCurriculumConfig>,
    randomization: Option<Randomization>,
    stream: Option<StreamConfig>,
    reward: Option<RewardConfig>,
    critic_state: Option<bool>,
    placement: Option<PlacementConfig>,
}

/// One file (or the merged chain): every key optional.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSchema {
    base: Option<String>,
    name: Option<String>,
    seed: Option<u64>,
    total_timesteps: Option<u64>,
    num_envs: Option<usize>,
    threads: Option<usize>,
    checkpoint_every: Option<u64>,
    milestone_every: Option<u64>,
    plot_every: Option<u64>,
    best_window: Option<usize>,
    time_budget_minutes: Option<f64>,
    objects: Option<String>,
    synergy: Option<PathBuf>,
    n_components: Option<usize>,
    sim_config: Option<PathBuf>,
    ppo: Option<PpoConfig>,
    policy: Option<PolicyConfig>,
    env: Option<EnvSection>,
}

/// Merges `over` into `base`: tables merge recursively, any other value replaces.
pub fn merge_tables(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge_tables(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// 1-based line of the first `key = ...` inside `[section]` in `src` (1 when not found).
fn key_line(src: &str, section: &str, key: &str) -> usize {
    let mut inside = false;
    for (i, line) in src.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            inside = t.trim_start_matches('[').trim_end_matches(']').trim() == section;
            continue;
        }
        if inside {
            if let Some(rest) = t.strip_prefix(key) {
                if rest.trim_start().starts_with('=') {
                    return i + 1;
                }
            }
        }
    }
    1
}

/// Parses one file's text: syntax and schema are checked with positions, then the raw
/// table is returned with the `base` it names.
fn parse_file(path: &Path, src: &str) -> Result<(toml::Table, Option<String>), TrainConfigError> {
    let schema: FileSchema = parse_toml(path, src)?;
    let table: toml::Table = parse_toml(path, src)?;
    if let Some(toml::Value::Table(ppo)) = table.get("ppo") {
        for key in PPO_KEYS_ELSEWHERE {
            if ppo.contains_key(key) {
                let line = key_line(src, "ppo", key);
                let home = if key == "policy" {
                    "in the [policy] table".to_string()
                } else if key == "env_threads" {
                    "at the top level as `threads`".to_string()
                } else {
                    format!("at the top level as `{key}`")
                };
                return Err(ConfigError::Parse {
                    path: path.to_path_buf(),
                    line,
                    column: 1,
                    message: format!("`ppo.{key}` is not allowed here: set it {home}"),
                }
                .into());
            }
        }
    }
    Ok((table, schema.base))
}

/// Loads `path` and its chain of `base` files, merged (parents first).
fn load_chain(
    path: &Path,
    depth: usize,
    seen: &mut Vec<PathBuf>,
) -> Result<toml::Table, TrainConfigError> {
    let src = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::CONFIG)
        .map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    if seen.contains(&canon) {
        return Err(TrainConfigError::Value {
            path: path.to_path_buf(),
            field: "base".into(),
            message: "the chain of base files loops back to this file".into(),
        });
    }
    seen.push(canon);
    let (mut table, base) = parse_file(path, &src)?;
    table.remove("base");
    let Some(base) = base else {
        return Ok(table);
    };
    if depth >= MAX_BASE_DEPTH {
        return Err(TrainConfigError::Value {
            path: path.to_path_buf(),
            field: "base".into(),
            message: format!("more than {MAX_BASE_DEPTH} nested base files"),
        });
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let base_path = dir.join(&base);
    // Name the file that refers to the missing one, not only the missing one.
    let refer = |message: String| TrainConfigError::Value {
        path: path.to_path_buf(),
        field: "base".into(),
        message,
    };
    if base.trim().is_empty() {
        return Err(refer(
            "is empty: name the config file to inherit from".into(),
        ));
    }
    match std::fs::metadata(&base_path) {
        Err(e) => return Err(refer(format!("cannot read {}: {e}", base_path.display()))),
        Ok(m) if m.is_dir() => {
            return Err(refer(format!(
                "{} is a folder, not a config file",
                base_path.display()
            )))
        }
        Ok(_) => {}
    }
    let mut merged = load_chain(&base_path, depth + 1, seen)?;
    merge_tables(&mut merged, table);
    Ok(merged)
}

impl TrainConfig {
    /// Loads the config file at `path` with its `base` chain, merges, fills defaults and
    /// validates. Errors name the file, and the line and key where the schema is broken.
    pub fn load(path: &Path) -> Result<TrainConfig, TrainConfigError> {
        let merged = load_chain(path, 0, &mut Vec::new())?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into());
        Self::from_table(path, merged, &stem)
    }

    /// Parses config text without inheritance (`base` is an error here); `path` names it
    /// in errors and its stem is the default name.
    pub fn parse(path: &Path, src: &str) -> Result<TrainConfig, TrainConfigError> {
        let (table, base) = parse_file(path, src)?;
        if base.is_some() {
            return Err(TrainConfigError::Value {
                path: path.to_path_buf(),
                field: "base".into(),
                message: "is not followed here: this config is read on its own (a \
                          checkpoint's config.toml is saved complete, without `base`)"
                    .into(),
            });
        }
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into());
        Self::from_table(path, table, &stem)
    }

    fn from_table(
        path: &Path,
        table: toml::Table,
        stem: &str,
    ) -> Result<TrainConfig, TrainConfigError> {
        let text = toml::to_string(&table).map_err(|e| TrainConfigError::Value {
            path: path.to_path_buf(),
            field: "(file)".into(),
            message: e.to_string(),
        })?;
        let f: FileSchema = parse_toml(path, &text)?;
        let e = f.env.unwrap_or_default();
        let d = EnvConfig::default();
        let grasp = EnvConfig {
            modality: e.modality.unwrap_or(d.modality),
            history: e.history.unwrap_or(d.history),
            max_steps: e.max_steps.unwrap_or(d.max_steps),
            start_posture: e.start_posture.unwrap_or(d.start_posture),
            grasp_depth: e.grasp_depth.unwrap_or(d.grasp_depth),
            closing_time: e.closing_time.unwrap_or(d.closing_time),
            closing_period: e.closing_period.unwrap_or(d.closing_period),
            closing: e.closing.unwrap_or(d.closing),
            at_max_steps: e.at_max_steps.unwrap_or(d.at_max_steps),
            action: e.action.unwrap_or(d.action),
            curriculum: e.curriculum.unwrap_or(d.curriculum),
            object_curriculum: e.object_curriculum.unwrap_or(d.object_curriculum),
            randomization: e.randomization.unwrap_or(d.randomization),
            stream: e.stream.unwrap_or(d.stream),
            reward: e.reward.unwrap_or(d.reward),
            critic_state: e.critic_state.unwrap_or(d.critic_state),
            placement: e.placement.unwrap_or(d.placement),
        };
        let ppo_defaults = PpoConfig::default();
        let cfg = TrainConfig {
            name: f.name.unwrap_or_else(|| stem.to_string()),
            seed: f.seed.unwrap_or(ppo_defaults.seed),
            total_timesteps: f.total_timesteps.unwrap_or(ppo_defaults.total_timesteps),
            num_envs: f.num_envs.unwrap_or(ppo_defaults.num_envs),
            threads: f.threads,
            checkpoint_every: f.checkpoint_every.unwrap_or(1),
            milestone_every: f.milestone_every.unwrap_or(0),
            plot_every: f.plot_every.unwrap_or(5),
            best_window: f.best_window.unwrap_or(10),
            time_budget_minutes: f.time_budget_minutes,
            objects: f.objects.unwrap_or_else(|| "train".into()),
            synergy: f
                .synergy
                .unwrap_or_else(|| PathBuf::from("assets/synergy/model.json")),
            n_components: f.n_components.unwrap_or(5),
            sim_config: f.sim_config,
            ppo: f.ppo.unwrap_or_default(),
            policy: f.policy.unwrap_or_default(),
            env: TrainEnvConfig {
                kind: e.kind.unwrap_or(EnvKind::Grasp),
                grasp,
                cartpole_max_steps: e.cartpole_max_steps.unwrap_or(500),
            },
        };
        cfg.validate(path)?;
        Ok(cfg)
    }

    /// The environment pool size: `threads`, or the available cores.
    pub fn env_threads(&self) -> usize {
        self.threads.unwrap_or_else(crate::util::threads::available)
    }

    /// The learner's config: `[ppo]` with the top-level `seed`, `num_envs`,
    /// `total_timesteps`, the thread count and `[policy]` filled in.
    pub fn ppo_config(&self) -> PpoConfig {
        PpoConfig {
            seed: self.seed,
            num_envs: self.num_envs,
            total_timesteps: self.total_timesteps,
            env_threads: self.env_threads(),
            policy: PolicyConfig {
                critic_state: match self.env.kind {
                    EnvKind::Grasp => {
                        crate::env::obs::ObsLayout::new(Modality::M1, 1, 1)
                            .with_critic_state(self.env.grasp.critic_state)
                            .critic_state
                    }
                    _ => 0,
                },
                ..self.policy.clone()
            },
            ..self.ppo.clone()
        }
    }

    /// Checks every value; errors name `path` and the field.
    pub fn validate(&self, path: &Path) -> Result<(), TrainConfigError> {
        let bad = |field: &str, message: String| {
            Err(TrainConfigError::Value {
                path: path.to_path_buf(),
                field: field.to_string(),
                message,
            })
        };
        let name_ok = !self.name.is_empty()
            && self.name.len() <= 100
            && self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
            && !self.name.starts_with('.');
        if !name_ok {
            return bad(
                "name",
                format!(
                    "'{}' must be 1-100 characters of letters, digits, '_', '-', '.' (it \
                     names the run folder)",
                    self.name
                ),
            );
        }
        // config.toml holds TOML integers (i64): a larger value given on the command
        // line could not be saved with the run.
        for (field, v) in [
            ("seed", self.seed),
            ("total_timesteps", self.total_timesteps),
        ] {
            if i64::try_from(v).is_err() {
                return bad(field, format!("{v} must be at most {}", i64::MAX));
            }
        }
        if self.checkpoint_every == 0 {
            return bad("checkpoint_every", "must be at least 1".into());
        }
        if self.plot_every == 0 {
            return bad("plot_every", "must be at least 1".into());
        }
        if self.best_window == 0 || self.best_window > 10_000 {
            return bad(
                "best_window",
                format!("{} must be in 1..=10000", self.best_window),
            );
        }
        if let Some(Err(m)) = self
            .time_budget_minutes
            .map(crate::util::num::check_minutes)
        {
            return bad("time_budget_minutes", m);
        }
        if let Some(Err(m)) = self.threads.map(crate::util::threads::check) {
            return bad("threads", m);
        }
        if self.objects != "primitives" && self.objects != crate::objects::stream::STREAM_SET {
            if let Err(e) = crate::objects::sets::resolve_specs(&self.objects) {
                return bad("objects", e.to_string());
            }
        }
        if !(1..=22).contains(&self.n_components) {
            return bad(
                "n_components",
                format!(
                    "{} must be in 1..=22 (the paper uses 3, 5, 8, 10)",
                    self.n_components
                ),
            );
        }
        if self.env.cartpole_max_steps == 0 {
            return bad("env.cartpole_max_steps", "must be at least 1".into());
        }
        // Settings that would be overwritten or ignored are refused, naming them.
        if self.policy.critic_state != 0 {
            return bad(
                "policy.critic_state",
                format!(
                    "{} is not read: the critic's privileged inputs are switched on by \
                     `[env] critic_state = true`; remove it from [policy]",
                    self.policy.critic_state
                ),
            );
        }
        if self.env.kind == EnvKind::Grasp
            && self.objects == crate::objects::stream::STREAM_SET
            && self.env.grasp.object_curriculum.enabled
        {
            return bad(
                "env.object_curriculum.enabled",
                "true, but the object curriculum weights the objects of a fixed set and \
                 objects = \"procedural\" builds new ones as it trains (it would be \
                 ignored): set it to false, or train on a set"
                    .into(),
            );
        }
        if self.env.kind == EnvKind::Grasp {
            let max = crate::env::obs::MAX_HISTORY;
            if self.env.grasp.history > max {
                return bad(
                    "env.history",
                    format!("{} must be in 1..={max}", self.env.grasp.history),
                );
            }
            // The rollout buffers with this environment's observation width (a long
            // history multiplies it).
            let layout = crate::env::obs::ObsLayout::new(
                self.env.grasp.modality,
                self.n_components,
                self.env.grasp.history.max(1),
            );
            let obs = layout.len() + crate::env::obs::CRITIC_STATE_LEN;
            if let Err(m) = self.ppo_config().check_rollout_bytes(obs as u64) {
                return bad("ppo.num_steps", m);
            }
            if let Err((field, message)) = self.env.grasp.curriculum.validate() {
                return bad(&format!("env.curriculum.{field}"), message);
            }
            if let Err(e) = self.env.grasp.validate() {
                return bad("env", e.to_string());
            }
        }
        // Each error under the table its key is set in: `[policy]` keys, top-level ones
        // (`num_envs`, ...) and `[ppo]` ones.
        match self.ppo_config().validate() {
            Ok(()) => {}
            Err(crate::ppo::PpoError::Policy(crate::policy::PolicyError::Config {
                field,
                message,
            })) => return bad(&format!("policy.{field}"), message),
            Err(crate::ppo::PpoError::Config { field, message }) => {
                let top = field.split('/').all(|f| PPO_KEYS_ELSEWHERE.contains(&f));
                let key = if top {
                    field.to_string()
                } else {
                    format!("ppo.{field}")
                };
                return bad(&key, message);
            }
            Err(e) => return bad("ppo", e.to_string()),
        }
        Ok(())
    }

    /// The resolved config as TOML text, which [`TrainConfig::parse`] reads back to an
    /// equal config.
    pub fn to_toml_string(&self) -> Result<String, TrainConfigError> {
        let err = |e: &dyn std::fmt::Display| TrainConfigError::Value {
            path: PathBuf::from("config.toml"),
            field: "(serialise)".into(),
            message: e.to_string(),
        };
        let mut t = toml::Table::new();
        t.insert("name".into(), self.name.clone().into());
        let seed = i64::try_from(self.seed).map_err(|e| err(&e))?;
        t.insert("seed".into(), seed.into());
        let steps = i64::try_from(self.total_timesteps).map_err(|e| err(&e))?;
        t.insert("total_timesteps".into(), steps.into());
        t.insert("num_envs".into(), (self.num_envs as i64).into());
        if let Some(n) = self.threads {
            t.insert("threads".into(), (n as i64).into());
        }
        let every = i64::try_from(self.checkpoint_every).map_err(|e| err(&e))?;
        t.insert("checkpoint_every".into(), every.into());
        if self.milestone_every > 0 {
            let m = i64::try_from(self.milestone_every).map_err(|e| err(&e))?;
            t.insert("milestone_every".into(), m.into());
        }
        let plot = i64::try_from(self.plot_every).map_err(|e| err(&e))?;
        t.insert("plot_every".into(), plot.into());
        t.insert("best_window".into(), (self.best_window as i64).into());
        if let Some(m) = self.time_budget_minutes {
            t.insert("time_budget_minutes".into(), m.into());
        }
        t.insert("objects".into(), self.objects.clone().into());
        t.insert(
            "synergy".into(),
            self.synergy.to_string_lossy().into_owned().into(),
        );
        t.insert("n_components".into(), (self.n_components as i64).into());
        if let Some(p) = &self.sim_config {
            t.insert("sim_config".into(), p.to_string_lossy().into_owned().into());
        }
        let mut ppo = toml::Table::try_from(&self.ppo).map_err(|e| err(&e))?;
        for k in PPO_KEYS_ELSEWHERE {
            ppo.remove(k);
        }
        t.insert("ppo".into(), ppo.into());
        let policy = toml::Table::try_from(&self.policy).map_err(|e| err(&e))?;
        t.insert("policy".into(), policy.into());
        let mut env = toml::Table::try_from(&self.env.grasp).map_err(|e| err(&e))?;
        let kind = match self.env.kind {
            EnvKind::Grasp => "grasp",
            EnvKind::Cartpole => "cartpole",
        };
        env.insert("kind".into(), kind.into());
        env.insert(
            "cartpole_max_steps".into(),
            i64::from(self.env.cartpole_max_steps).into(),
        );
        t.insert("env".into(), env.into());
        toml::to_string(&t).map_err(|e| err(&e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn merge_replaces_values_and_merges_tables() {
        let mut a: toml::Table = toml::from_str("x = 1\n[t]\na = 1\nb = 2\n").unwrap();
        let b: toml::Table = toml::from_str("y = 3\n[t]\nb = 5\n").unwrap();
        merge_tables(&mut a, b);
        let want: toml::Table = toml::from_str("x = 1\ny = 3\n[t]\na = 1\nb = 5\n").unwrap();
        assert_eq!(a, want);
    }

    #[test]
    fn inheritance_applies_child_over_base() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        write(
            dir.path(),
            "base.toml",
            "name = \"b\"\nseed = 3\nnum_envs = 4\n[ppo]\nnum_steps = 64\ngamma = 0.9\n\
             [env]\nhistory = 2\n",
        );
        let child = write(
            &dir.path().join("sub"),
            "child.toml",
            "base = \"../base.toml\"\nname = \"c\"\n[ppo]\ngamma = 0.95\n[policy]\nkind = \
             \"mlp\"\n[env]\nmodality = \"M1\"\n",
        );
        let c = TrainConfig::load(&child).unwrap();
        assert_eq!(c.name, "c");
        assert_eq!(c.seed, 3);
        assert_eq!(c.num_envs, 4);
        assert_eq!(c.ppo.num_steps, 64);
        assert_eq!(c.ppo.gamma, 0.95);
        assert_eq!(c.policy.kind, crate::policy::PolicyKind::Mlp);
        assert_eq!(c.env.grasp.history, 2);
        assert_eq!(c.env.grasp.modality, Modality::M1);
        let p = c.ppo_config();
        assert_eq!((p.seed, p.num_envs), (3, 4));
    }

    #[test]
    fn typo_in_a_base_file_names_that_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "base.toml", "seed = 1\n[ppo]\nnum_step = 8\n");
        let child = write(dir.path(), "c.toml", "base = \"base.toml\"\n");
        let e = TrainConfig::load(&child).unwrap_err().to_string();
        assert!(
            e.contains("base.toml") && e.contains("line 3") && e.contains("num_step"),
            "{e}"
        );
    }

    #[test]
    fn base_loops_and_misplaced_ppo_keys_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let a = write(dir.path(), "a.toml", "base = \"b.toml\"\n");
        write(dir.path(), "b.toml", "base = \"a.toml\"\n");
        let e = TrainConfig::load(&a).unwrap_err().to_string();
        assert!(e.contains("loops"), "{e}");
        let p = write(
            dir.path(),
            "p.toml",
            "seed = 1\n\n[ppo]\ngamma = 0.9\nseed = 4\n",
        );
        let e = TrainConfig::load(&p).unwrap_err().to_string();
        assert!(e.contains("line 5") && e.contains("ppo.seed"), "{e}");
        let m = write(dir.path(), "m.toml", "base = \"missing.toml\"\n");
        let e = TrainConfig::load(&m).unwrap_err().to_string();
        assert!(
            e.contains("m.toml: `base`") && e.contains("missing.toml"),
            "{e}"
        );
    }

    #[test]
    fn a_base_that_is_no_file_names_the_file_that_refers_to_it() {
        // A folder was named only by itself ("cannot read config DIR: Is a directory"),
        // an empty `base` as "cannot read : No such file"; a `base` in a checkpoint's
        // config.toml pointed at an API ("use TrainConfig::load").
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let d = write(dir.path(), "d.toml", "base = \"sub\"\n");
        let e = TrainConfig::load(&d).unwrap_err().to_string();
        assert!(
            e.contains("d.toml: `base`") && e.contains("sub is a folder, not a config file"),
            "{e}"
        );
        let empty = write(dir.path(), "e.toml", "base = \"\"\n");
        let e = TrainConfig::load(&empty).unwrap_err().to_string();
        assert!(e.contains("e.toml: `base`: is empty"), "{e}");
        let e = TrainConfig::parse(Path::new("ck/config.toml"), "base = \"b.toml\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("ck/config.toml: `base`")
                && e.contains("saved complete")
                && !e.contains("TrainConfig"),
            "{e}"
        );
    }

    #[test]
    fn out_of_range_values_name_the_field() {
        let p = Path::new("x.toml");
        for (text, field) in [
            ("checkpoint_every = 0\n", "checkpoint_every"),
            ("objects = \"ycb\"\n", "objects"),
            ("n_components = 30\n", "n_components"),
            ("name = \"a/b\"\n", "name"),
            ("time_budget_minutes = -1.0\n", "time_budget_minutes"),
            ("[ppo]\ngamma = 2.0\n", "gamma"),
            ("[env]\nhistory = 0\n", "history"),
            ("[env]\nhistory = 100000\n", "env.history"),
            ("[env.curriculum]\nwindow = 0\n", "env.curriculum.window"),
            ("threads = 0\n", "threads"),
            ("threads = 100000\n", "threads"),
            ("[ppo]\nlearning_rate = 1e300\n", "1e300 must be in (0, 1]"),
            ("[env]\nclosing_period = 1e-300\n", "closing_period"),
            (
                "[env.randomization]\nfriction = [0.5, 1.0, 7.0]\n",
                "`randomization.friction` has 3 numbers",
            ),
            ("[env.randomization]\nsize_scale = [1.0]\n", "size_scale"),
            ("[env.action]\ngrip_scale = 1.5\n", "action.grip_scale"),
            (
                "[env.action]\ngrip_scale = 0.25\ngrip_ramp = -0.1\n",
                "action.grip_ramp: -0.1 is outside [0, 1]",
            ),
            (
                "[env.action]\ngrip_scale = 0.0\ngrip_ramp = 0.05\n",
                "action.grip_ramp: ramps the grip, but the grip is off",
            ),
            (
                "[env.action]\ngrip_scale = 0.0\ngrip_delay = 1\n",
                "action.grip_delay: delays the grip, but the grip is off",
            ),
            (
                "[env]\nmax_steps = 5\n[env.action]\ngrip_scale = 0.25\ngrip_delay = 5\n",
                "action.grip_delay: 5 steps leave no step with the grip: must be below max_steps (5)",
            ),
            (
                "[env.action]\ngrip_scale = 0.25\ngrip_delay = -1\n",
                "line 3, column 14: invalid value: integer `-1`",
            ),
            (
                "[env.action]\nlift_squeeze = 1.5\n",
                "action.lift_squeeze: 1.5 is outside [0, 1]",
            ),
            (
                "[env.action]\nlift_squeeze = nan\n",
                "action.lift_squeeze: NaN is outside [0, 1]",
            ),
            (
                "[env.reward]\ndisplacement_weight = -1.0\n",
                "reward.displacement_weight",
            ),
            ("[env]\nmodality = \"M4\"\n", "M3G"),
            ("[env.placement]\nantipodal = 2.0\n", "placement.antipodal"),
            (
                "[env.placement]\noffset = 1e300\n",
                "placement.offset: 1e300 is outside [0, 0.05] m",
            ),
            ("[env.placement]\nspread = 0.1\n", "spread"),
        ] {
            let e = TrainConfig::parse(p, text).unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("x.toml"), "{text}: {e}");
        }
    }

    #[test]
    fn integers_a_run_folder_cannot_hold_are_refused() {
        let mut c = TrainConfig::parse(Path::new("x.toml"), "").unwrap();
        c.seed = u64::MAX;
        let e = c.validate(Path::new("x.toml")).unwrap_err().to_string();
        assert!(
            e.contains("`seed`") && e.contains("9223372036854775807"),
            "{e}"
        );
        c.seed = 1;
        c.total_timesteps = u64::MAX;
        let e = c.validate(Path::new("x.toml")).unwrap_err().to_string();
        assert!(e.contains("`total_timesteps`"), "{e}");
    }

    #[test]
    fn resolved_config_round_trips() {
        let c = TrainConfig::parse(
            Path::new("r.toml"),
            "name = \"rt\"\nthreads = 2\ntime_budget_minutes = 1.5\nsim_config = \
             \"configs/sim.toml\"\n[ppo]\ntarget_kl = 0.02\nlearning_rate = 0.0003\n[env]\n\
             kind = \"cartpole\"\ncartpole_max_steps = 200\n",
        )
        .unwrap();
        let text = c.to_toml_string().unwrap();
        let d = TrainConfig::parse(Path::new("config.toml"), &text).unwrap();
        assert_eq!(c, d);
        assert_eq!(d.env.kind, EnvKind::Cartpole);
    }

    #[test]
    fn object_curriculum_section_is_read_and_checked() {
        let c = TrainConfig::parse(
            Path::new("o.toml"),
            "[env.object_curriculum]\nenabled = true\nwindow = 4\n",
        )
        .unwrap();
        let oc = &c.env.grasp.object_curriculum;
        assert!(oc.enabled && oc.window == 4 && oc.floor == 0.1);
        let text = c.to_toml_string().unwrap();
        assert_eq!(TrainConfig::parse(Path::new("c.toml"), &text).unwrap(), c);
        let e = TrainConfig::parse(
            Path::new("o.toml"),
            "[env.object_curriculum]\nenabled = true\nfloor = -1.0\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("o.toml") && e.contains("object_curriculum.floor"),
            "{e}"
        );
    }

    #[test]
    fn settings_that_would_be_ignored_are_refused() {
        // Issue 49: both were accepted, and the run trained without them.
        for (text, want) in [
            (
                "[env]\ncritic_state = true\n[policy]\ncritic_state = 12\n",
                "`policy.critic_state`",
            ),
            (
                "objects = \"procedural\"\n[env.object_curriculum]\nenabled = true\n",
                "`env.object_curriculum.enabled`",
            ),
        ] {
            let e = TrainConfig::parse(Path::new("i.toml"), text)
                .unwrap_err()
                .to_string();
            assert!(e.contains("i.toml") && e.contains(want), "{e}");
        }
        // What a run folder's config.toml holds still reads.
        let c = TrainConfig::parse(Path::new("c.toml"), "[env]\ncritic_state = true\n").unwrap();
        let text = c.to_toml_string().unwrap();
        assert_eq!(TrainConfig::parse(Path::new("c.toml"), &text).unwrap(), c);
    }

    #[test]
    fn env_section_covers_every_env_config_field() {
        let t = toml::Table::try_from(EnvConfig::default()).unwrap();
        let text = toml::to_string(&t).unwrap();
        let s: EnvSection = parse_toml(Path::new("e.toml"), &text).unwrap();
        assert!(s.modality.is_some() && s.curriculum.is_some() && s.action.is_some());
    }
}
