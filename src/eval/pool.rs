//! Evaluations pooled over several saved files: the same agents on the same objects,
//! evaluated with different seeds of scenes (`grasp --seed S eval --json` for S = 0, 1,
//! 2, ...), read back as one evaluation of more trials (`grasp eval --from-json
//! a.json,b.json,c.json`).
//!
//! An agent's trials are joined in the order of the files, so two agents stay paired
//! trial by trial only when both come from the same seeds in the same order: [`pool`]
//! checks that from the seeds the files record, and refuses a seed given twice (its
//! trials would count twice), a placement, attempts or conditions that change between
//! an agent's files, and object lists that differ. Counts, outcomes, contacts and
//! failures are joined exactly; rates, intervals and means are computed again from them.
//! The one statistic that cannot be is the median turn of the failed lifts (a file keeps
//! no per-trial record of which failed trials lifted): it is left out of the pooled result.

use super::results::{failure_counts, over_1cm_by_body, ContactStats, LiftStats, ObjectResult};
use super::{wilson, AgentResult, EvalError, RankStats, RetryStats, TrialFailure};
use crate::util::seq::first_repeat;
use std::path::{Path, PathBuf};

fn error(path: &Path, message: String) -> EvalError {
    EvalError::Results {
        path: path.to_path_buf(),
        message,
    }
}

/// The agents of several evaluations (each file's agents, as read), pooled: every agent
/// (in the order it first appears) with its trials from every file that holds it, joined
/// in file order. One file is returned as it is.
pub fn pool(files: &[(PathBuf, Vec<AgentResult>)]) -> Result<Vec<AgentResult>, EvalError> {
    if let [(_, agents)] = files {
        return Ok(agents.clone());
    }
    let mut names: Vec<&str> = Vec::new();
    for (path, agents) in files {
        let own: Vec<&str> = agents.iter().map(|a| a.agent.as_str()).collect();
        if let Some(twice) = first_repeat(&own) {
            return Err(error(
                path,
                format!(
                    "holds two agents named '{twice}': their trials cannot be told apart \
                     when pooled"
                ),
            ));
        }
        for a in agents {
            if !names.contains(&a.agent.as_str()) {
                names.push(&a.agent);
            }
        }
    }
    let entries = |name: &str| -> Vec<(&Path, &AgentResult)> {
        files
            .iter()
            .filter_map(|(p, agents)| {
                agents
                    .iter()
                    .find(|a| a.agent == name)
                    .map(|a| (p.as_path(), a))
            })
            .collect()
    };
    let mut reference: Option<(&str, Vec<u64>)> = None;
    let mut pooled = Vec::with_capacity(names.len());
    for name in names {
        let list = entries(name);
        let seeds = seeds_of(name, &list)?;
        match &reference {
            None => reference = Some((name, seeds)),
            Some((first, want)) if *want != seeds => {
                return Err(error(
                    list[0].0,
                    format!(
                        "agent '{name}' comes from seeds {seeds:?} and agent '{first}' from \
                         seeds {want:?}: pooled agents must be evaluated on the same seeds, \
                         their files listed in the same order, so that their trials stay \
                         paired"
                    ),
                ))
            }
            Some(_) => {}
        }
        pooled.push(pool_agent(name, &list));
    }
    Ok(pooled)
}

/// The seeds of an agent's files, checked: each recorded, none twice, and the placement,
/// attempts and conditions the same in every file.
fn seeds_of(name: &str, list: &[(&Path, &AgentResult)]) -> Result<Vec<u64>, EvalError> {
    let (_, first) = list[0];
    let mut seeds = Vec::with_capacity(list.len());
    for &(path, r) in list {
        let seed = r.seed.ok_or_else(|| {
            error(
                path,
                format!(
                    "agent '{name}' was saved before evaluations recorded their seed, so its \
                     trials cannot be matched with another file's; pool files saved since"
                ),
            )
        })?;
        if seeds.contains(&seed) {
            return Err(error(
                path,
                format!(
                    "agent '{name}' is given for seed {seed} twice: its trials would count \
                     twice"
                ),
            ));
        }
        seeds.push(seed);
        let differs = |what: &str, a: String, b: String| {
            error(
                path,
                format!(
                    "agent '{name}' has {what}{b} here and {a} in {}: pooled trials must \
                     not differ in it",
                    list[0].0.display()
                ),
            )
        };
        if r.placement() != first.placement() {
            return Err(differs("the placement ", first.placement(), r.placement()));
        }
        if r.attempts() != first.attempts() {
            return Err(differs(
                "attempts per trial ",
                first.attempts().to_string(),
                r.attempts().to_string(),
            ));
        }
        // The same placement and attempts by name, but a record of them in one file only
        // (an edited file: `retries` with one attempt, a planner named `top-down`).
        let recorded = |x: &AgentResult| {
            format!(
                "{} pre-grasp record and {} retry record",
                if x.pregrasp.is_some() { "a" } else { "no" },
                if x.retries.is_some() { "a" } else { "no" },
            )
        };
        if r.pregrasp.is_some() != first.pregrasp.is_some()
            || r.retries.is_some() != first.retries.is_some()
        {
            return Err(differs("", recorded(first), recorded(r)));
        }
        if r.conditions != first.conditions {
            let c = |x: &AgentResult| {
                if x.conditions.is_some() {
                    "perturbed conditions"
                } else {
                    "unperturbed conditions"
                }
                .to_string()
            };
            return Err(differs("been evaluated in ", c(first), c(r)));
        }
        let objects = |x: &AgentResult| x.objects.iter().map(|o| o.object.clone()).collect();
        let (want, have): (Vec<String>, Vec<String>) = (objects(first), objects(r));
        if want != have {
            return Err(error(
                path,
                format!(
                    "agent '{name}' has the objects {} here and {} in {}: pooled files \
                     must evaluate the same objects in the same order",
                    have.join(", "),
                    want.join(", "),
                    list[0].0.display()
                ),
            ));
        }
    }
    Ok(seeds)
}

/// A per-trial list joined over the files, or empty where a file lacks it (saved before
/// it was recorded).
fn joined<T: Clone>(parts: &[&ObjectResult], field: impl Fn(&ObjectResult) -> &Vec<T>) -> Vec<T> {
    if parts.iter().any(|o| field(o).len() != o.trials) {
        return Vec::new();
    }
    parts
        .iter()
        .flat_map(|o| field(o).iter().cloned())
        .collect()
}

fn pool_object(parts: &[&ObjectResult]) -> ObjectResult {
    let trials: usize = parts.iter().map(|o| o.trials).sum();
    let successes: usize = parts.iter().map(|o| o.successes).sum();
    let mut failures = Vec::new();
    let mut offset = 0;
    for o in parts {
        failures.extend(o.failures.iter().map(|f| TrialFailure {
            trial: f.trial + offset,
            report: f.report.clone(),
        }));
        offset += o.trials;
    }
    // Without contacts recorded a trial's body is unknown, as in one file.
    let with = if parts.iter().all(|o| o.deepest_contacts_with.is_empty()) {
        Vec::new()
    } else {
        parts
            .iter()
            .flat_map(|o| {
                (0..o.trials).map(|t| o.deepest_contacts_with.get(t).cloned().unwrap_or_default())
            })
            .collect()
    };
    ObjectResult {
        object: parts[0].object.clone(),
        trials,
        successes,
        rate: successes as f64 / trials.max(1) as f64,
        ci95: wilson(successes, trials),
        mean_steps: mean_steps(parts.iter().copied()),
        physics_failures: parts.iter().map(|o| o.physics_failures).sum(),
        outcomes: parts
            .iter()
            .flat_map(|o| o.outcomes.iter().copied())
            .collect(),
        deepest_contacts: joined(parts, |o| &o.deepest_contacts),
        deepest_contacts_with: with,
        failures,
        attempts: joined(parts, |o| &o.attempts),
        failed_in_hand: parts.iter().map(|o| o.failed_in_hand).sum(),
        failed_out_of_hand: parts.iter().map(|o| o.failed_out_of_hand).sum(),
        lift_heights: joined(parts, |o| &o.lift_heights),
        lift_turns: joined(parts, |o| &o.lift_turns),
    }
}

/// The mean control steps per episode over `objects`' trials.
fn mean_steps<'a>(objects: impl Iterator<Item = &'a ObjectResult>) -> f64 {
    weighted(objects.map(|o| (o.mean_steps, o.trials)))
}

/// A mean over the files, each weighted by its count (0 with no count at all).
fn weighted(parts: impl Iterator<Item = (f64, usize)>) -> f64 {
    let (sum, n) = parts.fold((0.0, 0), |(s, n), (x, k)| (s + x * k as f64, n + k));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// The lift statistics of the pooled trials: counts summed, means weighted by the lifts
/// they are over (every successful trial's last episode lifted, so the held lifts are
/// the successes), the held lifts' median turn from the trials; the failed lifts' median
/// is left out (see the module docs).
fn pool_lifts(list: &[(&Path, &AgentResult)], objects: &[ObjectResult]) -> LiftStats {
    let lifts: Vec<(&LiftStats, usize)> = list
        .iter()
        .map(|(_, r)| (&r.lifts, r.objects.iter().map(|o| o.successes).sum()))
        .collect();
    let lifted = lifts.iter().map(|(l, _)| l.lifted).sum();
    let held_turns: Option<Vec<f64>> = objects
        .iter()
        .map(|o| {
            (o.lift_turns.len() == o.trials).then(|| {
                o.outcomes
                    .iter()
                    .zip(&o.lift_turns)
                    .filter(|(won, _)| **won)
                    .map(|(_, t)| t.to_degrees())
                    .collect::<Vec<f64>>()
            })
        })
        .collect::<Option<Vec<_>>>()
        .map(|v| v.concat());
    LiftStats {
        lifted,
        thumb_contact_rate: weighted(lifts.iter().map(|(l, _)| (l.thumb_contact_rate, l.lifted))),
        mean_grip_effort: weighted(lifts.iter().map(|(l, _)| (l.mean_grip_effort, l.lifted))),
        mean_grip_held: weighted(lifts.iter().map(|(l, held)| (l.mean_grip_held, *held))),
        mean_grip_dropped: weighted(
            lifts
                .iter()
                .map(|(l, held)| (l.mean_grip_dropped, l.lifted.saturating_sub(*held))),
        ),
        failed_in_hand: lifts.iter().map(|(l, _)| l.failed_in_hand).sum(),
        failed_out_of_hand: lifts.iter().map(|(l, _)| l.failed_out_of_hand).sum(),
        median_turn_held_deg: held_turns.map(|t| {
            if t.is_empty() {
                0.0
            } else {
                crate::util::stats::median(&t)
            }
        }),
        median_turn_failed_deg: None,
    }
}

fn pool_agent(name: &str, list: &[(&Path, &AgentResult)]) -> AgentResult {
    let (_, first) = list[0];
    let objects: Vec<ObjectResult> = (0..first.objects.len())
        .map(|k| {
            let parts: Vec<&ObjectResult> = list.iter().map(|(_, r)| &r.objects[k]).collect();
            pool_object(&parts)
        })
        .collect();
    let n_all: usize = objects.iter().map(|o| o.trials).sum();
    let k_all: usize = objects.iter().map(|o| o.successes).sum();
    let wall_s: f64 = list.iter().map(|(_, r)| r.wall_s).sum();
    let (failures_by_kind, penetrations_by_body) = failure_counts(&objects);
    let depths: Vec<f64> = objects
        .iter()
        .flat_map(|o| o.deepest_contacts.iter().copied())
        .collect();
    let pregrasp = match &first.pregrasp {
        None => None,
        Some(p) => {
            let mut p = p.clone();
            p.planned = 0;
            p.default_placement = 0;
            let mut chosen: Vec<usize> = Vec::new();
            for q in list.iter().filter_map(|(_, r)| r.pregrasp.as_ref()) {
                p.planned += q.planned;
                p.default_placement += q.default_placement;
                if let Some(RankStats { chosen: c, .. }) = &q.ranked {
                    chosen.resize(chosen.len().max(c.len()), 0);
                    for (sum, x) in chosen.iter_mut().zip(c) {
                        *sum += x;
                    }
                }
            }
            if let Some(r) = &mut p.ranked {
                r.chosen = chosen;
            }
            Some(p)
        }
    };
    let retries = first.retries.as_ref().map(|s| {
        let mut pooled = RetryStats {
            attempts: s.attempts,
            ..RetryStats::default()
        };
        for q in list.iter().filter_map(|(_, r)| r.retries.as_ref()) {
            pooled.first_attempt_successes += q.first_attempt_successes;
            pooled.retried += q.retried;
            pooled.won_on_retry += q.won_on_retry;
            for (why, n) in &q.not_retried {
                *pooled.not_retried.entry(why.clone()).or_default() += n;
            }
        }
        pooled
    });
    AgentResult {
        agent: name.to_string(),
        mean_rate: objects.iter().map(|o| o.rate).sum::<f64>() / objects.len().max(1) as f64,
        ci95: wilson(k_all, n_all),
        mean_steps: mean_steps(objects.iter()),
        control_steps_per_s: list
            .iter()
            .map(|(_, r)| r.control_steps_per_s * r.wall_s)
            .sum::<f64>()
            / wall_s.max(1e-9),
        physics_failures: objects.iter().map(|o| o.physics_failures).sum(),
        failures_by_kind,
        penetrations_by_body,
        deepest_contact: ContactStats::of(&depths),
        over_1cm_by_body: over_1cm_by_body(&objects),
        lifts: pool_lifts(list, &objects),
        wall_s,
        pregrasp,
        seed: None,
        retries,
        conditions: first.conditions.clone(),
        recordings: Vec::new(),
        interrupted: list.iter().any(|(_, r)| r.interrupted),
        record_errors: Vec::new(),
        objects,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{paired, read_results};

    fn read(f: &str) -> (PathBuf, Vec<AgentResult>) {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(f);
        let agents = read_results(&p).unwrap();
        (p, agents)
    }

    fn seeds(set: &str, placement: &str) -> Vec<(PathBuf, Vec<AgentResult>)> {
        (0..3)
            .map(|s| {
                read(&format!(
                    "docs/results/pregrasp_views_2026_12/{set}_{placement}_seed{s}.json"
                ))
            })
            .collect()
    }

    #[test]
    fn one_file_is_returned_as_it_is() {
        let one = vec![read(
            "docs/results/pregrasp_views_2026_12/novel_antipodal_seed0.json",
        )];
        assert_eq!(pool(&one).unwrap(), one[0].1);
    }

    #[test]
    fn three_seeds_pool_into_their_sums_and_stay_paired() {
        let files = seeds("novel", "antipodal");
        let pooled = pool(&files).unwrap();
        assert_eq!(pooled.len(), files[0].1.len());
        for (k, agent) in pooled.iter().enumerate() {
            assert_eq!(agent.agent, files[0].1[k].agent);
            assert_eq!(agent.seed, None);
            let mut rates = 0.0;
            for (o, object) in agent.objects.iter().enumerate() {
                let parts: Vec<&ObjectResult> = files.iter().map(|f| &f.1[k].objects[o]).collect();
                let n: usize = parts.iter().map(|p| p.trials).sum();
                let won: usize = parts.iter().map(|p| p.successes).sum();
                assert_eq!((object.trials, object.successes), (n, won));
                assert_eq!(object.outcomes.len(), n);
                assert_eq!(object.outcomes[..20], parts[0].outcomes[..]);
                assert_eq!(object.outcomes[40..], parts[2].outcomes[..]);
                assert_eq!(object.ci95, wilson(won, n));
                rates += won as f64 / n as f64;
            }
            assert!((agent.mean_rate - rates / agent.objects.len() as f64).abs() < 1e-12);
            let planned: usize = files
                .iter()
                .map(|f| f.1[k].pregrasp.as_ref().unwrap().planned)
                .sum();
            assert_eq!(agent.pregrasp.as_ref().unwrap().planned, planned);
            let lifted: usize = files.iter().map(|f| f.1[k].lifts.lifted).sum();
            assert_eq!(agent.lifts.lifted, lifted);
            assert_eq!(agent.lifts.median_turn_failed_deg, None);
        }
        // The pooled comparison is the three seeds' comparisons added up.
        let p = paired(&pooled[0], &pooled[1]).unwrap();
        let parts: Vec<_> = files
            .iter()
            .map(|f| paired(&f.1[0], &f.1[1]).unwrap())
            .collect();
        assert_eq!(
            p.only_agent,
            parts.iter().map(|q| q.only_agent).sum::<usize>()
        );
        assert_eq!(
            p.only_against,
            parts.iter().map(|q| q.only_against).sum::<usize>()
        );
        assert_eq!(p.both, parts.iter().map(|q| q.both).sum::<usize>());
    }

    #[test]
    fn the_held_lifts_median_turn_is_the_files_own() {
        // Pooled from one file's entry, the statistics computed again from its trials
        // are the ones the evaluation computed from its episodes.
        let (path, agents) = read("docs/results/squeeze_2026_12/report/novel_top-down_seed0.json");
        for a in &agents {
            let again = pool_agent(&a.agent, &[(path.as_path(), a)]);
            assert_eq!(again.objects, a.objects);
            // The same turns (read back in radians, turned into degrees again).
            let (held, want) = (
                again.lifts.median_turn_held_deg,
                a.lifts.median_turn_held_deg,
            );
            assert!(
                (held.unwrap() - want.unwrap()).abs() < 1e-9,
                "{held:?} {want:?}"
            );
            assert!((again.lifts.mean_grip_held - a.lifts.mean_grip_held).abs() < 1e-12);
            assert!((again.lifts.mean_grip_dropped - a.lifts.mean_grip_dropped).abs() < 1e-12);
            assert_eq!(again.deepest_contact, a.deepest_contact);
            assert_eq!(again.mean_rate, a.mean_rate);
            assert!((again.mean_steps - a.mean_steps).abs() < 1e-12);
        }
    }

    #[test]
    fn retries_pool_their_counts() {
        let files: Vec<_> = (0..3)
            .map(|s| {
                read(&format!(
                    "docs/results/retry_2026_12/novel_top-down_seed{s}.json"
                ))
            })
            .collect();
        let pooled = pool(&files).unwrap();
        let r = pooled[0].retries.as_ref().unwrap();
        let sum = |f: &dyn Fn(&RetryStats) -> usize| -> usize {
            files
                .iter()
                .map(|x| f(x.1[0].retries.as_ref().unwrap()))
                .sum()
        };
        assert_eq!(r.attempts, 2);
        assert_eq!(r.won_on_retry, sum(&|s| s.won_on_retry));
        assert_eq!(r.retried, sum(&|s| s.retried));
        assert_eq!(
            r.first_attempt_successes,
            sum(&|s| s.first_attempt_successes)
        );
        let attempts: usize = pooled[0].objects.iter().map(|o| o.attempts.len()).sum();
        assert_eq!(attempts, 3 * 10 * 20);
    }

    #[test]
    fn trials_that_would_not_pair_are_refused_naming_the_file() {
        let files = seeds("novel", "antipodal");
        let msg = |files: &[(PathBuf, Vec<AgentResult>)]| pool(files).unwrap_err().to_string();
        // The same seed twice.
        let twice = vec![files[0].clone(), files[1].clone(), files[0].clone()];
        let m = msg(&twice);
        assert!(
            m.contains("seed0.json") && m.contains("seed 0 twice"),
            "{m}"
        );
        // Another placement.
        let mut mixed = files.clone();
        mixed[2] = read("docs/results/retry_2026_12/novel_top-down_seed2.json");
        mixed[2].1.retain(|a| a.agent == "pca8");
        let m = msg(&mixed);
        assert!(m.contains("placement top-down here and antipodal"), "{m}");
        // Agents from seeds in another order.
        let mut swapped = files.clone();
        for a in &mut swapped[0].1[1..] {
            a.seed = Some(1);
        }
        for a in &mut swapped[1].1[1..] {
            a.seed = Some(0);
        }
        let m = msg(&swapped);
        assert!(
            m.contains("from seeds [1, 0, 2]") && m.contains("[0, 1, 2]"),
            "{m}"
        );
        // Other objects.
        let mut fewer = files.clone();
        fewer[1].1[0].objects.pop();
        let m = msg(&fewer);
        assert!(
            m.contains("seed1.json") && m.contains("same objects"),
            "{m}"
        );
        // Two agents of one name in a file.
        let mut named_twice = files.clone();
        let copy = named_twice[1].1[0].clone();
        named_twice[1].1.push(copy);
        let m = msg(&named_twice);
        assert!(
            m.contains("seed1.json") && m.contains("two agents named 'pca8'"),
            "{m}"
        );
        // A retry record in one file only (one attempt each, so the attempts agree).
        let mut edited = files.clone();
        edited[0].1[0].retries = Some(RetryStats {
            attempts: 1,
            ..RetryStats::default()
        });
        let m = msg(&edited);
        assert!(
            m.contains("seed1.json") && m.contains("a pre-grasp record and no retry record"),
            "{m}"
        );
        // No seed recorded.
        let mut old = files.clone();
        old[2].1[0].seed = None;
        let m = msg(&old);
        assert!(
            m.contains("seed2.json") && m.contains("before evaluations recorded"),
            "{m}"
        );
    }

    #[test]
    fn weighted_means_hand_computed() {
        assert_eq!(weighted([(2.0, 1), (5.0, 2)].into_iter()), 4.0);
        assert_eq!(weighted([(2.0, 0)].into_iter()), 0.0);
    }
}
