//! A grid's summary: per run and per variant rows read from the run folders
//! ([`summarize`]), the markdown table ([`markdown`]) and the report files
//! ([`write_reports`]: `summary.md`, `summary.csv`, `runs.csv`, one `<ablation>.svg` per
//! ablation).

use super::curves::{aggregate, final_success, mean_std, success_curve};
use super::evaluation::{self, PooledSet};
use super::{io_err, run_state, ExperimentError, Plan, RunState};
use crate::checkpoint::files;
use crate::train::metrics;
use crate::train::plot::write_band_plot;
use crate::util::fsx::write_atomic;
use serde::Serialize;
use std::path::PathBuf;

/// One run in the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunRow {
    /// Variant name.
    pub variant: String,
    /// Seed.
    pub seed: u64,
    /// `done`, `partial` or `missing`.
    pub state: String,
    /// Transitions so far.
    pub transitions: u64,
    /// Training wall time so far (s).
    pub wall_s: f64,
    /// Final training success ([`super::curves::final_success`]).
    pub final_success: Option<f64>,
    /// Success of the evaluation, when run.
    pub eval_success: Option<f64>,
}

/// One variant in the summary: means and sample standard deviations across its seeds
/// (finished and partial runs alike; `finished` says how many are done).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VariantRow {
    /// Variant name.
    pub variant: String,
    /// The paper's name of the setting.
    pub label: String,
    /// Ablations that include it.
    pub ablations: Vec<String>,
    /// Seeds planned.
    pub seeds: usize,
    /// Runs finished.
    pub finished: usize,
    /// Runs with data.
    pub with_data: usize,
    /// Final training success: mean and std across seeds.
    pub final_success: Option<(f64, f64)>,
    /// Transitions: mean across runs with data.
    pub transitions: f64,
    /// Wall time per run: mean across runs with data (s).
    pub wall_s: f64,
    /// Evaluation success: mean and std across seeds.
    pub eval_success: Option<(f64, f64)>,
}

/// The grid's results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridSummary {
    /// Grid name.
    pub grid: String,
    /// Per variant.
    pub variants: Vec<VariantRow>,
    /// Per run.
    pub runs: Vec<RunRow>,
    /// Per ablation and evaluated set: pooled success and paired tests against the
    /// ablation's reference.
    pub pooled: Vec<PooledSet>,
    /// The plots written (by [`write_reports`]).
    pub plots: Vec<PathBuf>,
}

/// Per variant, the smoothed `(transitions, success)` curve of each run with data.
pub type SeedCurves = Vec<Vec<Vec<(f64, f64)>>>;

/// Reads every run folder of `plan` into a summary (no plots yet) and the runs' curves.
pub fn summarize(plan: &Plan) -> Result<(GridSummary, SeedCurves), ExperimentError> {
    let g = &plan.grid;
    let mut runs = Vec::new();
    // Per variant, the smoothed success curve of each run with data.
    let mut curves: SeedCurves = vec![Vec::new(); plan.variants.len()];
    // An unreadable conditions file matches no cached evaluation.
    let conditions = g
        .eval
        .as_ref()
        .and_then(|e| e.conditions(&plan.path).ok())
        .flatten();
    for r in &plan.runs {
        let v = &plan.variants[r.variant];
        let state = run_state(&r.dir)?;
        let mpath = r.dir.join(files::METRICS);
        let rows = if mpath.is_file() && state != RunState::New {
            metrics::read_csv(&mpath).map_err(|source| ExperimentError::Train {
                context: format!("run {}", r.dir.display()),
                source,
            })?
        } else {
            Vec::new()
        };
        let eval_success = evaluation::cached_eval(plan, r, 0, &conditions).map(|c| c.success);
        if !rows.is_empty() {
            curves[r.variant].push(success_curve(&rows, g.smooth));
        }
        let last = rows.last();
        runs.push(RunRow {
            variant: v.name.clone(),
            seed: r.seed,
            state: match state {
                RunState::Done(_) => "done",
                RunState::Partial => "partial",
                RunState::New => "missing",
            }
            .into(),
            transitions: last.map_or(0, |x| x.global_step),
            wall_s: last.map_or(0.0, |x| x.wall_s),
            final_success: final_success(&rows, g.final_window),
            eval_success,
        });
    }
    let variants = plan
        .variants
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let mine: Vec<&RunRow> = runs.iter().filter(|r| r.variant == v.name).collect();
            let data: Vec<&&RunRow> = mine.iter().filter(|r| r.state != "missing").collect();
            let fs: Vec<f64> = mine.iter().filter_map(|r| r.final_success).collect();
            let es: Vec<f64> = mine.iter().filter_map(|r| r.eval_success).collect();
            VariantRow {
                variant: v.name.clone(),
                label: v.label.clone(),
                ablations: plan
                    .ablations
                    .iter()
                    .zip(&g.ablation)
                    .filter(|(m, _)| m.contains(&i))
                    .map(|(_, a)| a.name.clone())
                    .collect(),
                seeds: mine.len(),
                finished: mine.iter().filter(|r| r.state == "done").count(),
                with_data: data.len(),
                final_success: mean_std(&fs),
                transitions: mean_or_zero(data.iter().map(|r| r.transitions as f64)),
                wall_s: mean_or_zero(data.iter().map(|r| r.wall_s)),
                eval_success: mean_std(&es),
            }
        })
        .collect();
    Ok((
        GridSummary {
            grid: g.name.clone(),
            variants,
            runs,
            pooled: evaluation::pooled(plan, &conditions),
            plots: Vec::new(),
        },
        curves,
    ))
}

/// Mean of `v`, 0 when empty.
fn mean_or_zero(v: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

fn pct(v: Option<(f64, f64)>) -> String {
    v.map_or_else(
        || "-".into(),
        |(m, s)| format!("{:.1} ± {:.1}", 100.0 * m, 100.0 * s),
    )
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |x| format!("{x:.4}"))
}

/// The per-variant table as Markdown.
pub fn markdown(plan: &Plan, s: &GridSummary) -> String {
    let eval = plan
        .grid
        .eval
        .as_ref()
        .filter(|e| e.trials > 0)
        .map(|e| format!("{} success % ({} trials/object)", e.objects[0], e.trials));
    let mut out = format!(
        "# Experiment grid `{}`\n\nSeeds: {:?}. Final training success: mean of the last {} \
         updates' success rates, mean ± sample std across seeds (%).\n\n| variant | setting | \
         runs done | final training success % | transitions | wall time per run (s) |",
        s.grid, plan.grid.seeds, plan.grid.final_window
    );
    if let Some(e) = &eval {
        out.push_str(&format!(" {e} |"));
    }
    out.push_str("\n|---|---|---|---|---|---|");
    if eval.is_some() {
        out.push_str("---|");
    }
    out.push('\n');
    for v in &s.variants {
        let (transitions, wall) = if v.with_data == 0 {
            ("-".to_string(), "-".to_string())
        } else {
            (format!("{:.0}", v.transitions), format!("{:.1}", v.wall_s))
        };
        out.push_str(&format!(
            "| {} | {} | {}/{} | {} | {transitions} | {wall} |",
            v.variant,
            v.label,
            v.finished,
            v.seeds,
            pct(v.final_success),
        ));
        if eval.is_some() {
            out.push_str(&format!(" {} |", pct(v.eval_success)));
        }
        out.push('\n');
    }
    for (a, members) in plan.grid.ablation.iter().zip(&plan.ablations) {
        out.push_str(&format!(
            "\n## {}\n\n![{}]({}.svg)\n\nVariants: {}\n",
            a.title.as_deref().unwrap_or(&a.name),
            a.name,
            a.name,
            members
                .iter()
                .map(|&i| plan.variants[i].label.clone())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if let Some(e) = &plan.grid.eval {
        out.push_str(&evaluation::pooled_markdown(&s.pooled, e));
    }
    out
}

/// Writes `summary.md`, `summary.csv`, `runs.csv` and one SVG per ablation into the
/// plan's output folder; returns the summary with the plots' paths.
pub fn write_reports(plan: &Plan) -> Result<GridSummary, ExperimentError> {
    let (mut s, curves) = summarize(plan)?;
    crate::util::fsx::create_dirs(&plan.out).map_err(|e| io_err(&plan.out, e))?;
    for (a, members) in plan.grid.ablation.iter().zip(&plan.ablations) {
        let bands: Vec<_> = members
            .iter()
            .filter_map(|&i| aggregate(&plan.variants[i].label, &curves[i], plan.grid.band))
            .collect();
        let p = plan.out.join(format!("{}.svg", a.name));
        let title = a.title.clone().unwrap_or_else(|| a.name.clone());
        write_band_plot(&p, &title, "success rate", &bands).map_err(|e| io_err(&p, e))?;
        s.plots.push(p);
    }
    let write = |name: &str, text: String| {
        let p = plan.out.join(name);
        write_atomic(&p, text.as_bytes()).map_err(|e| io_err(&p, e))
    };
    write("summary.md", markdown(plan, &s))?;
    let mut csv = String::from(
        "variant,label,ablations,seeds,finished,final_success_mean,final_success_std,\
         transitions_mean,wall_s_mean,eval_success_mean,eval_success_std\n",
    );
    for v in &s.variants {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{:.0},{:.2},{},{}\n",
            v.variant,
            v.label,
            v.ablations.join(";"),
            v.seeds,
            v.finished,
            opt(v.final_success.map(|x| x.0)),
            opt(v.final_success.map(|x| x.1)),
            v.transitions,
            v.wall_s,
            opt(v.eval_success.map(|x| x.0)),
            opt(v.eval_success.map(|x| x.1)),
        ));
    }
    write("summary.csv", csv)?;
    let mut runs =
        String::from("variant,seed,state,transitions,wall_s,final_success,eval_success\n");
    for r in &s.runs {
        runs.push_str(&format!(
            "{},{},{},{},{:.2},{},{}\n",
            r.variant,
            r.seed,
            r.state,
            r.transitions,
            r.wall_s,
            opt(r.final_success),
            opt(r.eval_success)
        ));
    }
    write("runs.csv", runs)?;
    if !s.pooled.is_empty() {
        let mut csv = String::from(
            "ablation,objects,reference,variant,label,runs,successes,trials,success,ci_low,\
             ci_high,only_variant,only_reference,p_value\n",
        );
        for set in &s.pooled {
            for r in &set.rows {
                let (a, b, p) = r.vs_reference.map_or(
                    (String::new(), String::new(), String::new()),
                    |(a, b, p)| (a.to_string(), b.to_string(), format!("{p:.6}")),
                );
                csv.push_str(&format!(
                    "{},{},{},{},{},{},{},{},{:.4},{:.4},{:.4},{a},{b},{p}\n",
                    set.ablation,
                    set.objects,
                    set.reference,
                    r.variant,
                    r.label,
                    r.runs,
                    r.successes,
                    r.trials,
                    r.rate(),
                    r.ci95.0,
                    r.ci95.1
                ));
            }
        }
        write("pooled.csv", csv)?;
    }
    Ok(s)
}
