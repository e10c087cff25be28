//! A grid's evaluation: every finished run's latest checkpoint on the `[eval]` object
//! sets, and per ablation the variants' pooled success with paired tests against a
//! reference variant.
//!
//! ```toml
//! [eval]
//! objects = ["train", "unseen", "assets/meshes/novel"]   # or one set: "unseen"
//! trials = 20
//! pregrasp = "antipodal"          # or "top-down" (the default), as `grasp eval --pregrasp`
//! perturb = "../sensing/conditions.toml"   # optional, as `grasp eval --perturb`
//! ```
//!
//! Every run is evaluated on the same start poses (the trials' seed is common to the
//! grid), so run `k` of two variants meet identical scenes: the paired comparison of a
//! variant with its ablation's reference pools the trial pairs of every seed (exact
//! McNemar), and the pooled success carries a Wilson 95 % interval. Each set's outcomes
//! are cached in the run folder (`eval.json` for the first set, `eval_<set>.json` for the
//! others) while the settings and the checkpoint match.

use super::{io_err, run_state, ExperimentError, Plan, PlannedRun, RunState};
use crate::checkpoint::TrainedAgent;
use crate::checkpoint::{files, latest_dir};
use crate::eval::conditions::EvalConditions;
use crate::eval::paired::{mcnemar_exact, p_text};
use crate::eval::{evaluate, wilson, AgentSpec, EvalAgent, TrialPlan};
use crate::perception::pregrasp::AntipodalPregrasp;
use crate::robot::{Robot, Side};
use crate::util::fsx::write_atomic;
use serde::{Deserialize, Deserializer, Serialize};
use std::path::{Path, PathBuf};

/// Cached evaluation of a run on the first `[eval]` set.
pub const EVAL_FILE: &str = "eval.json";

/// Where the evaluated hands start (`grasp eval --pregrasp`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EvalPlacement {
    /// Over the object's centre, `grasp_depth` below its top (the training placement).
    #[default]
    TopDown,
    /// `grasp run`'s antipodal pre-grasp on the simulated depth cloud.
    Antipodal,
}

/// Optional evaluation of every run's latest checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvalSettings {
    /// Object sets (anything `grasp eval --objects` accepts); one string or a list.
    #[serde(deserialize_with = "one_or_many")]
    pub objects: Vec<String>,
    /// Trials per object (0: no evaluation).
    pub trials: usize,
    /// Curriculum level of the start poses (eq. 6), 1 = hardest.
    #[serde(default = "one")]
    pub difficulty: f64,
    /// Sample the policy's actions (as in training) instead of taking their mode
    /// (`grasp eval --stochastic`).
    #[serde(default)]
    pub stochastic: bool,
    /// Where the hands start.
    #[serde(default)]
    pub pregrasp: EvalPlacement,
    /// A conditions file (`grasp eval --perturb`), relative to the grid file.
    #[serde(default)]
    pub perturb: Option<PathBuf>,
}

fn one() -> f64 {
    1.0
}

fn one_or_many<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<String>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany {
        One(String),
        Many(Vec<String>),
    }
    Ok(match OneOrMany::deserialize(d)? {
        OneOrMany::One(s) => vec![s],
        OneOrMany::Many(v) => v,
    })
}

impl EvalSettings {
    /// Checks the values; errors name the field.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if !(0.0..=1.0).contains(&self.difficulty) {
            return Err((
                "eval.difficulty",
                format!("{} is outside [0, 1]", self.difficulty),
            ));
        }
        if self.objects.is_empty() {
            return Err(("eval.objects", "name at least one object set".into()));
        }
        if let Some(s) = self.objects.iter().find(|s| s.trim().is_empty()) {
            return Err(("eval.objects", format!("'{s}' is not an object set")));
        }
        if let Some(s) = crate::util::seq::first_repeat(&self.objects) {
            return Err(("eval.objects", format!("'{s}' is listed twice")));
        }
        if self.trials > crate::eval::MAX_TRIALS {
            return Err((
                "eval.trials",
                format!(
                    "{} must be in 0..={} (trials per object and run; 0: no evaluation)",
                    self.trials,
                    crate::eval::MAX_TRIALS
                ),
            ));
        }
        Ok(())
    }

    /// The conditions file's settings, read relative to the grid file `grid`.
    pub fn conditions(&self, grid: &Path) -> Result<Option<EvalConditions>, ExperimentError> {
        let Some(p) = &self.perturb else {
            return Ok(None);
        };
        let path = grid.parent().unwrap_or(Path::new(".")).join(p);
        EvalConditions::load(&path)
            .map(Some)
            .map_err(|e| ExperimentError::Value {
                path: grid.to_path_buf(),
                field: "eval.perturb".into(),
                message: e.to_string(),
            })
    }
}

/// The cache file of set number `k` of the `[eval]` objects in run folder `dir`.
pub fn eval_file(dir: &Path, k: usize, objects: &str) -> PathBuf {
    if k == 0 {
        return dir.join(EVAL_FILE);
    }
    let slug: String = objects
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    dir.join(format!("eval_{slug}.json"))
}

/// A run's evaluation on one object set (cached in the run folder).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunEval {
    /// Objects evaluated on.
    pub objects: String,
    /// Trials per object.
    pub trials: usize,
    /// Start-pose difficulty.
    pub difficulty: f64,
    /// Transitions of the evaluated checkpoint.
    pub transitions: u64,
    /// Mean success over objects.
    pub success: f64,
    /// The trials' seed (`grasp --seed`), common to every run of the grid.
    #[serde(default)]
    pub seed: u64,
    /// Sampled actions instead of the mode.
    #[serde(default)]
    pub stochastic: bool,
    /// Where the hands started.
    #[serde(default)]
    pub pregrasp: EvalPlacement,
    /// The perturbed conditions, when any.
    #[serde(default)]
    pub conditions: Option<EvalConditions>,
    /// The objects' names, in order.
    #[serde(default)]
    pub names: Vec<String>,
    /// Per object, each trial's outcome.
    #[serde(default)]
    pub outcomes: Vec<Vec<bool>>,
}

impl RunEval {
    /// Whether this cached evaluation answers `e`'s set `objects` for a checkpoint of
    /// `transitions` with trials seeded by `seed`.
    fn matches(
        &self,
        e: &EvalSettings,
        objects: &str,
        conditions: &Option<EvalConditions>,
        transitions: u64,
        seed: u64,
    ) -> bool {
        self.objects == objects
            && self.trials == e.trials
            && self.difficulty == e.difficulty
            && self.transitions == transitions
            && self.seed == seed
            && self.stochastic == e.stochastic
            && self.pregrasp == e.pregrasp
            && &self.conditions == conditions
            && !self.outcomes.is_empty()
    }
}

/// The cached evaluation of set `k` of finished run `r`, when it answers the grid's
/// current settings (`conditions` read from its `perturb` file) for the run's final
/// checkpoint.
pub fn cached_eval(
    plan: &Plan,
    r: &PlannedRun,
    k: usize,
    conditions: &Option<EvalConditions>,
) -> Option<RunEval> {
    let e = plan.grid.eval.as_ref()?;
    let objects = e.objects.get(k)?;
    let Ok(RunState::Done(rec)) = run_state(&r.dir) else {
        return None;
    };
    let text = crate::util::fsx::read_to_string_bounded(
        &eval_file(&r.dir, k, objects),
        crate::util::fsx::limits::DATA,
    )
    .ok()?;
    let c: RunEval = serde_json::from_str(&text).ok()?;
    c.matches(e, objects, conditions, rec.transitions, c.seed)
        .then_some(c)
}

/// Evaluates the latest checkpoint of every finished run on each of the grid's `[eval]`
/// object sets (cached, see the module docs). `threads` workers; `seed` seeds the trials
/// (common to all runs).
pub fn evaluate_runs(
    plan: &Plan,
    threads: usize,
    seed: u64,
    log: &(dyn Fn(&str) + Sync),
) -> Result<(), ExperimentError> {
    let Some(e) = plan.grid.eval.as_ref().filter(|e| e.trials > 0) else {
        return Ok(());
    };
    let conditions = e.conditions(&plan.path)?;
    let robot = Robot::builtin(Side::Left);
    for (k, set) in e.objects.iter().enumerate() {
        let objects =
            crate::train::objects::object_set(set).map_err(|message| ExperimentError::Value {
                path: plan.path.clone(),
                field: "eval.objects".into(),
                message,
            })?;
        let names: Vec<String> = objects.iter().map(|o| o.0.clone()).collect();
        for r in &plan.runs {
            let RunState::Done(rec) = run_state(&r.dir)? else {
                continue;
            };
            let cache = eval_file(&r.dir, k, set);
            let cached =
                crate::util::fsx::read_to_string_bounded(&cache, crate::util::fsx::limits::DATA)
                    .ok()
                    .and_then(|t| serde_json::from_str::<RunEval>(&t).ok());
            if cached.is_some_and(|c| c.matches(e, set, &conditions, rec.transitions, seed)) {
                continue;
            }
            let ck = latest_dir(&r.dir);
            let eval_err = |source: crate::eval::EvalError| ExperimentError::Eval {
                dir: r.dir.clone(),
                source,
            };
            let mut agent = TrainedAgent::load(&ck).map_err(|e| eval_err(e.into()))?;
            if !agent.has_config() {
                return Err(io_err(&ck.join(files::CONFIG), "missing"));
            }
            // The physics the run was trained in, as its checkpoint records it.
            let sim = agent.trained_sim().map_err(|e| {
                io_err(
                    agent.trained_sim_path().flatten().unwrap_or(Path::new("")),
                    e,
                )
            })?;
            agent.at_difficulty(e.difficulty);
            if let Some(c) = &conditions {
                c.apply(&mut agent.env);
            }
            let make_env = |o: usize| {
                let env = agent.environment(&robot, objects[o].clone(), sim.clone())?;
                Ok(match e.pregrasp {
                    EvalPlacement::TopDown => env,
                    EvalPlacement::Antipodal => {
                        env.with_pregrasp(Box::new(AntipodalPregrasp::default()))
                    }
                })
            };
            log(&format!(
                "evaluating {} seed {} on {set} x {} trials",
                rec.variant, r.seed, e.trials
            ));
            let res = evaluate(
                &names,
                &TrialPlan::once(e.trials, seed),
                threads,
                &make_env,
                EvalAgent {
                    spec: &AgentSpec::learned(ck.clone(), e.stochastic),
                    network: Some(agent.network()),
                },
                None,
            )
            .map_err(eval_err)?;
            let out = RunEval {
                objects: set.clone(),
                trials: e.trials,
                difficulty: e.difficulty,
                transitions: rec.transitions,
                success: res.mean_rate,
                seed,
                stochastic: e.stochastic,
                pregrasp: e.pregrasp,
                conditions: conditions.clone(),
                names: names.clone(),
                outcomes: res.objects.iter().map(|o| o.outcomes.clone()).collect(),
            };
            let json = serde_json::to_string_pretty(&out).map_err(|e| io_err(&cache, e))?;
            write_atomic(&cache, json.as_bytes()).map_err(|e| io_err(&cache, e))?;
        }
    }
    Ok(())
}

/// A variant's evaluated runs on one set: ((run seed, trials' seed), every trial's outcome).
type SeedOutcomes = Vec<((u64, u64), Vec<bool>)>;

/// One variant's pooled evaluation on one set within an ablation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PooledRow {
    /// Variant name.
    pub variant: String,
    /// The paper's name of the setting.
    pub label: String,
    /// Runs evaluated.
    pub runs: usize,
    /// Successful trials over all its evaluated runs.
    pub successes: usize,
    /// Trials over all its evaluated runs.
    pub trials: usize,
    /// Wilson 95 % interval of the pooled success.
    pub ci95: (f64, f64),
    /// Against the ablation's reference, pooled over the seeds both have: trials only this
    /// variant won, trials only the reference won, exact McNemar p. `None` for the
    /// reference itself or without common seeds.
    pub vs_reference: Option<(usize, usize, f64)>,
}

impl PooledRow {
    /// Pooled success rate.
    pub fn rate(&self) -> f64 {
        self.successes as f64 / self.trials.max(1) as f64
    }
}

/// One ablation's pooled evaluation on one set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PooledSet {
    /// Ablation name.
    pub ablation: String,
    /// Object set.
    pub objects: String,
    /// The reference variant's name.
    pub reference: String,
    /// Per variant of the ablation.
    pub rows: Vec<PooledRow>,
}

/// Per ablation and set, the pooled success of each variant and its paired comparison with
/// the ablation's reference (its `reference` config, else its first), from the cached
/// evaluations made in `conditions` (the grid's `perturb` file, as [`super::summarize`] read it).
pub fn pooled(plan: &Plan, conditions: &Option<EvalConditions>) -> Vec<PooledSet> {
    let Some(e) = plan.grid.eval.as_ref().filter(|e| e.trials > 0) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for ((a, members), &reference) in plan
        .grid
        .ablation
        .iter()
        .zip(&plan.ablations)
        .zip(&plan.references)
    {
        for k in 0..e.objects.len() {
            // Per member: ((run seed, trials' seed), outcomes of every trial).
            let evals: Vec<SeedOutcomes> = members
                .iter()
                .map(|&i| {
                    plan.runs
                        .iter()
                        .filter(|r| r.variant == i)
                        .filter_map(|r| {
                            cached_eval(plan, r, k, conditions)
                                .map(|c| ((r.seed, c.seed), c.outcomes.concat()))
                        })
                        .collect()
                })
                .collect();
            let ref_pos = members.iter().position(|&i| i == reference).unwrap_or(0);
            let rows = members
                .iter()
                .zip(&evals)
                .enumerate()
                .map(|(m, (&i, mine))| {
                    let successes = mine.iter().flat_map(|x| &x.1).filter(|&&b| b).count();
                    let trials = mine.iter().map(|x| x.1.len()).sum();
                    let vs_reference = (m != ref_pos)
                        .then(|| paired_over_seeds(mine, &evals[ref_pos]))
                        .flatten();
                    PooledRow {
                        variant: plan.variants[i].name.clone(),
                        label: plan.variants[i].label.clone(),
                        runs: mine.len(),
                        successes,
                        trials,
                        ci95: wilson(successes, trials),
                        vs_reference,
                    }
                })
                .collect();
            out.push(PooledSet {
                ablation: a.name.clone(),
                objects: e.objects[k].clone(),
                reference: plan.variants[reference].name.clone(),
                rows,
            });
        }
    }
    out
}

/// Trials only `a` won and only `b` won over the runs both evaluated on identical trials
/// (the same key: run seed and trials' seed), with the exact McNemar p; `None` without a
/// common key.
fn paired_over_seeds<K: PartialEq>(
    a: &[(K, Vec<bool>)],
    b: &[(K, Vec<bool>)],
) -> Option<(usize, usize, f64)> {
    let (mut only_a, mut only_b, mut common) = (0, 0, 0);
    for (key, x) in a {
        let Some((_, y)) = b.iter().find(|(k, y)| k == key && y.len() == x.len()) else {
            continue;
        };
        common += 1;
        for (&p, &q) in x.iter().zip(y) {
            only_a += usize::from(p && !q);
            only_b += usize::from(q && !p);
        }
    }
    (common > 0).then(|| (only_a, only_b, mcnemar_exact(only_a, only_b)))
}

/// The pooled tables as Markdown, one per ablation and set.
pub fn pooled_markdown(sets: &[PooledSet], e: &EvalSettings) -> String {
    let mut out = String::new();
    if sets.is_empty() {
        return out;
    }
    out.push_str(&format!(
        "\n## Evaluation\n\nEvery run's latest checkpoint, {} trials per object{}{}; success \
         pooled over the seeds with its Wilson 95 % interval, and each variant against the \
         ablation's reference on identical trials, pooled over the seeds (trials only the \
         variant won vs only the reference won, exact McNemar p).\n",
        e.trials,
        match e.pregrasp {
            EvalPlacement::TopDown => ", hands top-down over the object's centre",
            EvalPlacement::Antipodal => ", hands at the antipodal pre-grasp",
        },
        e.perturb
            .as_ref()
            .map(|p| format!(", perturbed as {}", p.display()))
            .unwrap_or_default(),
    ));
    for s in sets {
        out.push_str(&format!(
            "\n### {} on {} (reference {})\n\n| variant | setting | runs | success % [95 % CI] | vs reference |\n|---|---|---|---|---|\n",
            s.ablation, s.objects, s.reference
        ));
        for r in &s.rows {
            let vs = match r.vs_reference {
                None => "-".to_string(),
                Some((a, b, p)) => {
                    format!("{a} vs {b}, {}", p_text(p))
                }
            };
            let success = if r.trials == 0 {
                "-".to_string()
            } else {
                format!(
                    "{:.1} [{:.1}, {:.1}]",
                    100.0 * r.rate(),
                    100.0 * r.ci95.0,
                    100.0 * r.ci95.1
                )
            };
            out.push_str(&format!(
                "| {} | {} | {} | {success} | {vs} |\n",
                r.variant, r.label, r.runs
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_pair_trial_by_trial_and_unmatched_seeds_are_left_out() {
        let a = vec![(1, vec![true, true, false]), (2, vec![true, false])];
        let b = vec![(1, vec![true, false, false]), (3, vec![false, false])];
        // Seed 1 only: a wins trial 2, nothing else differs.
        let (wa, wb, p) = paired_over_seeds(&a, &b).unwrap();
        assert_eq!((wa, wb), (1, 0));
        assert_eq!(p, 1.0);
        assert!(paired_over_seeds(&a, &[(9, vec![true])]).is_none());
        // 10 vs 0 pooled over two seeds: p = 2 / 2^10.
        let a = vec![(1, vec![true; 6]), (2, vec![true; 4])];
        let b = vec![(1, vec![false; 6]), (2, vec![false; 4])];
        let (wa, wb, p) = paired_over_seeds(&a, &b).unwrap();
        assert_eq!((wa, wb), (10, 0));
        assert!((p - 2.0 / 1024.0).abs() < 1e-12, "{p}");
    }

    #[test]
    fn a_variant_without_evaluated_runs_shows_a_dash() {
        let e: EvalSettings = toml::from_str("objects = \"unseen\"\ntrials = 2").unwrap();
        let row = |variant: &str, successes, trials, vs| PooledRow {
            variant: variant.into(),
            label: "GRU-M3PCA5".into(),
            runs: usize::from(trials > 0),
            successes,
            trials,
            ci95: wilson(successes, trials),
            vs_reference: vs,
        };
        let md = pooled_markdown(
            &[PooledSet {
                ablation: "a".into(),
                objects: "unseen".into(),
                reference: "r".into(),
                rows: vec![row("r", 3, 4, None), row("v", 0, 0, None)],
            }],
            &e,
        );
        assert!(md.contains("| r | GRU-M3PCA5 | 1 | 75.0 ["), "{md}");
        assert!(md.contains("| v | GRU-M3PCA5 | 0 | - | - |"), "{md}");
    }

    #[test]
    fn a_bad_perturb_file_names_the_grid_field_and_file() {
        let dir = tempfile::tempdir().unwrap();
        let grid = dir.path().join("g.toml");
        let e: EvalSettings =
            toml::from_str("objects = \"unseen\"\ntrials = 1\nperturb = \"c.toml\"").unwrap();
        let err = e.conditions(&grid).unwrap_err().to_string();
        assert!(
            err.contains("eval.perturb") && err.contains("c.toml"),
            "{err}"
        );
        std::fs::write(dir.path().join("c.toml"), "[placement]\noffset = 0.5\n").unwrap();
        let err = e.conditions(&grid).unwrap_err().to_string();
        assert!(err.contains("placement.offset"), "{err}");
        std::fs::write(dir.path().join("c.toml"), "[placement]\noffset = 0.01\n").unwrap();
        assert_eq!(e.conditions(&grid).unwrap().unwrap().placement.offset, 0.01);
    }

    #[test]
    fn one_set_or_many_and_cache_files() {
        let one: EvalSettings = toml::from_str("objects = \"unseen\"\ntrials = 2").unwrap();
        assert_eq!(one.objects, ["unseen"]);
        assert_eq!(one.pregrasp, EvalPlacement::TopDown);
        let many: EvalSettings = toml::from_str(
            "objects = [\"train\", \"assets/meshes/novel\"]\ntrials = 2\npregrasp = \"antipodal\"",
        )
        .unwrap();
        assert_eq!(many.objects, ["train", "assets/meshes/novel"]);
        assert_eq!(many.pregrasp, EvalPlacement::Antipodal);
        let d = Path::new("r");
        assert_eq!(eval_file(d, 0, "train"), Path::new("r/eval.json"));
        assert_eq!(
            eval_file(d, 1, "assets/meshes/novel"),
            Path::new("r/eval_assets_meshes_novel.json")
        );
        let empty: EvalSettings = toml::from_str("objects = []\ntrials = 2").unwrap();
        assert_eq!(empty.validate().unwrap_err().0, "eval.objects");
        assert!(
            toml::from_str::<EvalSettings>("objects = \"u\"\ntrials = 1\npregrasp = \"x\"")
                .is_err()
        );
    }
}
