//! `grasp experiment`: the paper's ablations as a grid of training runs, summarised in a
//! table and Fig.-5-style plots.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::experiment::{evaluate_runs, markdown, plan, run_grid, write_reports, GridOptions};
use std::path::PathBuf;

use super::threads;
use super::Global;

/// Run a grid of training runs (variants x seeds) and summarise it.
///
/// Every (config, seed) run trains through the library's trainer into
/// <out>/<variant>/seed<k>. Finished runs hold done.json and are skipped; after a kill,
/// --resume continues unfinished runs from their latest checkpoint. Then, with an [eval]
/// table in the grid, each finished run's latest checkpoint is evaluated (cached in
/// eval.json), and summary.md, summary.csv, runs.csv and one <ablation>.svg per ablation
/// (mean success rate over seeds with a min-max band, against transitions) are written.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp experiment --grid configs/grids/tiny_grid.toml --out runs/tiny\n  grasp experiment --grid configs/grids/paper_ablation.toml --budget-minutes 600\n  grasp experiment --grid configs/grids/paper_ablation.toml --resume\n  grasp experiment --grid configs/grids/paper_ablation.toml --resume --report-only --json\n\n--parallel N trains N runs at once with the cores split between them (default: the\ngrid's `parallel`). On 2 shared cores both ways took the same time (docs/experiments.md), so the\ngrids run one after another with all threads: each run finishes sooner."
)]
pub struct ExperimentArgs {
    /// The grid file (TOML).
    #[arg(long)]
    pub grid: PathBuf,
    /// Output folder (default: runs/<grid name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Wall minutes for this invocation; unfinished runs resume next time.
    #[arg(long)]
    pub budget_minutes: Option<f64>,
    /// Continue a grid whose output folder already holds runs.
    #[arg(long)]
    pub resume: bool,
    /// Runs trained at once (default: the grid's `parallel`); the cores are split.
    #[arg(long)]
    pub parallel: Option<usize>,
    /// Cores to use in total (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Only (re)write the summary and plots from the run folders; train nothing.
    #[arg(long)]
    pub report_only: bool,
}

pub fn run(a: ExperimentArgs, g: &Global) -> Result<()> {
    if let Some(Err(m)) = a.budget_minutes.map(grasp::util::num::check_minutes) {
        bail!("--budget-minutes {m}");
    }
    if a.parallel == Some(0) {
        bail!("--parallel must be at least 1");
    }
    let grid = grasp::experiment::GridConfig::load(&a.grid)
        .with_context(|| format!("loading grid {}", a.grid.display()))?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(&grid.name));
    let p = plan(&a.grid, &out).with_context(|| format!("planning grid {}", a.grid.display()))?;
    let quiet = g.quiet;
    let log = move |line: &str| {
        if !quiet {
            eprintln!("{line}");
        }
    };
    let n_threads = threads(a.threads)?;
    let mut outcomes = Vec::new();
    if !a.report_only {
        outcomes = run_grid(
            &p,
            &GridOptions {
                budget_minutes: a.budget_minutes,
                resume: a.resume,
                threads: n_threads,
                parallel: a.parallel,
            },
            &log,
        )
        .with_context(|| format!("running grid {}", a.grid.display()))?;
        evaluate_runs(&p, n_threads, g.seed.unwrap_or(0), &log)
            .with_context(|| format!("evaluating the runs of {}", out.display()))?;
    }
    let summary =
        write_reports(&p).with_context(|| format!("writing the reports into {}", out.display()))?;
    if g.json {
        let v = serde_json::json!({ "runs": outcomes, "summary": summary });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print!("{}", markdown(&p, &summary));
        println!(
            "\nwrote {} (summary.md, summary.csv, runs.csv, {} plots)",
            out.display(),
            summary.plots.len()
        );
    }
    Ok(())
}
