//! Experiment grids: the paper's ablations (Sec. V-A, Fig. 5) as many training runs,
//! one per (variant config, seed), run through [`crate::train::TrainSession`], then
//! summarised and plotted.
//!
//! A grid is a TOML file ([`GridConfig`]):
//!
//! ```toml
//! name = "paper_ablation"
//! seeds = [1, 2, 3]
//! parallel = 1                 # runs at once; the cores are split between them
//! [budget]                     # per run: whichever ends first
//! transitions = 2000000
//! minutes = 480.0
//! [overrides]                  # applied to every run's config (all optional)
//! num_envs = 20
//! [eval]                       # optional: evaluate each run's latest checkpoint
//! objects = "unseen"
//! trials = 3
//! stochastic = false           # true: sampled actions, as in training
//! [[ablation]]
//! name = "modality"
//! title = "Modalities (Fig. 5a)"
//! configs = ["../gru_m1_pca5.toml", "../gru_m2_pca5.toml", "../gru_m3_pca5.toml"]
//! ```
//!
//! Config paths are relative to the grid file. Grids live in `configs/grids/` (every
//! `configs/*.toml` is a training config). A config named by several ablations is
//! trained once. Run folders are `<out>/<variant>/seed<k>`; a finished run holds
//! `done.json`. [`run_grid`] skips finished runs and resumes unfinished ones from their
//! latest checkpoint (with what is left of their minutes), so a grid killed at any moment
//! continues where it stopped. [`summarize`] and [`write_reports`] read the run folders
//! and write `summary.md`, `summary.csv` (per variant), `runs.csv` (per run) and one
//! `<ablation>.svg` per ablation: the success rate against transitions, mean over seeds
//! with a min-max band.

pub mod curves;
pub mod evaluation;
mod summary;

use crate::checkpoint::files;
use crate::checkpoint::latest_dir;
use crate::policy::PolicyKind;
use crate::train::{metrics, StopReason, TrainConfig, TrainError, TrainSession};
use crate::util::config::{load_toml, ConfigError};
use crate::util::fsx::write_atomic;
use crate::util::seq::first_repeat;
use curves::Band;
pub use evaluation::{evaluate_runs, EvalPlacement, EvalSettings, PooledSet, RunEval, EVAL_FILE};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;
pub use summary::{markdown, summarize, write_reports, GridSummary, RunRow, VariantRow};

/// Marker file of a finished run.
pub const DONE_FILE: &str = "done.json";

/// Per-run budget: training stops at whichever limit comes first.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunBudget {
    /// Transitions (`total_timesteps`) per run; the config's value when absent.
    pub transitions: Option<u64>,
    /// Wall minutes per run (over resumes); the config's `time_budget_minutes` when absent.
    pub minutes: Option<f64>,
}

/// Settings applied to every run's config.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunOverrides {
    /// Parallel environments.
    pub num_envs: Option<usize>,
    /// PPO rollout length per environment.
    pub num_steps: Option<usize>,
    /// PPO minibatches per epoch.
    pub num_minibatches: Option<usize>,
    /// PPO epochs per update.
    pub update_epochs: Option<usize>,
    /// Training objects (anything `--objects` accepts, or `primitives`).
    pub objects: Option<String>,
}

/// One ablation: the variants compared in one plot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ablation {
    /// Short name (file-safe): names the plot `<name>.svg`.
    pub name: String,
    /// Plot title (default: the name).
    pub title: Option<String>,
    /// Training configs of the variants, relative to the grid file.
    pub configs: Vec<PathBuf>,
    /// The variant the others are compared with, one of `configs` (default: the first).
    #[serde(default)]
    pub reference: Option<PathBuf>,
}

/// A grid file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridConfig {
    /// Name of the grid (the default output folder is `runs/<name>`).
    pub name: String,
    /// Seeds; every variant runs once per seed.
    pub seeds: Vec<u64>,
    /// Runs trained at once (the cores are split between them).
    #[serde(default = "one_usize")]
    pub parallel: usize,
    /// Trailing window (updates) of the plotted curves' smoothing.
    #[serde(default = "five")]
    pub smooth: usize,
    /// Updates averaged for the final training success.
    #[serde(default = "ten")]
    pub final_window: usize,
    /// Band of the plots: `minmax` or `std`.
    #[serde(default = "minmax")]
    pub band: Band,
    /// Per-run budget.
    #[serde(default)]
    pub budget: RunBudget,
    /// Settings applied to every run.
    #[serde(default)]
    pub overrides: RunOverrides,
    /// Optional evaluation.
    pub eval: Option<EvalSettings>,
    /// The ablations.
    pub ablation: Vec<Ablation>,
}

fn one_usize() -> usize {
    1
}
fn five() -> usize {
    5
}
fn ten() -> usize {
    10
}
fn minmax() -> Band {
    Band::MinMax
}

/// Errors of an experiment grid.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// The grid file could not be read or parsed.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A grid value is invalid.
    #[error("invalid grid {path}: `{field}`: {message}")]
    Value {
        /// The grid file.
        path: PathBuf,
        /// The field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A variant's training config is invalid (or a run failed).
    #[error("{context}: {source}")]
    Train {
        /// The config or run folder.
        context: String,
        /// The cause.
        source: TrainError,
    },
    /// The output folder already holds runs of this grid.
    #[error(
        "{dir} already holds runs of this grid: pass --resume to continue them, or another --out"
    )]
    Exists {
        /// The output folder.
        dir: PathBuf,
    },
    /// The output folder is no grid's (a checkpoint folder, a folder of other files).
    #[error("--out {dir} {why}: run the grid into a new folder")]
    NotAGridFolder {
        /// The folder.
        dir: PathBuf,
        /// What it is instead.
        why: String,
    },
    /// `--resume` of a grid whose edits change how its runs are trained.
    #[error(
        "cannot resume {dir}: the grid now trains it differently from how it was trained \
         (its config.toml differs in {keys}); restore the grid's settings, or run the \
         edited grid into another --out"
    )]
    Changed {
        /// The run folder.
        dir: PathBuf,
        /// The differing keys.
        keys: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// An evaluation failed.
    #[error("evaluating {dir}: {source}")]
    Eval {
        /// The run folder.
        dir: PathBuf,
        /// The cause.
        source: crate::eval::EvalError,
    },
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// A variant: one training config with the grid's budget and overrides applied.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// The config's `name` (names the variant's folder).
    pub name: String,
    /// The paper's name of the setting, e.g. `GRU-M3PCA5`.
    pub label: String,
    /// The config file.
    pub path: PathBuf,
    /// The resolved config (seed set per run).
    pub config: TrainConfig,
}

/// One (variant, seed) run.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRun {
    /// Index into [`Plan::variants`].
    pub variant: usize,
    /// The seed.
    pub seed: u64,
    /// The run folder.
    pub dir: PathBuf,
}

/// A grid resolved against its configs and output folder.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The grid.
    pub grid: GridConfig,
    /// The grid file.
    pub path: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// Distinct variants, in order of first mention.
    pub variants: Vec<Variant>,
    /// For each ablation, the indices of its variants.
    pub ablations: Vec<Vec<usize>>,
    /// For each ablation, the index of its reference variant.
    pub references: Vec<usize>,
    /// Every run, variant-major.
    pub runs: Vec<PlannedRun>,
}

/// The paper's name of a config's setting: `GRU-M3PCA5` style.
pub fn paper_label(cfg: &TrainConfig) -> String {
    let kind = match cfg.policy.kind {
        PolicyKind::Gru => "GRU",
        PolicyKind::Mlp => "MLP",
    };
    format!("{kind}-{:?}PCA{}", cfg.env.grasp.modality, cfg.n_components)
}

impl GridConfig {
    /// Loads and validates a grid file (errors name the file, line and field).
    pub fn load(path: &Path) -> Result<GridConfig, ExperimentError> {
        let g: GridConfig = load_toml(path)?;
        g.validate(path)?;
        Ok(g)
    }

    /// Checks the values; errors name `path` and the field.
    pub fn validate(&self, path: &Path) -> Result<(), ExperimentError> {
        let bad = |field: &str, message: String| {
            Err(ExperimentError::Value {
                path: path.to_path_buf(),
                field: field.into(),
                message,
            })
        };
        let safe = |s: &str| {
            !s.is_empty()
                && !s.starts_with('.')
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
        };
        if !safe(&self.name) {
            return bad(
                "name",
                format!("'{}' must be letters, digits, _ - .", self.name),
            );
        }
        if self.seeds.is_empty() {
            return bad("seeds", "list at least one seed".into());
        }
        if first_repeat(&self.seeds).is_some() {
            return bad("seeds", "a seed is listed twice".into());
        }
        if self.parallel == 0 || self.parallel > 64 {
            return bad("parallel", format!("{} must be in 1..=64", self.parallel));
        }
        if self.smooth == 0 || self.final_window == 0 {
            return bad("smooth/final_window", "must be at least 1".into());
        }
        if self.budget.transitions == Some(0) {
            return bad("budget.transitions", "must be at least 1".into());
        }
        if let Some(Err(m)) = self.budget.minutes.map(crate::util::num::check_minutes) {
            return bad("budget.minutes", m);
        }
        if let Some(Err((field, message))) = self.eval.as_ref().map(EvalSettings::validate) {
            return bad(field, message);
        }
        if self.ablation.is_empty() {
            return bad("ablation", "add at least one [[ablation]]".into());
        }
        for (k, a) in self.ablation.iter().enumerate() {
            if !safe(&a.name) {
                return bad(
                    &format!("ablation[{k}].name"),
                    format!("'{}' must be letters, digits, _ - .", a.name),
                );
            }
            if a.configs.is_empty() {
                return bad(
                    &format!("ablation[{k}].configs"),
                    "list at least one config".into(),
                );
            }
            if let Some(c) = first_repeat(&a.configs) {
                return bad(
                    &format!("ablation[{k}].configs"),
                    format!("{} is listed twice", c.display()),
                );
            }
            if let Some(r) = a.reference.as_ref().filter(|r| !a.configs.contains(r)) {
                return bad(
                    &format!("ablation[{k}].reference"),
                    format!("{} is not one of the ablation's configs", r.display()),
                );
            }
            if self.ablation[..k].iter().any(|b| b.name == a.name) {
                return bad(
                    &format!("ablation[{k}].name"),
                    format!("'{}' is used twice", a.name),
                );
            }
        }
        Ok(())
    }
}

/// Resolves the grid at `path` into variants and runs under `out`: every config is
/// loaded (with its `base` chain) and the budget and overrides applied and validated.
pub fn plan(path: &Path, out: &Path) -> Result<Plan, ExperimentError> {
    let grid = GridConfig::load(path)?;
    let root = path.parent().unwrap_or(Path::new("."));
    let mut variants: Vec<Variant> = Vec::new();
    let mut ablations = Vec::new();
    let mut references = Vec::new();
    for a in &grid.ablation {
        let mut members = Vec::new();
        for c in &a.configs {
            let cpath = root.join(c);
            let idx = match variants.iter().position(|v| v.path == cpath) {
                Some(i) => i,
                None => {
                    let train_err = |source: TrainError| ExperimentError::Train {
                        context: format!("config {} (grid {})", cpath.display(), path.display()),
                        source,
                    };
                    let mut cfg = TrainConfig::load(&cpath).map_err(|e| train_err(e.into()))?;
                    apply(&grid, &mut cfg);
                    cfg.validate(&cpath).map_err(|e| train_err(e.into()))?;
                    if let Some(other) = variants.iter().find(|v| v.name == cfg.name) {
                        return Err(ExperimentError::Value {
                            path: path.to_path_buf(),
                            field: "ablation.configs".into(),
                            message: format!(
                                "{} and {} have the same name '{}' (it names the run folder)",
                                other.path.display(),
                                cpath.display(),
                                cfg.name
                            ),
                        });
                    }
                    variants.push(Variant {
                        name: cfg.name.clone(),
                        label: paper_label(&cfg),
                        path: cpath.clone(),
                        config: cfg,
                    });
                    variants.len() - 1
                }
            };
            if !members.contains(&idx) {
                members.push(idx);
            }
        }
        let reference = a
            .reference
            .as_ref()
            .and_then(|r| variants.iter().position(|v| v.path == root.join(r)))
            .unwrap_or(members[0]);
        references.push(reference);
        ablations.push(members);
    }
    let runs = variants
        .iter()
        .enumerate()
        .flat_map(|(i, v)| {
            grid.seeds.iter().map(move |&seed| PlannedRun {
                variant: i,
                seed,
                dir: out.join(&v.name).join(format!("seed{seed}")),
            })
        })
        .collect();
    Ok(Plan {
        grid,
        path: path.to_path_buf(),
        out: out.to_path_buf(),
        variants,
        ablations,
        references,
        runs,
    })
}

fn apply(grid: &GridConfig, cfg: &mut TrainConfig) {
    if let Some(t) = grid.budget.transitions {
        cfg.total_timesteps = t;
    }
    if let Some(m) = grid.budget.minutes {
        cfg.time_budget_minutes = Some(m);
    }
    let o = &grid.overrides;
    if let Some(n) = o.num_envs {
        cfg.num_envs = n;
    }
    if let Some(n) = o.num_steps {
        cfg.ppo.num_steps = n;
    }
    if let Some(n) = o.num_minibatches {
        cfg.ppo.num_minibatches = n;
    }
    if let Some(n) = o.update_epochs {
        cfg.ppo.update_epochs = n;
    }
    if let Some(s) = &o.objects {
        cfg.objects = s.clone();
    }
}

/// The record of a finished run (`done.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Variant name.
    pub variant: String,
    /// Seed.
    pub seed: u64,
    /// PPO updates.
    pub updates: u64,
    /// Transitions collected.
    pub transitions: u64,
    /// Episodes finished.
    pub episodes: u64,
    /// Training wall time over all resumes (s).
    pub wall_s: f64,
    /// `completed` (all transitions) or `time_budget` (the run's minutes).
    pub stop: String,
}

/// Where a run stands on disk.
#[derive(Debug, Clone, PartialEq)]
pub enum RunState {
    /// Finished (`done.json`).
    Done(RunRecord),
    /// Started: it has a latest checkpoint.
    Partial,
    /// Not started (or killed before its first checkpoint).
    New,
}

/// Reads the state of the run folder `dir`.
pub fn run_state(dir: &Path) -> Result<RunState, ExperimentError> {
    let done = dir.join(DONE_FILE);
    if done.is_file() {
        let text = crate::util::fsx::read_to_string_bounded(&done, crate::util::fsx::limits::DATA)
            .map_err(|e| io_err(&done, e))?;
        let r: RunRecord = serde_json::from_str(&text).map_err(|e| io_err(&done, e))?;
        return Ok(RunState::Done(r));
    }
    if latest_dir(dir).join(crate::ppo::CHECKPOINT_FILE).is_file() {
        return Ok(RunState::Partial);
    }
    Ok(RunState::New)
}

/// How [`run_grid`] runs.
#[derive(Debug, Clone, PartialEq)]
pub struct GridOptions {
    /// Wall minutes for this invocation: no run starts after it, running ones stop (with a
    /// checkpoint) when it ends, unfinished runs resume next time.
    pub budget_minutes: Option<f64>,
    /// Continue a grid whose output folder already holds runs.
    pub resume: bool,
    /// Cores to use in total (split between parallel runs).
    pub threads: usize,
    /// Runs at once (default: the grid's `parallel`).
    pub parallel: Option<usize>,
}

/// What happened to one run in [`run_grid`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunOutcome {
    /// Variant name.
    pub variant: String,
    /// Seed.
    pub seed: u64,
    /// The run folder.
    pub dir: PathBuf,
    /// `skipped` (already finished), `finished`, `stopped` (grid budget; resumable) or
    /// `not_started` (grid budget).
    pub status: String,
    /// Training wall time spent in this invocation (s).
    pub wall_s: f64,
}

/// Trains every unfinished run of `plan` (see the module docs); `log` receives one line
/// per started and ended run. Runs are taken in order by `parallel` workers, each with
/// `threads / parallel` environment threads.
pub fn run_grid(
    plan: &Plan,
    opts: &GridOptions,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Vec<RunOutcome>, ExperimentError> {
    let states = plan
        .runs
        .iter()
        .map(|r| run_state(&r.dir))
        .collect::<Result<Vec<_>, _>>()?;
    if !opts.resume && states.iter().any(|s| *s != RunState::New) {
        return Err(ExperimentError::Exists {
            dir: plan.out.clone(),
        });
    }
    check_out_folder(plan)?;
    for (r, state) in plan.runs.iter().zip(&states) {
        if *state != RunState::New {
            check_unchanged(plan, r)?;
        }
    }
    crate::util::fsx::create_dirs(&plan.out).map_err(|e| io_err(&plan.out, e))?;
    let parallel = opts.parallel.unwrap_or(plan.grid.parallel).max(1);
    let threads = (opts.threads / parallel).max(1);
    let deadline = opts
        .budget_minutes
        .and_then(|m| std::time::Duration::try_from_secs_f64(m * 60.0).ok())
        .and_then(|d| Instant::now().checked_add(d));
    let queue: Mutex<VecDeque<usize>> = Mutex::new((0..plan.runs.len()).collect());
    let results: Mutex<Vec<(usize, RunOutcome)>> = Mutex::new(Vec::new());
    let first_error: Mutex<Option<ExperimentError>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..parallel.min(plan.runs.len()) {
            scope.spawn(|| loop {
                if first_error.lock().map_or(true, |e| e.is_some()) {
                    return;
                }
                let Some(i) = queue.lock().ok().and_then(|mut q| q.pop_front()) else {
                    return;
                };
                let r = &plan.runs[i];
                let outcome = match &states[i] {
                    RunState::Done(_) => Ok(outcome(plan, r, "skipped", 0.0)),
                    _ => execute(plan, r, threads, deadline, log),
                };
                match outcome {
                    Ok(o) => {
                        if let Ok(mut v) = results.lock() {
                            v.push((i, o));
                        }
                    }
                    Err(e) => {
                        if let Ok(mut f) = first_error.lock() {
                            f.get_or_insert(e);
                        }
                    }
                }
            });
        }
    });
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }
    let mut v = results.into_inner().unwrap_or_default();
    v.sort_by_key(|x| x.0);
    Ok(v.into_iter().map(|x| x.1).collect())
}

fn outcome(plan: &Plan, r: &PlannedRun, status: &str, wall_s: f64) -> RunOutcome {
    RunOutcome {
        variant: plan.variants[r.variant].name.clone(),
        seed: r.seed,
        dir: r.dir.clone(),
        status: status.into(),
        wall_s,
    }
}

/// Refuses an output folder that is no grid's, before anything is written in it: a
/// checkpoint folder, or a non-empty folder holding neither a run folder of the grid's
/// variants nor its `summary.md` (the repository root, a folder of other files), where
/// the reports (`summary.md`, `runs.csv`, plots) would be written among the user's files.
fn check_out_folder(plan: &Plan) -> Result<(), ExperimentError> {
    let out = &plan.out;
    let refuse = |why: String| {
        Err(ExperimentError::NotAGridFolder {
            dir: out.clone(),
            why,
        })
    };
    if out.join(crate::ppo::CHECKPOINT_FILE).exists() {
        return refuse(format!(
            "is a checkpoint folder (it holds {})",
            crate::ppo::CHECKPOINT_FILE
        ));
    }
    let Ok(entries) = std::fs::read_dir(out) else {
        // Missing (created later) or unreadable (said when it is created).
        return Ok(());
    };
    let mut names: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    let ours = |n: &String| n == "summary.md" || plan.variants.iter().any(|v| &v.name == n);
    if names.is_empty() || names.iter().any(ours) {
        return Ok(());
    }
    names.sort();
    let shown: Vec<&str> = names.iter().take(3).map(String::as_str).collect();
    refuse(format!(
        "is not empty and holds no runs or reports of this grid (it holds {}{})",
        shown.join(", "),
        if names.len() > 3 { ", ..." } else { "" }
    ))
}

/// Keys of a run's config.toml that do not change how it trains: the threads and the
/// minutes left are set anew on every resume.
const RESUME_FREE_KEYS: [&str; 2] = ["threads", "time_budget_minutes"];

/// Refuses to continue (or count) run `r` when the grid now plans it with other
/// training settings than its saved config.toml holds (objects, transitions, PPO sizes,
/// the environment, ...): finished and resumed runs trained differently would be pooled
/// into one mean. Names the differing keys.
fn check_unchanged(plan: &Plan, r: &PlannedRun) -> Result<(), ExperimentError> {
    let path = r.dir.join(files::CONFIG);
    let Ok(text) =
        crate::util::fsx::read_to_string_bounded(&path, crate::util::fsx::limits::CONFIG)
    else {
        // A run without its config.toml is refused by training itself.
        return Ok(());
    };
    let saved: toml::Table = toml::from_str(&text).map_err(|e| io_err(&path, e))?;
    let mut cfg = plan.variants[r.variant].config.clone();
    cfg.seed = r.seed;
    let planned_text = cfg.to_toml_string().map_err(|e| io_err(&path, e))?;
    let planned: toml::Table = toml::from_str(&planned_text).map_err(|e| io_err(&path, e))?;
    let mut keys = Vec::new();
    diff_tables(&saved, &planned, "", &mut keys);
    keys.retain(|k| !RESUME_FREE_KEYS.contains(&k.as_str()));
    if keys.is_empty() {
        return Ok(());
    }
    Err(ExperimentError::Changed {
        dir: r.dir.clone(),
        keys: keys.join(", "),
    })
}

/// The dotted keys whose values differ between `a` and `b` (present in one only
/// included), sorted.
fn diff_tables(a: &toml::Table, b: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    let mut names: Vec<&String> = a.keys().chain(b.keys()).collect();
    names.sort();
    names.dedup();
    for k in names {
        let key = format!("{prefix}{k}");
        match (a.get(k), b.get(k)) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                diff_tables(x, y, &format!("{key}."), out)
            }
            (x, y) if x != y => out.push(key),
            _ => {}
        }
    }
}

/// Trains (or resumes) one run within the grid's deadline.
fn execute(
    plan: &Plan,
    r: &PlannedRun,
    threads: usize,
    deadline: Option<Instant>,
    log: &(dyn Fn(&str) + Sync),
) -> Result<RunOutcome, ExperimentError> {
    let v = &plan.variants[r.variant];
    let train_err = |source| ExperimentError::Train {
        context: format!("run {}", r.dir.display()),
        source,
    };
    let grid_left = deadline.map(|d| d.saturating_duration_since(Instant::now()).as_secs_f64());
    if grid_left.is_some_and(|s| s < 1.0) {
        return Ok(outcome(plan, r, "not_started", 0.0));
    }
    let resume = run_state(&r.dir)? == RunState::Partial;
    let metrics_path = r.dir.join(files::METRICS);
    let spent = if resume && metrics_path.is_file() {
        metrics::read_csv(&metrics_path)
            .map_err(train_err)?
            .last()
            .map_or(0.0, |row| row.wall_s)
    } else {
        0.0
    };
    if !resume && r.dir.exists() {
        // Killed before its first checkpoint: nothing to continue from.
        std::fs::remove_dir_all(&r.dir).map_err(|e| io_err(&r.dir, e))?;
    }
    let mut cfg = v.config.clone();
    cfg.seed = r.seed;
    cfg.threads = Some(threads);
    let own_left = cfg.time_budget_minutes.map(|m| m * 60.0 - spent);
    let left = match (own_left, grid_left) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    cfg.time_budget_minutes = left.map(|s| s.max(1.0) / 60.0);
    log(&format!(
        "{} {} seed {} ({} transitions, {} threads{})",
        if resume { "resuming" } else { "starting" },
        v.name,
        r.seed,
        cfg.total_timesteps,
        threads,
        left.map_or(String::new(), |s| format!(", at most {:.1} min", s / 60.0))
    ));
    let own_done = own_left.is_some_and(|s| s < 1.0);
    let summary = if own_done {
        None
    } else {
        let mut session = TrainSession::open(cfg, &r.dir, resume).map_err(train_err)?;
        Some(session.run(&mut |_| {}).map_err(train_err)?)
    };
    let (finished, record) = match &summary {
        None => {
            // The run's own minutes were already spent before a kill.
            let rows = metrics::read_csv(&metrics_path).map_err(train_err)?;
            let last = rows.last();
            (
                true,
                RunRecord {
                    variant: v.name.clone(),
                    seed: r.seed,
                    updates: last.map_or(0, |x| x.update),
                    transitions: last.map_or(0, |x| x.global_step),
                    episodes: last.map_or(0, |x| x.episodes),
                    wall_s: spent,
                    stop: "time_budget".into(),
                },
            )
        }
        Some(s) => {
            let own_total = v.config.time_budget_minutes.map(|m| m * 60.0);
            let finished =
                s.stop == StopReason::Completed || own_total.is_some_and(|t| s.wall_s >= t - 1.0);
            (
                finished,
                RunRecord {
                    variant: v.name.clone(),
                    seed: r.seed,
                    updates: s.updates,
                    transitions: s.global_step,
                    episodes: s.episodes,
                    wall_s: s.wall_s,
                    stop: match s.stop {
                        StopReason::Completed => "completed".into(),
                        StopReason::TimeBudget => "time_budget".into(),
                        StopReason::Interrupted => "interrupted".into(),
                    },
                },
            )
        }
    };
    let this_call = summary.as_ref().map_or(0.0, |s| s.wall_s - spent);
    if finished {
        let p = r.dir.join(DONE_FILE);
        let json = serde_json::to_string_pretty(&record).map_err(|e| io_err(&p, e))?;
        write_atomic(&p, json.as_bytes()).map_err(|e| io_err(&p, e))?;
    }
    log(&format!(
        "{} {} seed {}: {} transitions, {:.1} s",
        if finished {
            "finished"
        } else {
            "stopped (grid budget)"
        },
        v.name,
        r.seed,
        record.transitions,
        record.wall_s
    ));
    Ok(outcome(
        plan,
        r,
        if finished { "finished" } else { "stopped" },
        this_call,
    ))
}

#[cfg(test)]
mod tests;
