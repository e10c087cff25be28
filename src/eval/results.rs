//! What an evaluation yields: per-object and per-agent results ([`AgentResult`]), the
//! statistics over their episodes (contacts, lifts, physics failures, pre-grasps), and
//! [`read_results`], which reads the results of an earlier `grasp eval --json` back.

use super::conditions;
use super::record::RecordingEntry;
use super::{wilson, EvalError, RetryStats};
use crate::env::grasp::EpisodeSummary;
use crate::sim::{FailureReport, PhysicsFailure};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Per-object result of one agent.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ObjectResult {
    /// Object name.
    pub object: String,
    /// Trials run.
    pub trials: usize,
    /// Successful trials.
    pub successes: usize,
    /// Success rate.
    pub rate: f64,
    /// Wilson 95 % interval (low, high).
    pub ci95: (f64, f64),
    /// Mean stage-2 control steps per episode.
    pub mean_steps: f64,
    /// Episodes that ended in a physics failure.
    pub physics_failures: usize,
    /// Success of each trial, in trial order (trial `t` is the same scene for every agent).
    pub outcomes: Vec<bool>,
    /// Each trial's deepest object contact (m; 0 when nothing penetrated), in trial order
    /// (empty in evaluations saved before it was recorded).
    #[serde(default)]
    pub deepest_contacts: Vec<f64>,
    /// What the object touched in each trial's deepest contact (a hand link or `table`;
    /// empty when nothing penetrated), in trial order (empty in evaluations saved before
    /// it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub deepest_contacts_with: Vec<String>,
    /// The physics failures, each with its trial, kind, body pair, depth and step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub failures: Vec<TrialFailure>,
    /// Attempts each trial took, in trial order (`grasp eval --attempts N`, N > 1; empty
    /// for one attempt per trial).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attempts: Vec<usize>,
    /// Failed lifts with the object still in the hand, below the success height (tipped,
    /// pivoting or slipping in the grasp), and with it out of the hand (dropped, or never
    /// picked up); see [`LiftStats`] (0 in evaluations saved before they were recorded).
    #[serde(default)]
    pub failed_in_hand: usize,
    /// See `failed_in_hand`.
    #[serde(default)]
    pub failed_out_of_hand: usize,
    /// Each trial's object height when the lift was judged: its lowest point above the
    /// table top (m; 0 where the trial did not lift), in trial order (empty in evaluations
    /// saved before it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lift_heights: Vec<f64>,
    /// How far the object turned during each trial's lift (rad; 0 where the trial did not
    /// lift), in trial order (empty in evaluations saved before it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lift_turns: Vec<f64>,
}

/// One trial's physics failure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialFailure {
    /// The trial (same scene for every agent).
    pub trial: usize,
    /// What failed and when; `None` when the simulator recorded no detail.
    #[serde(flatten)]
    pub report: Option<FailureReport>,
}

/// The deepest object contacts of an agent's episodes (m): penetrations of the object by
/// the hand or the table, below the failure threshold too.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactStats {
    /// Median over episodes of each episode's deepest contact.
    pub median: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// The deepest of all.
    pub max: f64,
    /// Episodes whose deepest contact was over 1 cm.
    pub over_1cm: usize,
    /// Share of episodes whose deepest contact was at most 1 cm.
    pub within_1cm: f64,
}

impl ContactStats {
    /// The statistics of per-episode deepest contacts `depths` (m).
    pub fn of(depths: &[f64]) -> ContactStats {
        if depths.is_empty() {
            return ContactStats::default();
        }
        let mut d = depths.to_vec();
        d.sort_by(f64::total_cmp);
        let rank = |q: f64| d[((q * d.len() as f64).ceil() as usize).clamp(1, d.len()) - 1];
        let over = d.iter().filter(|&&x| x > 0.01).count();
        ContactStats {
            median: rank(0.5),
            p99: rank(0.99),
            max: d[d.len() - 1],
            over_1cm: over,
            within_1cm: 1.0 - over as f64 / d.len() as f64,
        }
    }
}

/// The trials whose deepest contact was over 1 cm, by what the object touched
/// (`unknown` for trials saved without it).
pub fn over_1cm_by_body(objects: &[ObjectResult]) -> BTreeMap<String, usize> {
    let mut m = BTreeMap::new();
    for o in objects {
        for (t, d) in o.deepest_contacts.iter().enumerate() {
            if *d > 0.01 {
                let with = o.deepest_contacts_with.get(t).filter(|w| !w.is_empty());
                *m.entry(with.map_or("unknown".to_string(), String::clone))
                    .or_insert(0) += 1;
            }
        }
    }
    m
}

/// All results of one agent.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct AgentResult {
    /// Agent label.
    pub agent: String,
    /// Per object, in the set's order.
    pub objects: Vec<ObjectResult>,
    /// Mean success over objects.
    pub mean_rate: f64,
    /// Wilson interval over all trials.
    pub ci95: (f64, f64),
    /// Mean control steps per episode.
    pub mean_steps: f64,
    /// Control steps per wall second (stage 2 and lift steps of all episodes).
    pub control_steps_per_s: f64,
    /// Episodes that ended in a physics failure, over all objects (each one a failed
    /// trial, counted in the success rates).
    pub physics_failures: usize,
    /// The physics failures by kind (`deep_penetration`, `too_fast`, ...).
    #[serde(default)]
    pub failures_by_kind: BTreeMap<String, usize>,
    /// The deep-penetration failures by what the object touched (hand link or `table`).
    #[serde(default)]
    pub penetrations_by_body: BTreeMap<String, usize>,
    /// Each episode's deepest object contact, over all episodes.
    #[serde(default)]
    pub deepest_contact: ContactStats,
    /// The episodes whose deepest contact was over 1 cm, by what the object touched.
    #[serde(default)]
    pub over_1cm_by_body: BTreeMap<String, usize>,
    /// How the lifts were made: thumb contact and grip, over every episode that lifted.
    pub lifts: LiftStats,
    /// Wall time (s).
    pub wall_s: f64,
    /// Where the hands started when not at the default top-down placement (`grasp eval
    /// --pregrasp antipodal`); absent for the default placement and in evaluations saved
    /// before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pregrasp: Option<PregraspStats>,
    /// The seed of the trials' start poses (`grasp --seed`); absent in evaluations saved
    /// before it was recorded. Agents are paired trial by trial only on the same seed and
    /// placement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// How the trials used their attempts (`grasp eval --attempts N`, N > 1); absent for
    /// one attempt per trial. Agents are paired only on the same attempts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retries: Option<RetryStats>,
    /// The perturbed conditions every agent was evaluated in (`grasp eval --perturb`);
    /// absent for the default, unperturbed evaluation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conditions: Option<conditions::EvalConditions>,
    /// Episodes recorded (with `record`), per object then trial.
    #[serde(skip_serializing_if = "Vec::is_empty", skip_deserializing)]
    pub recordings: Vec<RecordingEntry>,
    /// Whether a signal (SIGINT, SIGTERM) stopped the evaluation before all its trials:
    /// the objects and trials are those that finished.
    #[serde(default, skip_serializing_if = "is_false")]
    pub interrupted: bool,
    /// Recordings that could not be written (with `record`), one error each; not saved.
    #[serde(skip)]
    pub record_errors: Vec<String>,
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl AgentResult {
    /// Where the agent's hands started: the pre-grasp planner's name, else `top-down`.
    pub fn placement(&self) -> String {
        self.pregrasp
            .as_ref()
            .map_or_else(|| "top-down".to_string(), |p| p.name())
    }

    /// Attempts allowed per trial (1 without `grasp eval --attempts`).
    pub fn attempts(&self) -> usize {
        self.retries.as_ref().map_or(1, |s| s.attempts)
    }
}

/// Where an agent's hands started when a pre-grasp planner placed them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PregraspStats {
    /// The planner (`antipodal`).
    pub placement: String,
    /// Episodes the planner placed.
    pub planned: usize,
    /// Episodes left at the default placement (the planner found no grasp).
    pub default_placement: usize,
    /// How a critic chose among the planner's top placements (`--rank-top`); absent when
    /// the planner's best started every episode.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ranked: Option<RankStats>,
}

/// How a critic chose the placements of an evaluation
/// ([`rank::RankedPregrasp`](super::rank::RankedPregrasp)).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RankStats {
    /// Placements compared per plan (the planner's best first).
    pub top: usize,
    /// The checkpoint whose critic ranked them.
    pub ranker: String,
    /// Plans that chose each place of the planner's order (index 0: its best).
    pub chosen: Vec<usize>,
}

impl PregraspStats {
    /// The placement as a name: the planner's, with its ranking where one chose.
    pub fn name(&self) -> String {
        match &self.ranked {
            Some(r) => format!(
                "{}, ranked by {} among the top {}",
                self.placement, r.ranker, r.top
            ),
            None => self.placement.clone(),
        }
    }
}

/// How an agent's lifts were made, over the episodes that lifted: the learned-grasp
/// diagnostics of the thumb's opposition and of the grip held through the lift.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct LiftStats {
    /// Episodes that lifted.
    pub lifted: usize,
    /// Share of those whose thumb tip touched the object when the lift began.
    pub thumb_contact_rate: f64,
    /// Mean grip through the lift (the 22 finger joints' absolute efforts summed, N m).
    pub mean_grip_effort: f64,
    /// Mean grip of the lifts that held the object, and of those that did not (N m; 0
    /// when there were none).
    pub mean_grip_held: f64,
    /// See `mean_grip_held`.
    pub mean_grip_dropped: f64,
    /// Failed lifts that ended with the object still in the hand, below the success
    /// height: tipped, pivoting or slipping in the grasp
    /// ([`EpisodeSummary::failed_in_hand`]; 0 in evaluations saved before it was recorded).
    #[serde(default)]
    pub failed_in_hand: usize,
    /// Failed lifts that ended with the object out of the hand: dropped, or never picked
    /// up ([`EpisodeSummary::failed_out_of_hand`]).
    #[serde(default)]
    pub failed_out_of_hand: usize,
    /// Median turn of the object during the lifts that held it, and during those that
    /// failed (degrees; 0 when there were none): a grasp that pins the object keeps it
    /// small, one the object tips or pivots in does not
    /// ([`EpisodeSummary::object_turn`]). Absent in evaluations saved before it was
    /// recorded, and for failed lifts in results pooled over several files
    /// ([`pool`](super::pool)), which keep no per-trial record of which trials lifted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median_turn_held_deg: Option<f64>,
    /// See `median_turn_held_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median_turn_failed_deg: Option<f64>,
}

impl LiftStats {
    /// The statistics of `episodes` (those that did not lift are left out).
    pub fn of<'a>(episodes: impl IntoIterator<Item = &'a EpisodeSummary>) -> LiftStats {
        let lifted: Vec<&EpisodeSummary> = episodes.into_iter().filter(|e| e.lifted).collect();
        let mean = |f: &dyn Fn(&EpisodeSummary) -> bool| {
            let xs: Vec<f64> = lifted
                .iter()
                .filter(|e| f(e))
                .map(|e| e.grip_effort)
                .collect();
            // An empty f64 sum is -0.0, which would print as "-0.00".
            if xs.is_empty() {
                0.0
            } else {
                xs.iter().sum::<f64>() / xs.len() as f64
            }
        };
        let median_turn = |f: &dyn Fn(&EpisodeSummary) -> bool| {
            let turns: Vec<f64> = lifted
                .iter()
                .filter(|e| f(e))
                .map(|e| e.object_turn.to_degrees())
                .collect();
            if turns.is_empty() {
                0.0
            } else {
                crate::util::stats::median(&turns)
            }
        };
        LiftStats {
            lifted: lifted.len(),
            thumb_contact_rate: lifted.iter().filter(|e| e.thumb_contact_at_lift).count() as f64
                / lifted.len().max(1) as f64,
            mean_grip_effort: mean(&|_| true),
            mean_grip_held: mean(&|e| e.success),
            mean_grip_dropped: mean(&|e| !e.success),
            failed_in_hand: lifted.iter().filter(|e| e.failed_in_hand()).count(),
            failed_out_of_hand: lifted.iter().filter(|e| e.failed_out_of_hand()).count(),
            median_turn_held_deg: Some(median_turn(&|e| e.success)),
            median_turn_failed_deg: Some(median_turn(&|e| e.failed_lift())),
        }
    }
}

/// The physics failures of `objects` by kind, and the deep penetrations by what the object
/// touched.
pub(super) fn failure_counts(
    objects: &[ObjectResult],
) -> (BTreeMap<String, usize>, BTreeMap<String, usize>) {
    let mut kinds = BTreeMap::new();
    let mut bodies = BTreeMap::new();
    for f in objects.iter().flat_map(|o| &o.failures) {
        let kind = f.report.as_ref().map_or("unknown", |r| r.failure.kind());
        *kinds.entry(kind.to_string()).or_insert(0) += 1;
        if let Some(FailureReport {
            failure: PhysicsFailure::DeepPenetration { with, .. },
            ..
        }) = &f.report
        {
            *bodies.entry(with.clone()).or_insert(0) += 1;
        }
    }
    (kinds, bodies)
}

/// One line on an agent's physics: failures by kind and body, and the deepest contacts.
pub fn physics_line(r: &AgentResult) -> String {
    let n: usize = r.objects.iter().map(|o| o.trials).sum();
    // With several attempts per trial a trial is several episodes: counted per trial.
    let unit = if r.retries.is_some() {
        "trials"
    } else {
        "episodes"
    };
    let mut s = format!(
        "{}: {} of {n} {unit} ended in a physics failure",
        r.agent, r.physics_failures
    );
    // "name count, name count" of a tally.
    let tally = |m: &BTreeMap<String, usize>| {
        let parts: Vec<String> = m.iter().map(|(k, v)| format!("{k} {v}")).collect();
        parts.join(", ")
    };
    if !r.failures_by_kind.is_empty() {
        s.push_str(&format!(" ({})", tally(&r.failures_by_kind)));
    }
    if !r.penetrations_by_body.is_empty() {
        s.push_str(&format!(
            "; deep contacts with {}",
            tally(&r.penetrations_by_body)
        ));
    }
    if r.objects.iter().all(|o| o.deepest_contacts.is_empty()) {
        // An evaluation saved before the deepest contacts were recorded.
        s.push('\n');
        return s;
    }
    let c = &r.deepest_contact;
    s.push_str(&format!(
        "; deepest object contact per {}: median {:.1} mm, 99th percentile {:.1} mm, \
         max {:.1} mm, {} over 1 cm",
        &unit[..unit.len() - 1],
        c.median * 1e3,
        c.p99 * 1e3,
        c.max * 1e3,
        c.over_1cm
    ));
    if !r.over_1cm_by_body.is_empty() {
        s.push_str(&format!(" ({})", tally(&r.over_1cm_by_body)));
    }
    s.push('\n');
    s
}

/// Reads the results of an earlier `grasp eval --json` (one entry per agent, every trial's
/// outcome) so that they can be printed, compared or plotted again without re-running the
/// episodes. Each object's counts must agree with its outcomes; the rates and Wilson
/// intervals (per object and per agent) are recomputed from them, as
/// [`evaluate`](super::evaluate) computes them; agents must list the same objects.
pub fn read_results(path: &Path) -> Result<Vec<AgentResult>, EvalError> {
    let bad = |message: String| EvalError::Results {
        path: path.to_path_buf(),
        message,
    };
    let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
        .map_err(|e| bad(e.to_string()))?;
    let mut results: Vec<AgentResult> = serde_json::from_str(&text).map_err(|e| {
        bad(format!(
            "not the JSON of `grasp eval --json` (a list of agents' results): {e}"
        ))
    })?;
    if results.is_empty() {
        return Err(bad("holds no agents".into()));
    }
    for r in &mut results {
        // A success rate of no trials is not 0 %: such an agent is refused, not shown.
        if let Some(o) = r.objects.iter().find(|o| o.trials == 0) {
            return Err(bad(format!(
                "agent '{}', object '{}': no trials (an evaluation runs at least one)",
                r.agent, o.object
            )));
        }
        if r.objects.is_empty() {
            return Err(bad(format!("agent '{}': no objects", r.agent)));
        }
        // An evaluation runs each object once (`--objects` refuses a name given twice):
        // a repeated object would be counted twice in the agent's mean and trials.
        let names: Vec<&str> = r.objects.iter().map(|o| o.object.as_str()).collect();
        if let Some(o) = crate::util::seq::first_repeat(&names) {
            return Err(bad(format!(
                "agent '{}': object '{o}' is listed twice",
                r.agent
            )));
        }
        for o in &mut r.objects {
            let k = o.outcomes.iter().filter(|&&s| s).count();
            if o.outcomes.len() != o.trials || k != o.successes {
                return Err(bad(format!(
                    "agent '{}', object '{}': {} successes in {} trials, but the outcomes \
                     list {k} in {}",
                    r.agent,
                    o.object,
                    o.successes,
                    o.trials,
                    o.outcomes.len()
                )));
            }
            o.rate = k as f64 / o.trials.max(1) as f64;
            o.ci95 = wilson(k, o.trials);
        }
        check_retries(r).map_err(bad)?;
        let k_all: usize = r.objects.iter().map(|o| o.successes).sum();
        let n_all: usize = r.objects.iter().map(|o| o.trials).sum();
        check_counts(r, n_all).map_err(bad)?;
        r.mean_rate = r.objects.iter().map(|o| o.rate).sum::<f64>() / r.objects.len().max(1) as f64;
        r.ci95 = wilson(k_all, n_all);
        r.over_1cm_by_body = over_1cm_by_body(&r.objects);
    }
    let first: Vec<&str> = results[0]
        .objects
        .iter()
        .map(|o| o.object.as_str())
        .collect();
    for r in &results[1..] {
        if !r
            .objects
            .iter()
            .map(|o| o.object.as_str())
            .eq(first.iter().copied())
        {
            return Err(bad(format!(
                "agent '{}' lists other objects than '{}'",
                r.agent, results[0].agent
            )));
        }
    }
    Ok(results)
}

/// Checks that `r`'s rates are rates (in [0, 1]) and its counts fit its `n_all` trials
/// (an edited `thumb_contact_rate: 7.0` printed 700.0 %, `physics_failures: 99` of 2
/// trials was shown as it was).
fn check_counts(r: &AgentResult, n_all: usize) -> Result<(), String> {
    let agent = &r.agent;
    let l = &r.lifts;
    if !(0.0..=1.0).contains(&l.thumb_contact_rate) {
        return Err(format!(
            "agent '{agent}': `lifts.thumb_contact_rate` {} must be a rate in [0, 1]",
            crate::util::num::short(l.thumb_contact_rate)
        ));
    }
    for (field, v) in [
        ("lifts.mean_grip_effort", l.mean_grip_effort),
        ("lifts.mean_grip_held", l.mean_grip_held),
        ("lifts.mean_grip_dropped", l.mean_grip_dropped),
    ] {
        if !v.is_finite() {
            return Err(format!("agent '{agent}': `{field}` is not a finite number"));
        }
    }
    for (field, v) in [
        ("mean_steps", r.mean_steps),
        ("control_steps_per_s", r.control_steps_per_s),
        ("wall_s", r.wall_s),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "agent '{agent}': `{field}` {} must be a finite number >= 0",
                crate::util::num::short(v)
            ));
        }
    }
    if let Some(p) = &r.pregrasp {
        let episodes = n_all.saturating_mul(r.attempts().max(1));
        if p.planned.saturating_add(p.default_placement) > episodes {
            return Err(format!(
                "agent '{agent}': `pregrasp` places {} + {} episodes, more than its {n_all} \
                 trials of {} attempts",
                p.planned,
                p.default_placement,
                r.attempts().max(1)
            ));
        }
    }
    for (field, n) in [
        ("physics_failures", r.physics_failures),
        ("lifts.lifted", l.lifted),
        (
            "lifts.failed_in_hand + lifts.failed_out_of_hand",
            l.failed_in_hand.saturating_add(l.failed_out_of_hand),
        ),
    ] {
        if n > n_all {
            return Err(format!(
                "agent '{agent}': `{field}` is {n}, more than its {n_all} trials"
            ));
        }
    }
    for o in &r.objects {
        if o.physics_failures > o.trials
            || o.failed_in_hand.saturating_add(o.failed_out_of_hand) > o.trials
        {
            return Err(format!(
                "agent '{agent}', object '{}': more physics failures or failed lifts than \
                 its {} trials",
                o.object, o.trials
            ));
        }
    }
    Ok(())
}

/// Checks `r`'s attempts per trial against its `retries` and recomputes the counts of
/// trials won at the first attempt, retried and won on a retry from them, as
/// [`RetryStats::of`] counts them (the reasons a trial was not retried are kept: the
/// file is their only record).
fn check_retries(r: &mut AgentResult) -> Result<(), String> {
    let Some(s) = r.retries.as_mut() else {
        return match r.objects.iter().find(|o| !o.attempts.is_empty()) {
            Some(o) => Err(format!(
                "agent '{}', object '{}': attempts per trial without the agent's `retries`",
                r.agent, o.object
            )),
            None => Ok(()),
        };
    };
    if !(1..=super::MAX_ATTEMPTS).contains(&s.attempts) {
        return Err(format!(
            "agent '{}': `retries.attempts` {} must be in 1..={} (attempts per trial)",
            r.agent,
            s.attempts,
            super::MAX_ATTEMPTS
        ));
    }
    let (mut first, mut retried, mut won_on_retry) = (0, 0, 0);
    for o in &r.objects {
        let in_range = o.attempts.iter().all(|n| (1..=s.attempts).contains(n));
        if o.attempts.len() != o.trials || !in_range {
            return Err(format!(
                "agent '{}', object '{}': the attempts per trial must be {} numbers in \
                 1..={} (`retries.attempts`), one per trial",
                r.agent, o.object, o.trials, s.attempts
            ));
        }
        for (&won, &n) in o.outcomes.iter().zip(&o.attempts) {
            first += usize::from(won && n == 1);
            retried += usize::from(n > 1);
            won_on_retry += usize::from(won && n > 1);
        }
    }
    s.first_attempt_successes = first;
    s.retried = retried;
    s.won_on_retry = won_on_retry;
    Ok(())
}

/// The name a saved agent goes by in `results` when `--policy` gives `name`: `baseline1`
/// and `baseline2` name the baselines (saved as "Baseline 1" and "Baseline 2"), any other
/// name is the agent's own.
pub fn saved_agent_name(name: &str) -> String {
    match name {
        "baseline1" => super::AgentSpec::Baseline1.label(),
        "baseline2" => super::AgentSpec::Baseline2.label(),
        other => other.to_string(),
    }
}

/// The agents of `results` (read from `path`) that `names` pick, in that order; all of
/// them when `names` is empty. `baseline1` and `baseline2` name the baselines. A name
/// that several agents of the file share is refused: it would pick one of them silently.
pub fn select_agents(
    path: &Path,
    results: Vec<AgentResult>,
    names: &[String],
) -> Result<Vec<AgentResult>, EvalError> {
    if names.is_empty() {
        return Ok(results);
    }
    let bad = |message: String| EvalError::Results {
        path: path.to_path_buf(),
        message,
    };
    names
        .iter()
        .map(|p| {
            let name = saved_agent_name(p);
            let found: Vec<&AgentResult> = results.iter().filter(|r| r.agent == name).collect();
            match found.as_slice() {
                [one] => Ok((*one).clone()),
                [] => Err(bad(format!(
                    "holds no agent '{name}'; it holds: {}",
                    results
                        .iter()
                        .map(|r| r.agent.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))),
                many => Err(bad(format!(
                    "holds {} agents named '{name}': --policy cannot tell them apart (show \
                     all agents without --policy, or evaluate them with --labels)",
                    many.len()
                ))),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_stats_hand_computed() {
        // Ten depths (mm): 0, 1, ..., 8 and 25; nearest-rank median is the 5th (4 mm), the
        // 99th percentile the 10th (25 mm); one over 1 cm.
        let d: Vec<f64> = (0..9).map(|k| k as f64 * 1e-3).chain([0.025]).collect();
        let c = ContactStats::of(&d);
        assert!((c.median - 0.004).abs() < 1e-12, "{c:?}");
        assert!((c.p99 - 0.025).abs() < 1e-12);
        assert!((c.max - 0.025).abs() < 1e-12);
        assert_eq!(c.over_1cm, 1);
        assert!((c.within_1cm - 0.9).abs() < 1e-12);
        assert_eq!(ContactStats::of(&[]), ContactStats::default());
    }

    #[test]
    fn lift_stats_hand_computed() {
        let ep = |lifted, success, thumb, grip, in_hand| EpisodeSummary {
            object: "box".into(),
            success,
            steps: 3,
            episode_return: 0.0,
            lifted,
            physics_failure: false,
            failure: None,
            deepest_contact: 0.0,
            deepest_contact_with: None,
            touched_in_stage1: true,
            thumb_contact_at_lift: thumb,
            grip_effort: grip,
            object_height: 0.0,
            in_hand,
            object_turn: grip / 10.0,
        };
        // Four lifts (2 held with grips 4 and 2; 2 failed with 1 and 3, one of them with
        // the object still in the hand), thumb on 3 of them; the episode that never lifted
        // is left out.
        let eps = [
            ep(true, true, true, 4.0, true),
            ep(true, true, false, 2.0, true),
            ep(true, false, true, 1.0, true),
            ep(true, false, true, 3.0, false),
            ep(false, false, true, 9.0, false),
        ];
        let s = LiftStats::of(&eps);
        assert_eq!(s.lifted, 4);
        assert!((s.thumb_contact_rate - 3.0 / 4.0).abs() < 1e-12);
        assert!((s.mean_grip_effort - 10.0 / 4.0).abs() < 1e-12);
        assert!((s.mean_grip_held - 3.0).abs() < 1e-12);
        assert!((s.mean_grip_dropped - 2.0).abs() < 1e-12);
        assert_eq!((s.failed_in_hand, s.failed_out_of_hand), (1, 1));
        // Turns of grip / 10 rad: held 0.4 and 0.2 (median 0.3), failed 0.1 and 0.3 (0.2).
        assert!((s.median_turn_held_deg.unwrap() - 0.3f64.to_degrees()).abs() < 1e-9);
        assert!((s.median_turn_failed_deg.unwrap() - 0.2f64.to_degrees()).abs() < 1e-9);
        assert_eq!(
            LiftStats::of(&[]),
            LiftStats {
                median_turn_held_deg: Some(0.0),
                median_turn_failed_deg: Some(0.0),
                ..LiftStats::default()
            }
        );
        // A physics failure is neither kind of failed lift.
        let broken = EpisodeSummary {
            physics_failure: true,
            ..ep(true, false, true, 1.0, true)
        };
        assert!(!broken.failed_in_hand() && !broken.failed_out_of_hand());
    }
    #[test]
    fn saved_results_read_back_and_are_checked() {
        let r = AgentResult {
            agent: "Baseline 2".into(),
            objects: vec![ObjectResult {
                object: "box".into(),
                trials: 4,
                successes: 3,
                rate: 0.75,
                ci95: wilson(3, 4),
                mean_steps: 1.0,
                physics_failures: 1,
                outcomes: vec![true, false, true, true],
                deepest_contacts: vec![0.001, 0.03, 0.0, 0.002],
                deepest_contacts_with: ["table", "lh_ffdistal", "", "lh_thdistal"]
                    .map(String::from)
                    .to_vec(),
                failures: vec![TrialFailure {
                    trial: 1,
                    report: Some(FailureReport {
                        failure: PhysicsFailure::DeepPenetration {
                            depth: 0.03,
                            with: "lh_ffdistal".into(),
                            part: Some(2),
                        },
                        step: 140,
                    }),
                }],
                attempts: Vec::new(),
                failed_in_hand: 0,
                failed_out_of_hand: 0,
                lift_heights: Vec::new(),
                lift_turns: Vec::new(),
            }],
            mean_rate: 0.75,
            ci95: wilson(3, 4),
            mean_steps: 1.0,
            control_steps_per_s: 3.0,
            physics_failures: 1,
            failures_by_kind: [("deep_penetration".to_string(), 1)].into(),
            penetrations_by_body: [("lh_ffdistal".to_string(), 1)].into(),
            deepest_contact: ContactStats::of(&[0.001, 0.03, 0.0, 0.002]),
            over_1cm_by_body: [("lh_ffdistal".to_string(), 1)].into(),
            lifts: LiftStats::default(),
            wall_s: 1.0,
            pregrasp: None,
            conditions: None,
            retries: None,
            seed: None,
            recordings: Vec::new(),
            interrupted: false,
            record_errors: Vec::new(),
        };
        assert_eq!(over_1cm_by_body(&r.objects), r.over_1cm_by_body);
        let line = physics_line(&r);
        assert!(line.contains("1 over 1 cm (lh_ffdistal 1)"), "{line}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("eval.json");
        let write = |rs: &[AgentResult]| {
            std::fs::write(&path, serde_json::to_string_pretty(rs).unwrap()).unwrap();
        };
        write(std::slice::from_ref(&r));
        assert_eq!(read_results(&path).unwrap(), vec![r.clone()]);
        // Rates are rates, counts fit the trials.
        for edit in [
            (|x: &mut AgentResult| x.lifts.thumb_contact_rate = 7.0) as fn(&mut AgentResult),
            |x| x.physics_failures = 99,
            |x| x.lifts.lifted = 5,
            |x| x.objects[0].physics_failures = 5,
            |x| x.control_steps_per_s = -1.0,
            |x| {
                x.pregrasp = Some(PregraspStats {
                    placement: "antipodal".into(),
                    planned: 4,
                    default_placement: 1,
                    ranked: None,
                })
            },
        ] {
            let mut bad = r.clone();
            edit(&mut bad);
            write(&[bad]);
            let e = read_results(&path).unwrap_err().to_string();
            assert!(e.contains("eval.json") && e.contains("Baseline 2"), "{e}");
        }
        // Saved before the bodies were recorded: counted as unknown.
        let mut legacy = r.clone();
        legacy.objects[0].deepest_contacts_with.clear();
        write(&[legacy]);
        let back = read_results(&path).unwrap();
        assert_eq!(
            back[0].over_1cm_by_body,
            [("unknown".to_string(), 1)].into()
        );
        // Counts that contradict the outcomes.
        let mut bad = r.clone();
        bad.objects[0].successes = 4;
        write(&[bad]);
        let e = read_results(&path).unwrap_err().to_string();
        assert!(
            e.contains("4 successes in 4 trials, but the outcomes list 3 in 4"),
            "{e}"
        );
        // Agents on different objects; no agents.
        let mut other = r.clone();
        other.objects[0].object = "can".into();
        write(&[r, other]);
        let e = read_results(&path).unwrap_err().to_string();
        assert!(e.contains("lists other objects"), "{e}");
        write(&[]);
        assert!(read_results(&path).is_err());
    }

    /// One agent named `agent` on `objects`, each with `outcomes` and `attempts`.
    fn saved(agent: &str, objects: &[&str], outcomes: &[bool], attempts: &[usize]) -> AgentResult {
        let k = outcomes.iter().filter(|&&s| s).count();
        AgentResult {
            agent: agent.into(),
            objects: objects
                .iter()
                .map(|o| ObjectResult {
                    object: o.to_string(),
                    trials: outcomes.len(),
                    successes: k,
                    outcomes: outcomes.to_vec(),
                    attempts: attempts.to_vec(),
                    ..ObjectResult::default()
                })
                .collect(),
            retries: (!attempts.is_empty()).then(|| RetryStats {
                attempts: 2,
                ..RetryStats::default()
            }),
            ..AgentResult::default()
        }
    }

    #[test]
    fn saved_results_that_would_mislead_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("eval.json");
        let write = |rs: &[AgentResult]| {
            std::fs::write(&path, serde_json::to_string_pretty(rs).unwrap()).unwrap();
        };
        // An object twice in one agent was pooled into its mean as two objects.
        write(&[saved("A", &["wedge", "wedge"], &[true, false], &[])]);
        let e = read_results(&path).unwrap_err().to_string();
        assert!(
            e.contains("agent 'A': object 'wedge' is listed twice"),
            "{e}"
        );
        // The retry counts are recomputed from the trials' attempts: an edited count
        // printed "99 of 2 trials won at the first (4950.0 %)".
        let mut r = saved("A", &["wedge"], &[true, true, false], &[1, 2, 2]);
        r.retries.as_mut().unwrap().first_attempt_successes = 99;
        write(&[r]);
        let back = read_results(&path).unwrap();
        let s = back[0].retries.as_ref().unwrap();
        assert_eq!(
            (s.first_attempt_successes, s.retried, s.won_on_retry),
            (1, 2, 1)
        );
        for (attempts, allowed, want) in [
            (vec![1, 3, 1], 2, "3 numbers in 1..=2"),
            (vec![1, 1], 2, "3 numbers in 1..=2"),
            (vec![0, 1, 1], 2, "3 numbers in 1..=2"),
            (vec![1, 1, 1], 0, "`retries.attempts` 0 must be in 1..=10"),
        ] {
            let mut r = saved("A", &["wedge"], &[true, true, false], &attempts);
            r.retries.as_mut().unwrap().attempts = allowed;
            write(&[r]);
            let e = read_results(&path).unwrap_err().to_string();
            assert!(
                e.contains("eval.json") && e.contains(want),
                "{attempts:?}: {e}"
            );
        }
        let mut r = saved("A", &["wedge"], &[true], &[1]);
        r.retries = None;
        write(&[r]);
        let e = read_results(&path).unwrap_err().to_string();
        assert!(e.contains("without the agent's `retries`"), "{e}");
    }

    #[test]
    fn an_agent_name_the_file_holds_twice_is_not_picked_silently() {
        let path = Path::new("eval.json");
        let two = || {
            vec![
                saved("Baseline 2", &["wedge"], &[true], &[]),
                saved("Baseline 2", &["wedge"], &[false], &[]),
                saved("B1", &["wedge"], &[false], &[]),
            ]
        };
        let e = select_agents(path, two(), &["baseline2".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("eval.json") && e.contains("holds 2 agents named 'Baseline 2'"),
            "{e}"
        );
        let picked = select_agents(path, two(), &["B1".into()]).unwrap();
        assert_eq!(picked.len(), 1);
        assert_eq!(select_agents(path, two(), &[]).unwrap().len(), 3);
        let e = select_agents(path, two(), &["baseline1".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("holds no agent 'Baseline 1'; it holds: Baseline 2, Baseline 2, B1"),
            "{e}"
        );
    }
}
