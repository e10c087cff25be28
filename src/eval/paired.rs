//! Paired comparison of two agents evaluated on identical start poses.
//!
//! `grasp eval` gives every agent the same trial seeds (common random numbers), so trial
//! `t` on object `o` is the same scene for all of them. Two agents' outcomes then form
//! pairs, and the trials where exactly one of them succeeds (the discordant pairs) carry
//! the whole difference. The exact McNemar test asks how likely a split at least this
//! uneven is when either agent is equally likely to be the one that succeeds: a two-sided
//! binomial test of the discordant counts with p = 1/2. It is far more sensitive than
//! comparing the two agents' separate Wilson intervals, which ignores the pairing.

use super::AgentResult;
use serde::Serialize;

/// Outcome counts of agent `agent` against agent `against` over their common trials.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Paired {
    /// The agent compared.
    pub agent: String,
    /// The agent it is compared against.
    pub against: String,
    /// Trials both agents won.
    pub both: usize,
    /// Trials only `agent` won.
    pub only_agent: usize,
    /// Trials only `against` won.
    pub only_against: usize,
    /// Trials both lost.
    pub neither: usize,
    /// Two-sided exact McNemar p-value of the discordant counts.
    pub p_value: f64,
}

/// Two-sided exact McNemar p-value for discordant counts `b` and `c`:
/// `min(1, 2 P[X <= min(b, c)])` with `X ~ Binomial(b + c, 1/2)`; 1 when `b + c = 0`.
pub fn mcnemar_exact(b: usize, c: usize) -> f64 {
    let n = b + c;
    if n == 0 {
        return 1.0;
    }
    let k = b.min(c);
    // ln C(n, i) - n ln 2, summed in the linear domain; exact enough for n in the thousands.
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_choose = 0.0; // ln C(n, 0)
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_choose + ln_half_n).exp();
    }
    (2.0 * tail).min(1.0)
}

/// Why `a` and `b` cannot be paired trial by trial (their trials are not the same
/// scenes), or `None` when they can.
pub fn unpaired_reason(a: &AgentResult, b: &AgentResult) -> Option<String> {
    if a.placement() != b.placement() {
        return Some(format!(
            "their hands started from different placements ({} and {})",
            a.placement(),
            b.placement()
        ));
    }
    if a.conditions != b.conditions {
        let c = |r: &AgentResult| {
            if r.conditions.is_some() {
                "perturbed"
            } else {
                "unperturbed"
            }
        };
        return Some(format!(
            "they were evaluated in different conditions ({} and {}, `grasp eval --perturb`)",
            c(a),
            c(b)
        ));
    }
    if a.attempts() != b.attempts() {
        return Some(format!(
            "they had different attempts per trial ({} and {}, `grasp eval --attempts`)",
            a.attempts(),
            b.attempts()
        ));
    }
    if a.seed != b.seed {
        let s = |r: &AgentResult| r.seed.map_or("not recorded".to_string(), |v| v.to_string());
        return Some(format!(
            "their start poses came from different seeds ({} and {})",
            s(a),
            s(b)
        ));
    }
    let same_trials = a.objects.len() == b.objects.len()
        && a.objects
            .iter()
            .zip(&b.objects)
            .all(|(x, y)| x.object == y.object && x.outcomes.len() == y.outcomes.len());
    if !same_trials {
        let n = |r: &AgentResult| r.objects.iter().map(|o| o.outcomes.len()).sum::<usize>();
        return Some(format!(
            "they ran different objects or numbers of trials ({} and {} trials)",
            n(a),
            n(b)
        ));
    }
    None
}

/// Pairs `a` with `b` trial by trial. `None` when their trials are not the same scenes:
/// other objects or numbers of trials, another start-pose seed or another placement
/// (see [`unpaired_reason`]).
pub fn paired(a: &AgentResult, b: &AgentResult) -> Option<Paired> {
    if unpaired_reason(a, b).is_some() {
        return None;
    }
    let (mut both, mut only_a, mut only_b, mut neither) = (0, 0, 0, 0);
    for (oa, ob) in a.objects.iter().zip(&b.objects) {
        if oa.object != ob.object || oa.outcomes.len() != ob.outcomes.len() {
            return None;
        }
        for (&x, &y) in oa.outcomes.iter().zip(&ob.outcomes) {
            match (x, y) {
                (true, true) => both += 1,
                (true, false) => only_a += 1,
                (false, true) => only_b += 1,
                (false, false) => neither += 1,
            }
        }
    }
    Some(Paired {
        agent: a.agent.clone(),
        against: b.agent.clone(),
        both,
        only_agent: only_a,
        only_against: only_b,
        neither,
        p_value: mcnemar_exact(only_a, only_b),
    })
}

/// The first agent paired against each of the others (those with the same trials).
pub fn paired_with_first(results: &[AgentResult]) -> Vec<Paired> {
    let Some((first, rest)) = results.split_first() else {
        return Vec::new();
    };
    rest.iter().filter_map(|r| paired(first, r)).collect()
}

/// One line for each agent after the first that cannot be paired with it, saying why
/// (no paired comparison is printed for it).
pub fn unpaired_lines(results: &[AgentResult]) -> String {
    let Some((first, rest)) = results.split_first() else {
        return String::new();
    };
    rest.iter()
        .filter_map(|r| {
            unpaired_reason(first, r).map(|why| {
                format!(
                    "{} vs {}: not compared trial by trial: {why}\n",
                    first.agent, r.agent
                )
            })
        })
        .collect()
}

/// A p-value as the reports print it: `p = 0.077`, or `p < 0.001` below 0.001.
pub fn p_text(p: f64) -> String {
    if p < 0.001 {
        "p < 0.001".to_string()
    } else {
        format!("p = {p:.3}")
    }
}

/// One line per comparison, e.g. `A vs B on identical start poses: only the first won 12
/// trials, only the second 4, both 50, neither 29 (exact McNemar p = 0.077)`; p-values
/// below 0.001 are printed as `p < 0.001`.
pub fn paired_lines(pairs: &[Paired]) -> String {
    let mut s = String::new();
    for p in pairs {
        let pv = p_text(p.p_value);
        s.push_str(&format!(
            "{} vs {} on identical start poses: only the first won {} trials, only the second {}, both {}, neither {} (exact McNemar {pv})\n",
            p.agent, p.against, p.only_agent, p.only_against, p.both, p.neither
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{wilson, ObjectResult};

    #[test]
    fn mcnemar_hand_computed() {
        // b = 0, c = 5: 2 * 0.5^5 = 0.0625.
        assert!((mcnemar_exact(0, 5) - 0.0625).abs() < 1e-12);
        // b = 1, c = 9: 2 * (1 + 10) / 1024 = 0.021484375.
        assert!((mcnemar_exact(1, 9) - 0.021484375).abs() < 1e-12);
        assert!((mcnemar_exact(9, 1) - 0.021484375).abs() < 1e-12);
        // b = 2, c = 6: 2 * (1 + 8 + 28) / 256 = 0.2890625.
        assert!((mcnemar_exact(2, 6) - 0.2890625).abs() < 1e-12);
        // A balanced split and no discordant pairs give 1.
        assert_eq!(mcnemar_exact(4, 4), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        // Large n stays finite: b = 40, c = 60 is about 0.0569 (two-sided binomial).
        let p = mcnemar_exact(40, 60);
        assert!((p - 0.0569).abs() < 1e-3, "{p}");
    }

    fn agent(name: &str, outcomes: &[&[bool]]) -> AgentResult {
        let objects: Vec<ObjectResult> = outcomes
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let k = o.iter().filter(|&&x| x).count();
                ObjectResult {
                    object: format!("obj{i}"),
                    trials: o.len(),
                    successes: k,
                    rate: k as f64 / o.len() as f64,
                    ci95: wilson(k, o.len()),
                    mean_steps: 1.0,
                    outcomes: o.to_vec(),
                    deepest_contacts: vec![0.0; o.len()],
                    ..Default::default()
                }
            })
            .collect();
        AgentResult {
            agent: name.into(),
            objects,
            mean_rate: 0.0,
            ci95: (0.0, 1.0),
            mean_steps: 1.0,
            control_steps_per_s: 1.0,
            wall_s: 1.0,
            ..Default::default()
        }
    }

    #[test]
    fn pairs_count_trial_by_trial() {
        let a = agent("A", &[&[true, true, false], &[true, false]]);
        let b = agent("B", &[&[true, false, false], &[false, true]]);
        let p = paired(&a, &b).unwrap();
        assert_eq!(
            (p.both, p.only_agent, p.only_against, p.neither),
            (1, 2, 1, 1)
        );
        // b = 2, c = 1: 2 * (1 + 3) / 8 = 1 (capped).
        assert_eq!(p.p_value, 1.0);
        let lines = paired_lines(&paired_with_first(&[a.clone(), b.clone()]));
        assert!(lines.contains("A vs B"), "{lines}");
        assert!(lines.contains("only the first won 2 trials, only the second 1"));
        // Different trial counts or objects are not the same scenes.
        let c = agent("C", &[&[true, true], &[true, false]]);
        assert!(paired(&a, &c).is_none());
        let mut d = b.clone();
        d.objects[1].object = "other".into();
        assert!(paired(&a, &d).is_none());
        assert!(paired_with_first(std::slice::from_ref(&a)).is_empty());
        let lines = unpaired_lines(&[a.clone(), b.clone(), c.clone()]);
        assert_eq!(
            lines,
            "A vs C: not compared trial by trial: they ran different objects or numbers of \
             trials (5 and 4 trials)\n"
        );
        // Another seed or placement: not the same scenes either (issue 49).
        let mut e = b.clone();
        e.seed = Some(3);
        assert!(paired(&a, &e).is_none());
        let mut f = b.clone();
        f.pregrasp = Some(crate::eval::PregraspStats {
            placement: "antipodal".into(),
            planned: 5,
            default_placement: 0,
            ranked: None,
        });
        assert!(paired(&a, &f).is_none());
        // Placements a critic chose among the planner's top ones: another placement.
        let mut r = f.clone();
        if let Some(p) = r.pregrasp.as_mut() {
            p.ranked = Some(crate::eval::RankStats {
                top: 5,
                ranker: "runs/q/checkpoints/latest".into(),
                chosen: vec![3, 1, 1, 0, 0],
            });
        }
        assert!(paired(&f, &r).is_none());
        assert!(unpaired_lines(&[f.clone(), r.clone()]).contains(
            "different placements (antipodal and antipodal, ranked by \
             runs/q/checkpoints/latest among the top 5)"
        ));
        assert!(paired(&r, &r.clone()).is_some());
        let lines = unpaired_lines(&[a.clone(), e, f]);
        assert!(
            lines.contains(
                "A vs B: not compared trial by trial: their start poses came from \
                            different seeds (not recorded and 3)"
            ) && lines.contains("different placements (top-down and antipodal)"),
            "{lines}"
        );
        // Perturbed conditions (`grasp eval --perturb`) against none: not the same scenes.
        let mut g = b.clone();
        g.conditions = Some(crate::eval::conditions::EvalConditions::default());
        assert!(paired(&a, &g).is_none());
        assert!(unpaired_lines(&[a.clone(), g])
            .contains("different conditions (unperturbed and perturbed"));
        // Tiny p-values are printed as a bound.
        let strong = Paired {
            only_agent: 20,
            only_against: 0,
            p_value: mcnemar_exact(20, 0),
            ..p
        };
        assert!(paired_lines(&[strong]).contains("(exact McNemar p < 0.001)"));
    }
}
