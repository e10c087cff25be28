//! `grasp pca`: fit hand synergies to a pose dataset and look at them.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::Side;
use grasp::synergy::{finger_limits, Dataset, LoadOptions, SynergyModel};
use std::path::PathBuf;

use super::Global;

/// Hand synergies: PCA of finger postures (Sec. III of the paper).
#[derive(Debug, Args)]
pub struct PcaArgs {
    #[command(subcommand)]
    pub command: PcaCommand,
}

#[derive(Debug, Subcommand)]
pub enum PcaCommand {
    /// Fit a synergy model to a CSV pose dataset and print the eigenvalue table.
    #[command(after_help = "\
The dataset's header names the 22 finger joints (FFJ4..THJ1, with or without rh_/lh_
prefixes, any case, any order); other columns are ignored. Angles are radians.

Examples:
  grasp pca fit poses.csv
  grasp pca fit poses.csv --components 3 --out pca3.json
  grasp --json pca fit poses.csv > table.json")]
    Fit(FitArgs),
}

#[derive(Debug, Args)]
pub struct FitArgs {
    /// The pose dataset (CSV).
    pub dataset: PathBuf,
    /// Number of synergies to keep (1-22; the paper compares 3, 5, 8 and 10).
    #[arg(short = 'n', long, default_value_t = 5,
          value_parser = clap::value_parser!(u16).range(1..=22))]
    pub components: u16,
    /// Where to write the model (JSON).
    #[arg(long, default_value = "synergy_model.json")]
    pub out: PathBuf,
    /// Which hand's joint limits check the data.
    #[arg(long, default_value = "left")]
    pub hand: Side,
    /// How far (rad) an angle may exceed its joint limits before it is an error.
    #[arg(long, default_value_t = grasp::synergy::dataset::DEFAULT_LIMIT_TOLERANCE)]
    pub tolerance: f64,
}

pub fn run(args: PcaArgs, g: &Global) -> Result<()> {
    match args.command {
        PcaCommand::Fit(a) => fit(a, g),
    }
}

fn fit(a: FitArgs, g: &Global) -> Result<()> {
    let n = usize::from(a.components);
    if !(a.tolerance.is_finite() && a.tolerance >= 0.0) {
        anyhow::bail!(
            "--tolerance must be a finite number >= 0, got {}",
            a.tolerance
        );
    }
    let opts = LoadOptions {
        tolerance: a.tolerance,
        min_rows: n.max(2),
        min_rows_reason: format!(" to fit {n} component(s)"),
    };
    let data = Dataset::load(&a.dataset, &finger_limits(a.hand), &opts)?;
    if !data.extras.is_empty() && !g.quiet {
        eprintln!(
            "note: ignored column(s) in {}: {}",
            a.dataset.display(),
            data.extras.join(", ")
        );
    }
    let model = SynergyModel::fit(&data.rows, n)
        .with_context(|| format!("cannot fit synergies to {}", a.dataset.display()))?
        .with_source(a.dataset.display().to_string());
    model.save(&a.out)?;

    let cumulative = model.cumulative_ratio();
    if g.json {
        let rows: Vec<_> = (0..model.eigenvalues().len())
            .map(|k| {
                serde_json::json!({
                    "component": k + 1,
                    "eigenvalue": model.eigenvalues()[k],
                    "explained_variance_ratio": model.explained_variance_ratio()[k],
                    "cumulative_ratio": cumulative[k],
                    "kept": k < n,
                })
            })
            .collect();
        let out = serde_json::json!({
            "dataset": a.dataset.display().to_string(),
            "model": a.out.display().to_string(),
            "n_samples": model.n_samples(),
            "n_components": n,
            "ignored_columns": data.extras,
            "components": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "Fitted {n} synergies to {} postures from {}; model written to {}",
        model.n_samples(),
        a.dataset.display(),
        a.out.display()
    );
    println!(
        "{:>9}  {:>12}  {:>9}  {:>10}",
        "component", "eigenvalue", "ratio", "cumulative"
    );
    let table = model
        .eigenvalues()
        .iter()
        .zip(model.explained_variance_ratio())
        .zip(&cumulative);
    for (k, ((e, r), c)) in table.enumerate() {
        let mark = if k < n { "*" } else { " " };
        println!("{:>8}{mark}  {e:>12.5e}  {r:>9.5}  {c:>10.5}", k + 1);
    }
    println!("(* kept in the model)");
    Ok(())
}
