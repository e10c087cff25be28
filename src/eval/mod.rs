//! Evaluation: per-object success rates of learned and scripted agents on identical
//! initial poses (common random numbers), with Wilson 95 % confidence intervals, in the
//! layout of the paper's Table I.
//!
//! - [`evaluate`]: one agent on every object of a set, trials seeded per (object, trial);
//! - [`TrainedAgent`](crate::checkpoint::TrainedAgent): a checkpoint loaded with the
//!   environment it was trained in (the `config.toml` saved beside it), so evaluations
//!   observe what the policy expects;
//! - [`paired`](mod@paired): two agents compared trial by trial (exact McNemar test);
//! - [`record`]: episode recordings (JSON and a self-contained 3D replay page);
//! - [`plot`]: Table I as a picture, per-object success of the agents side by side;
//! - [`read_results`]: the results of an earlier `grasp eval --json`, to print or plot again;
//! - [`pool`](mod@pool): several such files (seeds of scenes) read as one evaluation;
//! - [`regression`]: the CI regression check against committed reference figures.
//!
//! The learned agent ([`PolicyAgent`], [`AgentSpec`]) is in `agent.rs`, the result types
//! and their statistics ([`AgentResult`], [`read_results`], ...) in `results.rs`, the
//! tables in `tables.rs`; all re-exported here.

pub mod conditions;
pub mod paired;
pub mod physics;
pub mod plot;
pub mod pool;
pub mod rank;
pub mod record;
pub mod regression;
pub mod request;
pub mod rollout;
pub mod trial;

mod agent;
mod results;
mod tables;

pub use agent::{policy_step, AgentSpec, EvalAgent, PolicyAgent};
pub use paired::{paired, paired_lines, paired_with_first, unpaired_lines, Paired};
pub use results::{
    over_1cm_by_body, physics_line, read_results, saved_agent_name, select_agents, AgentResult,
    ContactStats, LiftStats, ObjectResult, PregraspStats, RankStats, TrialFailure,
};
pub use tables::{csv_table, markdown_table, text_table};

use crate::env::grasp::{EpisodeSummary, GraspEnv, GraspEnvError};
pub use rank::{CountedPregrasp, RankedPregrasp};
use rayon::prelude::*;
use record::RecordOptions;
use results::failure_counts;
use std::path::PathBuf;
pub use trial::TrialOutcome;
use trial::{run_trial, Actor};
pub use trial::{RetryStats, TrialPlan};

/// Most trials per object an evaluation runs (`grasp eval --trials`, a grid's `[eval]
/// trials`): each is a simulated episode per agent.
pub const MAX_TRIALS: usize = 10_000;

/// Most attempts per trial (`grasp eval --attempts`, `grasp run --attempts`).
pub const MAX_ATTEMPTS: usize = 10;

/// Checks an `--attempts` flag: 1..=[`MAX_ATTEMPTS`]; `what` says what one attempt is.
pub fn check_attempts(n: usize, what: &str) -> Result<(), String> {
    if n == 0 || n > MAX_ATTEMPTS {
        return Err(format!(
            "--attempts {n} must be in 1..={MAX_ATTEMPTS} ({what})"
        ));
    }
    Ok(())
}

/// Wilson score interval for `k` successes in `n` trials at 95 % (z = 1.96): (low, high).
/// `n = 0` gives (0, 1).
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054_f64;
    let n = n as f64;
    let p = k as f64 / n;
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z * ((p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt()) / denom;
    // At k = 0 (k = n) the bound is 0 (1) exactly; the formula leaves round-off there
    // (5.55e-17).
    let low = if k == 0 {
        0.0
    } else {
        (centre - half).max(0.0)
    };
    let high = if k as f64 == n {
        1.0
    } else {
        (centre + half).min(1.0)
    };
    (low, high)
}
/// Seed of trial `trial` on the object named `object`: shared by all agents (common
/// random numbers), and keyed by the object's name rather than its place in the list, so
/// a trial has the same start pose in any object list or set that contains the object.
pub fn trial_seed(seed: u64, object: &str, trial: usize) -> u64 {
    let mut h = crate::util::hash::Fnv128::new();
    h.write(object.as_bytes());
    let key = h.finish();
    crate::env::api::episode_seed(seed, (key ^ (key >> 64)) as u64 as usize, trial as u64)
}

/// Evaluates `agent` on every object of `make_env`'s set for `plan.trials` trials each
/// (scenes seeded by `plan.seed`, up to `plan.attempts` attempts each: [`trial`]), in a
/// pool of `threads` workers. `make_env(o)` builds an environment whose object set is
/// the single object `o` (so the scene of a trial depends only on its seed). With
/// `record`, every episode is also written as a recording ([`record::write_recording`]);
/// recording changes no outcome.
pub fn evaluate(
    names: &[String],
    plan: &TrialPlan,
    threads: usize,
    make_env: &(dyn Fn(usize) -> Result<GraspEnv, GraspEnvError> + Sync),
    agent: EvalAgent<'_>,
    record: Option<&RecordOptions>,
) -> Result<AgentResult, EvalError> {
    evaluate_until(names, plan, threads, make_env, agent, record, None)
}

/// [`evaluate`] that stops starting trials once `stop` is set (a signal): the trials in
/// progress finish, the result holds the finished trials of the objects that have any
/// and is marked `interrupted`. A recording that cannot be written (a full disk) does not
/// stop the evaluation: its error is kept in `record_errors`.
pub fn evaluate_until(
    names: &[String],
    plan: &TrialPlan,
    threads: usize,
    make_env: &(dyn Fn(usize) -> Result<GraspEnv, GraspEnvError> + Sync),
    agent: EvalAgent<'_>,
    record: Option<&RecordOptions>,
    stop: Option<&std::sync::atomic::AtomicBool>,
) -> Result<AgentResult, EvalError> {
    let EvalAgent { spec, network } = agent;
    let stopped = || crate::util::signal::is_set(stop);
    let TrialPlan {
        trials,
        seed,
        attempts,
    } = *plan;
    let start = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| EvalError::Agent(e.to_string()))?;
    let label = spec.label();
    // The name in recordings: the user's label for the agent, when given.
    let rec_label = record
        .and_then(|r| r.name.clone())
        .unwrap_or_else(|| label.clone());
    let per_object: Vec<Vec<TrialOutcome>> = pool.install(|| {
        (0..names.len())
            .into_par_iter()
            .map(|o| -> Result<Vec<TrialOutcome>, EvalError> {
                if stopped() {
                    return Ok(Vec::new());
                }
                let mut env = make_env(o)?;
                let mut agent: Option<PolicyAgent> = match spec.checkpoint() {
                    Some(dir) => Some(PolicyAgent::new(
                        network.cloned().ok_or_else(|| {
                            EvalError::Agent(format!(
                                "{}: a checkpoint agent is evaluated with its loaded network",
                                dir.display()
                            ))
                        })?,
                        matches!(spec, AgentSpec::Sampled(_)),
                        // A stream of its own per object, apart from every trial's seed.
                        trial_seed(seed, &names[o], trials),
                    )),
                    None => None,
                };
                let mut actor = match (spec, agent.as_mut()) {
                    (AgentSpec::Baseline1, _) => Actor::Baseline(false),
                    (AgentSpec::Baseline2, _) => Actor::Baseline(true),
                    (_, Some(a)) => Actor::Policy(a),
                    (_, None) => unreachable!("a checkpoint agent is built above"),
                };
                let mut done = Vec::with_capacity(trials);
                for t in 0..trials {
                    if stopped() {
                        break;
                    }
                    let s = trial_seed(seed, &names[o], t);
                    let rec = record.map(|r| (r, rec_label.as_str()));
                    done.push(run_trial(&mut env, &mut actor, (s, t, attempts), rec)?);
                }
                Ok(done)
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    let wall_s = start.elapsed().as_secs_f64();
    Ok(aggregate(label, names, per_object, plan, wall_s))
}

/// The result of agent `label` from its trials `per_object` (one list per object of
/// `names`, in trial order; an object with none is left out, and fewer than
/// `plan.trials` anywhere marks the result interrupted), as [`evaluate`] reports it:
/// per-object counts, Wilson intervals, physics failures, contact and lift statistics.
/// Shared with the table of `grasp run --objects`.
pub fn aggregate(
    label: String,
    names: &[String],
    per_object: Vec<Vec<TrialOutcome>>,
    plan: &TrialPlan,
    wall_s: f64,
) -> AgentResult {
    let TrialPlan {
        trials,
        seed,
        attempts,
    } = *plan;
    let interrupted = per_object.iter().any(|t| t.len() < trials);
    // An object none of whose trials finished is left out (no rate to give).
    let (names, per_object): (Vec<&String>, Vec<Vec<TrialOutcome>>) = names
        .iter()
        .zip(per_object)
        .filter(|(_, t)| !t.is_empty())
        .unzip();
    let record_errors: Vec<String> = per_object
        .iter()
        .flatten()
        .flat_map(|t| t.record_errors.iter().cloned())
        .collect();
    let mut objects = Vec::new();
    let mut recordings = Vec::new();
    let lifts = LiftStats::of(per_object.iter().flatten().map(|t| &t.summary));
    let retries = (attempts > 1)
        .then(|| RetryStats::of(attempts, &per_object.iter().flatten().collect::<Vec<_>>()));
    let (mut k_all, mut n_all, mut steps_all) = (0, 0, 0usize);
    for (name, trials) in names.into_iter().zip(per_object) {
        let eps: Vec<&EpisodeSummary> = trials.iter().map(|t| &t.summary).collect();
        let k = eps.iter().filter(|e| e.success).count();
        let n = eps.len();
        let steps: usize = eps.iter().map(|e| e.steps).sum();
        k_all += k;
        n_all += n;
        steps_all += steps;
        objects.push(ObjectResult {
            object: name.clone(),
            trials: n,
            successes: k,
            rate: k as f64 / n.max(1) as f64,
            ci95: wilson(k, n),
            mean_steps: steps as f64 / n.max(1) as f64,
            physics_failures: eps.iter().filter(|e| e.physics_failure).count(),
            outcomes: eps.iter().map(|e| e.success).collect(),
            deepest_contacts: eps.iter().map(|e| e.deepest_contact).collect(),
            deepest_contacts_with: eps
                .iter()
                .map(|e| e.deepest_contact_with.clone().unwrap_or_default())
                .collect(),
            failures: eps
                .iter()
                .enumerate()
                .filter(|(_, e)| e.physics_failure)
                .map(|(trial, e)| TrialFailure {
                    trial,
                    report: e.failure.clone(),
                })
                .collect(),
            attempts: if attempts > 1 {
                trials.iter().map(|t| t.attempts).collect()
            } else {
                Vec::new()
            },
            failed_in_hand: eps.iter().filter(|e| e.failed_in_hand()).count(),
            failed_out_of_hand: eps.iter().filter(|e| e.failed_out_of_hand()).count(),
            lift_heights: eps.iter().map(|e| e.object_height).collect(),
            lift_turns: eps.iter().map(|e| e.object_turn).collect(),
        });
        recordings.extend(trials.into_iter().flat_map(|t| t.recordings));
    }
    let mean_rate = objects.iter().map(|o| o.rate).sum::<f64>() / objects.len().max(1) as f64;
    let physics_failures = objects.iter().map(|o| o.physics_failures).sum();
    let (failures_by_kind, penetrations_by_body) = failure_counts(&objects);
    let depths: Vec<f64> = objects
        .iter()
        .flat_map(|o| o.deepest_contacts.iter().copied())
        .collect();
    if physics_failures > 0 {
        tracing::warn!(
            "{label}: {physics_failures} of {n_all} episodes ended in a physics failure (a \
             simulator error or panic; counted as failed trials)"
        );
    }
    AgentResult {
        physics_failures,
        failures_by_kind,
        penetrations_by_body,
        deepest_contact: ContactStats::of(&depths),
        over_1cm_by_body: over_1cm_by_body(&objects),
        lifts,
        agent: label,
        mean_rate,
        ci95: wilson(k_all, n_all),
        mean_steps: steps_all as f64 / n_all.max(1) as f64,
        control_steps_per_s: steps_all as f64 / wall_s.max(1e-9),
        wall_s,
        pregrasp: None,
        conditions: None,
        retries,
        seed: Some(seed),
        objects,
        recordings,
        interrupted,
        record_errors,
    }
}

impl From<crate::checkpoint::CheckpointError> for EvalError {
    fn from(e: crate::checkpoint::CheckpointError) -> Self {
        EvalError::Checkpoint {
            path: e.path,
            message: e.message,
        }
    }
}

/// Errors of an evaluation.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The environment could not be built.
    #[error(transparent)]
    Env(#[from] GraspEnvError),
    /// The simulator refused a scene.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// The agent could not be loaded or run.
    #[error("agent: {0}")]
    Agent(String),
    /// The agents cannot be evaluated in one physics ([`physics::common_sim_config`]).
    #[error("{0}")]
    Physics(String),
    /// A checkpoint's saved setup is unreadable or does not fit the request.
    #[error("checkpoint {path}: {message}")]
    Checkpoint {
        /// The file (config.toml or synergy.json).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A recording could not be written.
    #[error(transparent)]
    Record(#[from] record::RecordError),
    /// The per-object plot could not be drawn or written.
    #[error("plot {path}: {message}")]
    Plot {
        /// The SVG file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Saved results (`grasp eval --json`) could not be read.
    #[error("results {path}: {message}")]
    Results {
        /// The JSON file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_hand_computed() {
        // k = 8, n = 10: p = 0.8, z^2 = 3.8415; centre = (0.8 + 0.19207) / 1.38415 =
        // 0.71673; half = 1.96 sqrt(0.016 + 0.0096037) / 1.38415 = 0.22658.
        let (lo, hi) = wilson(8, 10);
        assert!((lo - 0.4902).abs() < 1e-3, "{lo}");
        assert!((hi - 0.9433).abs() < 1e-3, "{hi}");
        let (lo, hi) = wilson(0, 10);
        assert!(lo == 0.0 && (hi - 0.2775).abs() < 1e-3, "{hi}");
        assert_eq!(wilson(0, 0), (0.0, 1.0));
        let (lo, hi) = wilson(10, 10);
        assert!((lo - 0.7225).abs() < 1e-3 && (hi - 1.0).abs() < 1e-12);
        // The bounds at no and at every success are exact, not round-off (5.55e-17).
        for n in 1..=300 {
            assert_eq!(wilson(0, n).0, 0.0, "n = {n}");
            assert_eq!(wilson(n, n).1, 1.0, "n = {n}");
        }
    }
    #[test]
    fn trial_seeds_follow_the_object_name_not_its_place() {
        assert_eq!(trial_seed(4, "apple", 2), trial_seed(4, "apple", 2));
        assert_ne!(trial_seed(4, "apple", 2), trial_seed(4, "can_soup", 2));
        assert_ne!(trial_seed(4, "apple", 2), trial_seed(4, "apple", 3));
        assert_ne!(trial_seed(4, "apple", 2), trial_seed(5, "apple", 2));
    }
}
