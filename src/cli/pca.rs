//! `grasp pca`: fit hand synergies to a pose dataset and look at them.

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::joints::FINGER_JOINTS;
use grasp::robot::{Robot, Side};
use grasp::synergy::collect::{self, CollectOptions};
use grasp::synergy::{draw, finger_limits, Dataset, LoadOptions, SynergyModel};
use grasp::util::fsx::write_atomic;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use super::Global;

/// Hand synergies: PCA of finger postures (Sec. III of the paper).
#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  grasp pca collect --out poses.csv --samples 3000 --seed 7
  grasp pca fit poses.csv --components 5 --out synergy_model.json
  grasp pca show synergy_model.json --out postures.svg")]
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
    /// Show the first three synergies: joint ranges, or hand postures as an SVG figure.
    #[command(after_help = "\
Each synergy Ck is shown at -2, -1, 0, +1 and +2 standard deviations (sqrt of its
eigenvalue) from the mean posture, made feasible (clamped to the joint limits, J1 = J2 in
the coupled fingers). Without --out the joint ranges are printed; with --out the postures
are drawn as stick figures (palm-side and side views, like Fig. 2b of the paper).

Examples:
  grasp pca show synergy_model.json
  grasp pca show synergy_model.json --out postures.svg
  grasp --json pca show synergy_model.json")]
    Show(ShowArgs),
    /// Make a pose dataset: close the simulated hand on objects from GRASP-taxonomy
    /// preshapes and record the finger angles at stable contact.
    #[command(after_help = "\
Samples cycle through 23 of the 33 grasp types of the GRASP taxonomy (Feix et al. 2016);
each draws a box or cylinder of a size that suits it (2-10 cm, 50-500 g, friction 0.8), a
hand yaw and height; the hand starts above the object in the type's preshape and closes
toward its closed posture, each joint stopping at its target or torque limit. The 22 finger
angles are recorded at stable contact (>= 2 fingertips touching, or a steady hand-object
force), checked against the joint limits and for self-collision, and given uniform noise
of at most 0.02 rad. The same seed gives the same file on any number of threads. The CSV
has the 22 lh_/rh_ joint columns and a grasp_type column (ignored by `pca fit`).

Examples:
  grasp pca collect --out poses.csv
  grasp pca collect --out small.csv --samples 200 --seed 7
  grasp --json pca collect --out poses.csv --samples 3000 --seed 1")]
    Collect(CollectArgs),
}

#[derive(Debug, Args)]
pub struct CollectArgs {
    /// Where to write the dataset (CSV).
    #[arg(long, default_value = "poses.csv")]
    pub out: PathBuf,
    /// Number of postures to record.
    #[arg(long, default_value_t = 3000,
          value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub samples: u32,
    /// Attempts per sample before the collection fails.
    #[arg(long, default_value_t = 50,
          value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub max_attempts: u32,
    /// Which hand.
    #[arg(long, default_value = "left")]
    pub hand: Side,
    /// Simulator configuration (TOML); the built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
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

#[derive(Debug, Args)]
pub struct ShowArgs {
    /// The synergy model (JSON, from `grasp pca fit`).
    pub model: PathBuf,
    /// Write the posture figure (SVG) here instead of printing joint ranges.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Which hand draws the postures and limits them.
    #[arg(long, default_value = "left")]
    pub hand: Side,
}

pub fn run(args: PcaArgs, g: &Global) -> Result<()> {
    match args.command {
        PcaCommand::Fit(a) => fit(a, g),
        PcaCommand::Show(a) => show(a, g),
        PcaCommand::Collect(a) => collect(a, g),
    }
}

/// Refuses an output (`flag`, `out`) that is one of `inputs` (flag, path) or that cannot
/// be written.
fn check_out(inputs: &[(&str, Option<&PathBuf>)], flag: &str, out: &Path) -> Result<()> {
    use grasp::util::fsx::{check_outputs, Named};
    let named: Vec<Named> = inputs
        .iter()
        .filter_map(|&(f, p)| p.map(|p| Named::new(f, p)))
        .collect();
    check_outputs(&named, &[Named::new(flag, out)], &[])?;
    // Checked before the work: a collection is not thrown away by its write.
    grasp::util::fsx::check_writable_file(out)
        .map_err(|e| anyhow::anyhow!("{flag} {}: {}", out.display(), e.source))?;
    Ok(())
}

fn collect(a: CollectArgs, g: &Global) -> Result<()> {
    check_out(&[("--sim-config", a.sim_config.as_ref())], "--out", &a.out)?;
    let cfg = super::sim_config(a.sim_config.as_ref())?;
    let robot = Robot::builtin(a.hand);
    let opts = CollectOptions {
        samples: a.samples as usize,
        seed: g.seed.unwrap_or(0),
        max_attempts: a.max_attempts as usize,
    };
    let bar = if std::io::stderr().is_terminal() && !g.quiet {
        let b = ProgressBar::new(opts.samples as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} postures, {elapsed} (eta {eta})")
        {
            b.set_style(style);
        }
        b
    } else {
        ProgressBar::hidden()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(super::threads(a.threads)?)
        .build()
        .context("cannot start the worker threads")?;
    let t0 = std::time::Instant::now();
    let result = pool.install(|| collect::collect(&robot, &cfg, &opts, &|| bar.inc(1)));
    bar.finish_and_clear();
    let out = result?;
    let seconds = t0.elapsed().as_secs_f64();
    out.write_csv(&a.out, a.hand)
        .with_context(|| format!("cannot write the dataset {}", a.out.display()))?;
    let s = &out.stats;
    if g.json {
        let v = serde_json::json!({
            "out": a.out.display().to_string(),
            "samples": out.poses.len(),
            "seed": opts.seed,
            "seconds": seconds,
            "stats": s,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else if !g.quiet {
        println!(
            "Collected {} postures (seed {}) into {} in {seconds:.1} s",
            out.poses.len(),
            opts.seed,
            a.out.display()
        );
        println!(
            "attempts {}: rejected {} physics failure, {} no stable contact, {} outside limits, \
             {} self-collision",
            s.attempts, s.physics_failure, s.no_stable_contact, s.outside_limits, s.self_collision
        );
        println!("{:>20}  {:>8}  {:>8}", "grasp type", "postures", "attempts");
        for (name, n, tries) in &s.per_type {
            println!("{name:>20}  {n:>8}  {tries:>8}");
        }
    }
    Ok(())
}

fn show(a: ShowArgs, g: &Global) -> Result<()> {
    if let Some(out) = &a.out {
        check_out(&[("MODEL", Some(&a.model))], "--out", out)?;
    }
    let model = SynergyModel::load(&a.model)?;
    let limits = finger_limits(a.hand);
    let rows = model.n_components().min(draw::FIGURE_COMPONENTS);
    if let Some(out) = &a.out {
        let robot = Robot::builtin(a.hand);
        let svg = draw::synergies_svg(&robot, &model, &limits)
            .with_context(|| format!("cannot draw the synergies of {}", a.model.display()))?;
        write_atomic(out, svg.as_bytes())?;
        if g.json {
            let v = serde_json::json!({ "model": a.model.display().to_string(),
                                        "svg": out.display().to_string(), "rows": rows });
            println!("{}", serde_json::to_string_pretty(&v)?);
        } else if !g.quiet {
            println!(
                "Drew synergies C1-C{rows} of {} at {:?} sigma into {}",
                a.model.display(),
                draw::SIGMA_STEPS,
                out.display()
            );
        }
        return Ok(());
    }
    let ranges: Vec<_> = (0..rows)
        .map(|k| draw::joint_ranges(&model, k, &limits))
        .collect();
    if g.json {
        let comps: Vec<_> = ranges
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let joints: serde_json::Map<String, serde_json::Value> = FINGER_JOINTS
                    .iter()
                    .zip(r)
                    .map(|(j, (lo, hi))| (j.to_string(), serde_json::json!([lo, hi])))
                    .collect();
                serde_json::json!({
                    "component": k + 1,
                    "eigenvalue": model.eigenvalues()[k],
                    "sigma": model.eigenvalues()[k].sqrt(),
                    "explained_variance_ratio": model.explained_variance_ratio()[k],
                    "joint_ranges": joints,
                })
            })
            .collect();
        let v = serde_json::json!({
            "model": a.model.display().to_string(),
            "sigma_steps": draw::SIGMA_STEPS,
            "components": comps,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!(
        "{}: {} components from {} samples; joint ranges (rad) over -2..+2 sigma, feasible",
        a.model.display(),
        model.n_components(),
        model.n_samples()
    );
    print!("{:>6}", "joint");
    for k in 0..rows {
        print!(
            "  {:>17}",
            format!(
                "C{} ({:.1} %)",
                k + 1,
                100.0 * model.explained_variance_ratio()[k]
            )
        );
    }
    println!();
    for (j, name) in FINGER_JOINTS.iter().enumerate() {
        let mut line = format!("{name:>6}");
        for r in &ranges {
            line.push_str(&format!("  {:>8.3}..{:<7.3}", r[j].0, r[j].1));
        }
        println!("{}", line.trim_end());
    }
    Ok(())
}

fn fit(a: FitArgs, g: &Global) -> Result<()> {
    check_out(&[("DATASET", Some(&a.dataset))], "--out", &a.out)?;
    let n = usize::from(a.components);
    if !(a.tolerance.is_finite() && a.tolerance >= 0.0) {
        anyhow::bail!(
            "--tolerance must be a finite number >= 0, got {}",
            grasp::util::num::short(a.tolerance)
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
    if model.rank() < n {
        bail!(
            "cannot fit {n} synergies to {}: its postures vary along only {} independent \
             direction(s) (the other eigenvalues are round-off, below {:e} times the largest); \
             ask for at most {} with --components",
            a.dataset.display(),
            model.rank(),
            grasp::synergy::pca::RANK_TOLERANCE,
            model.rank()
        );
    }
    model.save(&a.out)?;

    let cumulative = model.cumulative_ratio();
    let per_joint = model.per_joint_explained(&data.rows);
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
            "per_joint_explained": FINGER_JOINTS
                .iter()
                .zip(&per_joint)
                .map(|(j, v)| (j.to_string(), serde_json::json!(v)))
                .collect::<serde_json::Map<_, _>>(),
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
    println!("variance of each joint explained by the {n} kept components (%):");
    for (names, values) in FINGER_JOINTS.chunks(6).zip(per_joint.chunks(6)) {
        let line: Vec<String> = names
            .iter()
            .zip(values)
            .map(|(j, v)| format!("{j:>5} {:>5.1}", 100.0 * v))
            .collect();
        println!("  {}", line.join("  "));
    }
    Ok(())
}
