//! One trial of an evaluation: an agent's episode on the trial's scene, and with
//! `attempts > 1` the attempts after a failed lift ([`GraspEnv::prepare_retry`]): the
//! object where the failed attempt left it, the placement planned again on it.

use super::record::{self, RecordOptions, RecordingEntry};
use super::{EvalError, PolicyAgent};
use crate::env::grasp::{run_episode, EpisodeSummary, GraspEnv, NoRetry};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The trials of an evaluation: how many per object, the seed of their scenes and the
/// attempts each may take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrialPlan {
    /// Trials per object.
    pub trials: usize,
    /// The seed of the trials' scenes (`grasp --seed`).
    pub seed: u64,
    /// Attempts per trial (1: the paper's protocol, one lift per trial).
    pub attempts: usize,
}

impl TrialPlan {
    /// `trials` trials of one attempt each (the paper's protocol).
    pub fn once(trials: usize, seed: u64) -> TrialPlan {
        TrialPlan {
            trials,
            seed,
            attempts: 1,
        }
    }
}

/// The seed of attempt `attempt` (0 = the first) of the trial whose scene is `seed`: the
/// first attempt is the trial's scene itself, so one attempt is exactly the paper's trial.
pub fn attempt_seed(seed: u64, attempt: usize) -> u64 {
    if attempt == 0 {
        seed
    } else {
        crate::env::api::episode_seed(seed, attempt, 0x0072_6574_7279)
    }
}

/// How an agent's trials used their attempts (`grasp eval --attempts N` with N > 1).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RetryStats {
    /// Attempts allowed per trial.
    pub attempts: usize,
    /// Trials won at the first attempt (the one-attempt protocol's successes).
    pub first_attempt_successes: usize,
    /// Trials that took more than one attempt.
    pub retried: usize,
    /// Trials won at a later attempt.
    pub won_on_retry: usize,
    /// Failed attempts after which the trial got no further one, by reason
    /// (`not_at_rest`, `off_table`, `physics_failure`); attempts used up are not counted.
    pub not_retried: BTreeMap<String, usize>,
}

impl RetryStats {
    /// The statistics of `trials` with `attempts` allowed each.
    pub fn of(attempts: usize, trials: &[&TrialOutcome]) -> RetryStats {
        let mut s = RetryStats {
            attempts,
            ..RetryStats::default()
        };
        for t in trials {
            let won = t.summary.success;
            s.first_attempt_successes += usize::from(won && t.attempts == 1);
            s.retried += usize::from(t.attempts > 1);
            s.won_on_retry += usize::from(won && t.attempts > 1);
            if let Some(r) = t.stopped {
                *s.not_retried.entry(r.name().to_string()).or_default() += 1;
            }
        }
        s
    }
}

/// A trial's result.
#[derive(Debug, Clone)]
pub struct TrialOutcome {
    /// The trial as one episode: the last attempt's summary (its success is the trial's),
    /// with the control steps and returns of every attempt summed and the deepest contact
    /// of any attempt.
    pub summary: EpisodeSummary,
    /// Attempts made.
    pub attempts: usize,
    /// Why a failed trial stopped before its last allowed attempt.
    pub stopped: Option<NoRetry>,
    /// The attempts' recordings, when recording.
    pub recordings: Vec<RecordingEntry>,
    /// Recordings that could not be written (a full disk): the evaluation goes on, and
    /// the caller reports them after the results.
    pub record_errors: Vec<String>,
}

/// `first` followed by `next`: `next`'s summary with both attempts' steps and returns
/// summed and the deeper of their deepest contacts.
pub fn then(first: &EpisodeSummary, next: EpisodeSummary) -> EpisodeSummary {
    let deeper = first.deepest_contact > next.deepest_contact;
    EpisodeSummary {
        steps: first.steps + next.steps,
        episode_return: first.episode_return + next.episode_return,
        deepest_contact: first.deepest_contact.max(next.deepest_contact),
        deepest_contact_with: if deeper {
            first.deepest_contact_with.clone()
        } else {
            next.deepest_contact_with.clone()
        },
        ..next
    }
}

/// Who acts in a trial: a scripted baseline (`true`: baseline 2, stopping fingers at
/// touch) or a learned policy.
pub enum Actor<'a> {
    /// Baseline 1 (`false`) or 2 (`true`).
    Baseline(bool),
    /// A learned policy.
    Policy(&'a mut PolicyAgent),
}

/// Runs trial `trial` (scene `seed`) of `actor` on `env` with up to `attempts` attempts,
/// recording every attempt under the agent name `label` with `record` (the first as
/// `<trial>`, later ones as `<trial>_attempt<k>`, see [`record::write_recording`]).
pub fn run_trial(
    env: &mut GraspEnv,
    actor: &mut Actor,
    (seed, trial, attempts): (u64, usize, usize),
    record: Option<(&RecordOptions, &str)>,
) -> Result<TrialOutcome, EvalError> {
    let mut out: Option<TrialOutcome> = None;
    let mut record_errors = Vec::new();
    for k in 0..attempts.max(1) {
        if let Some(o) = out.as_mut() {
            if o.summary.success {
                break;
            }
            if let Err(reason) = env.prepare_retry() {
                o.stopped = Some(reason);
                break;
            }
        }
        let s = attempt_seed(seed, k);
        let (summary, entry) = match record {
            Some((r, label)) => {
                let rec = match actor {
                    Actor::Baseline(stop) => {
                        record::record_baseline_episode(env, *stop, label, s, r.every)?
                    }
                    Actor::Policy(a) => record::record_agent_episode(env, *a, label, s, r.every),
                };
                let keep = !r.only_failures || rec.summary.physics_failure;
                let entry = if keep {
                    match record::write_recording(&r.dir, &rec, trial, k) {
                        Ok(e) => Some(e),
                        Err(e) => {
                            record_errors.push(e.to_string());
                            None
                        }
                    }
                } else {
                    None
                };
                (rec.summary, entry)
            }
            None => (
                match actor {
                    Actor::Baseline(stop) => env.run_baseline(*stop, s)?,
                    Actor::Policy(a) => run_episode(env, *a, s),
                },
                None,
            ),
        };
        match out.as_mut() {
            None => {
                out = Some(TrialOutcome {
                    summary,
                    attempts: 1,
                    stopped: None,
                    recordings: entry.into_iter().collect(),
                    record_errors: Vec::new(),
                })
            }
            Some(o) => {
                o.summary = then(&o.summary, summary);
                o.attempts += 1;
                o.recordings.extend(entry);
            }
        }
    }
    let mut out = out.unwrap_or_else(|| unreachable!("at least one attempt runs"));
    out.record_errors = record_errors;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(success: bool, steps: usize, depth: f64, with: &str) -> EpisodeSummary {
        EpisodeSummary {
            object: "box".into(),
            success,
            steps,
            episode_return: steps as f64 * 0.5,
            lifted: true,
            physics_failure: false,
            failure: None,
            deepest_contact: depth,
            deepest_contact_with: Some(with.into()),
            touched_in_stage1: true,
            thumb_contact_at_lift: success,
            grip_effort: 1.0,
            object_height: if success { 0.12 } else { 0.0 },
            in_hand: success,
            object_turn: 0.1,
        }
    }

    #[test]
    fn a_retried_trial_sums_steps_and_keeps_the_deeper_contact() {
        let a = summary(false, 3, 0.004, "lh_thdistal");
        let b = summary(true, 5, 0.001, "table");
        let t = then(&a, b);
        assert!(t.success);
        assert_eq!(t.steps, 8);
        assert!((t.episode_return - 4.0).abs() < 1e-12);
        assert_eq!(t.deepest_contact, 0.004);
        assert_eq!(t.deepest_contact_with.as_deref(), Some("lh_thdistal"));
    }

    #[test]
    fn the_first_attempt_is_the_trial_scene() {
        assert_eq!(attempt_seed(42, 0), 42);
        assert_ne!(attempt_seed(42, 1), 42);
        assert_ne!(attempt_seed(42, 1), attempt_seed(42, 2));
    }

    #[test]
    fn retry_stats_count_first_and_later_wins() {
        let t = |won: bool, attempts: usize, stopped: Option<NoRetry>| TrialOutcome {
            summary: summary(won, 1, 0.0, "table"),
            attempts,
            stopped,
            recordings: Vec::new(),
            record_errors: Vec::new(),
        };
        let trials = [
            t(true, 1, None),
            t(true, 2, None),
            t(false, 2, None),
            t(false, 1, Some(NoRetry::NotAtRest)),
        ];
        let s = RetryStats::of(2, &trials.iter().collect::<Vec<_>>());
        assert_eq!(s.first_attempt_successes, 1);
        assert_eq!(s.retried, 2);
        assert_eq!(s.won_on_retry, 1);
        assert_eq!(s.not_retried.get("not_at_rest"), Some(&1));
        assert_eq!(s.not_retried.len(), 1);
    }
}
