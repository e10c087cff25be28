//! The results as tables: [`markdown_table`] in the layout of the paper's Table I, and
//! [`csv_table`] with one row per (agent, object).

use super::AgentResult;

/// `name` as one Markdown table cell: a `|` would open another column, a line break
/// another row (agent names come from `--labels` and saved JSON, objects from file names).
fn md_cell(name: &str) -> String {
    name.replace('|', "\\|").replace(char::is_control, " ")
}

/// `name` as one CSV field: commas become `;` and line breaks spaces, so that each
/// (agent, object) stays one row of the same columns.
fn csv_field(name: &str) -> String {
    name.replace(',', ";").replace(char::is_control, " ")
}

/// The per-agent text table `grasp eval` prints: each agent's mean success with its
/// Wilson interval, steps per episode, speed and physics failures, then one line per
/// object (successes, rate, interval, physics failures).
pub fn text_table(results: &[AgentResult]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    for r in results {
        let _ = writeln!(
                s,
                "{}: mean success {:.1} % (95 % CI {:.1}-{:.1}), {:.2} steps per episode, {:.1} control steps/s, {} physics failures",
                r.agent,
                100.0 * r.mean_rate,
                100.0 * r.ci95.0,
                100.0 * r.ci95.1,
                r.mean_steps,
                r.control_steps_per_s,
                r.physics_failures
            );
        for o in &r.objects {
            let failures = match o.physics_failures {
                0 => String::new(),
                f => format!("  {f} physics failure{}", if f == 1 { "" } else { "s" }),
            };
            let _ = writeln!(
                s,
                "  {:<22} {:>3}/{:<3} {:>5.0} %  [{:>3.0}, {:>3.0}]{failures}",
                o.object,
                o.successes,
                o.trials,
                100.0 * o.rate,
                100.0 * o.ci95.0,
                100.0 * o.ci95.1
            );
        }
    }
    s
}

/// A Markdown table in the layout of Table I: agents as rows, objects as columns, then
/// the mean. Rates in percent. When any episode ended in a physics failure, a last column
/// counts them per agent.
pub fn markdown_table(results: &[AgentResult]) -> String {
    let Some(first) = results.first() else {
        return String::new();
    };
    let mut s = String::from("| agent |");
    for o in &first.objects {
        s.push_str(&format!(" {} |", md_cell(&o.object)));
    }
    let failures = results.iter().any(|r| r.physics_failures > 0);
    s.push_str(" mean | 95 % CI | steps |");
    if failures {
        s.push_str(" physics failures |");
    }
    s.push_str("\n|---|");
    for _ in &first.objects {
        s.push_str("---|");
    }
    s.push_str(if failures {
        "---|---|---|---|\n"
    } else {
        "---|---|---|\n"
    });
    for r in results {
        s.push_str(&format!("| {} |", md_cell(&r.agent)));
        for o in &r.objects {
            s.push_str(&format!(" {:.0} |", 100.0 * o.rate));
        }
        s.push_str(&format!(
            " {:.1} | {:.1}-{:.1} | {:.2} |",
            100.0 * r.mean_rate,
            100.0 * r.ci95.0,
            100.0 * r.ci95.1,
            r.mean_steps
        ));
        if failures {
            s.push_str(&format!(" {} |", r.physics_failures));
        }
        s.push('\n');
    }
    s
}

/// CSV with one row per (agent, object).
pub fn csv_table(results: &[AgentResult]) -> String {
    let mut s = String::from(
        "agent,object,trials,successes,rate,ci95_low,ci95_high,mean_steps,physics_failures\n",
    );
    for r in results {
        for o in &r.objects {
            s.push_str(&format!(
                "{},{},{},{},{:.4},{:.4},{:.4},{:.3},{}\n",
                csv_field(&r.agent),
                csv_field(&o.object),
                o.trials,
                o.successes,
                o.rate,
                o.ci95.0,
                o.ci95.1,
                o.mean_steps,
                o.physics_failures
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{wilson, ObjectResult};

    #[test]
    fn tables_have_one_row_per_agent_and_object() {
        let r = AgentResult {
            agent: "Baseline 1".into(),
            objects: vec![ObjectResult {
                object: "box".into(),
                trials: 10,
                successes: 8,
                rate: 0.8,
                ci95: wilson(8, 10),
                mean_steps: 1.0,
                outcomes: vec![true; 8].into_iter().chain([false; 2]).collect(),
                deepest_contacts: vec![0.0; 10],
                ..Default::default()
            }],
            mean_rate: 0.8,
            ci95: wilson(8, 10),
            mean_steps: 1.0,
            control_steps_per_s: 3.0,
            wall_s: 1.0,
            ..Default::default()
        };
        let md = markdown_table(std::slice::from_ref(&r));
        assert!(
            md.contains("| Baseline 1 | 80 | 80.0 | 49.0-94.3 | 1.00 |\n"),
            "{md}"
        );
        assert!(!md.contains("physics"), "{md}");
        let mut broken = r.clone();
        broken.physics_failures = 1;
        broken.objects[0].physics_failures = 1;
        let md = markdown_table(std::slice::from_ref(&broken));
        assert!(md.contains("| steps | physics failures |"), "{md}");
        assert!(md.contains("| 1.00 | 1 |\n"), "{md}");
        let csv = csv_table(&[r]);
        assert_eq!(csv.lines().count(), 2);
        assert!(csv.contains("Baseline 1,box,10,8,0.8000"));
    }

    #[test]
    fn names_keep_to_their_cell() {
        // A line break in an agent's name (a saved JSON's) split its CSV and Markdown
        // rows; a comma in an object's (a mesh file "a,b.obj") shifted the CSV columns.
        let r = AgentResult {
            agent: "A\nB|C".into(),
            objects: vec![ObjectResult {
                object: "a,b".into(),
                trials: 1,
                outcomes: vec![false],
                ..Default::default()
            }],
            ..Default::default()
        };
        let csv = csv_table(std::slice::from_ref(&r));
        assert_eq!(csv.lines().count(), 2, "{csv}");
        assert!(csv.contains("\nA B|C,a;b,1,0,"), "{csv}");
        let md = markdown_table(&[r]);
        assert_eq!(md.lines().count(), 3, "{md}");
        assert!(md.contains("| a,b |") && md.contains("| A B\\|C |"), "{md}");
    }
}
