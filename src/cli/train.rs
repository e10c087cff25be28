//! `grasp train`: run PPO from a config file into a run folder.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::train::{OpenOptions, StopReason, TrainConfig, TrainSession};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use super::Global;

/// Train a policy with PPO as a config file describes.
///
/// The run folder (default runs/<name>) receives config.toml, metrics.csv (one row per
/// update), a TensorBoard event file, checkpoints/latest and checkpoints/best, and
/// learning_curve.svg. Every file is replaced atomically: after a crash or kill -9,
/// `--resume` continues from checkpoints/latest, dropping the metrics rows recorded after
/// it. With checkpoint_every = 1 (the default) at most one update is lost. Ctrl-C (SIGINT)
/// or SIGTERM (a scheduler's or `timeout`'s stop) finishes the update in progress, writes
/// checkpoints/latest and exits with status 130; a second one exits at once. One process
/// at a time trains in a folder (a second is refused while the first holds its lock).
/// A folder whose run stopped during its first update starts afresh; nothing recorded
/// is ever deleted: a folder with metrics rows but no checkpoints/latest is refused with
/// what to do, and `--resume` refuses a changed [env] unless --allow-env-change.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp train --config configs/cartpole.toml\n  grasp train --config configs/quick.toml --out runs/quick1 --seed 3\n  grasp train --config configs/gru_m3_pca5.toml --time-budget-minutes 60\n  grasp train --config configs/gru_m3_pca5.toml --resume\n  grasp train --config configs/stream.toml --objects procedural\n  grasp train --config configs/base.toml --total-timesteps 20000 --num-envs 4 --json\n\nThe global --seed overrides the config's seed."
)]
pub struct TrainArgs {
    /// Training config (TOML; may name a `base` config to inherit from).
    #[arg(long)]
    pub config: PathBuf,
    /// Run folder (default: runs/<name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Continue the run in the folder from its latest checkpoint.
    #[arg(long)]
    pub resume: bool,
    /// With --resume: continue even though the config's [env] table or object set
    /// (`objects`, --objects) differs from the one the checkpoint was trained under
    /// (otherwise refused, naming the keys).
    #[arg(long, requires = "resume")]
    pub allow_env_change: bool,
    /// Override the config's planned number of transitions.
    #[arg(long)]
    pub total_timesteps: Option<u64>,
    /// Override the config's number of parallel environments.
    #[arg(long)]
    pub num_envs: Option<usize>,
    /// Override the config's wall-clock budget: stop cleanly, with a checkpoint, after
    /// this many minutes.
    #[arg(long, allow_negative_numbers = true)]
    pub time_budget_minutes: Option<f64>,
    /// Override the config's object set: train, unseen, a folder, a manifest, names, or
    /// `procedural` (a fresh procedural object every few episodes, see `[env.stream]`).
    #[arg(long)]
    pub objects: Option<String>,
}

pub fn run(a: TrainArgs, g: &Global) -> Result<()> {
    let mut cfg = TrainConfig::load(&a.config)
        .with_context(|| format!("loading training config {}", a.config.display()))?;
    if let Some(s) = g.seed {
        cfg.seed = s;
    }
    if let Some(n) = a.total_timesteps {
        cfg.total_timesteps = n;
    }
    if let Some(n) = a.num_envs {
        cfg.num_envs = n;
    }
    if let Some(m) = a.time_budget_minutes {
        if let Err(e) = grasp::util::num::check_minutes(m) {
            bail!("--time-budget-minutes {e} (it overrides the config's time_budget_minutes)");
        }
        cfg.time_budget_minutes = Some(m);
    }
    if let Some(o) = &a.objects {
        if cfg.env.kind != grasp::train::EnvKind::Grasp {
            bail!(
                "--objects {o}: {} trains the cart-pole (`[env] kind = \"cartpole\"`), which \
                 has no objects; --objects applies to the grasping environment",
                a.config.display()
            );
        }
        cfg.objects = o.clone();
    }
    cfg.validate(&a.config)
        .context("invalid value given on the command line")?;
    let unused = cfg.env.grasp.randomization.changed();
    if !cfg.env.grasp.randomization.enabled && !unused.is_empty() && !g.quiet {
        eprintln!(
            "warning: {}: [env.randomization] sets {} but not `enabled = true`: training \
             randomises nothing",
            a.config.display(),
            unused.join(", ")
        );
    }
    let dir = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(&cfg.name));
    let opts = OpenOptions {
        resume: a.resume,
        allow_env_change: a.allow_env_change,
    };
    let mut session = TrainSession::open_with(cfg, &dir, opts)
        .with_context(|| format!("preparing run folder {}", dir.display()))?;
    let target = if g.quiet || g.json {
        ProgressDrawTarget::hidden()
    } else {
        // Hidden by indicatif when stderr is not a terminal.
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(None, target);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} transitions ({eta} left) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let quiet = g.quiet;
        ctrlc::set_handler(move || {
            if stop.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
            if !quiet {
                eprintln!(
                    "\ninterrupted (SIGINT or SIGTERM): finishing the update in progress, \
                     then writing a checkpoint (Ctrl-C again to quit at once)"
                );
            }
        })
        .context("installing the Ctrl-C and SIGTERM handler")?;
    }
    session.set_stop_flag(Arc::clone(&stop));
    let start_step = session.trainer().global_step();
    bar.set_position(start_step);
    let summary = session
        .run(&mut |p| {
            bar.set_length(p.planned_steps);
            bar.set_position(p.row.global_step);
            let succ = p
                .row
                .stats
                .success_rate
                .map_or_else(|| "-".into(), |s| format!("{:.0}%", 100.0 * s));
            let ret = p
                .row
                .stats
                .episode_return
                .map_or_else(|| "-".into(), |r| format!("{r:.1}"));
            bar.set_message(format!(
                "upd {}/{} | {} episodes | success {succ} | return {ret} | {:.0} tr/s",
                p.row.update, p.planned_updates, p.row.episodes, p.row.transitions_per_s
            ));
        })
        .with_context(|| format!("training into {}", dir.display()))?;
    bar.finish_and_clear();
    if g.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else if !g.quiet {
        let fmt = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |x| format!("{x:.3}"));
        let why = match summary.stop {
            StopReason::Completed => "completed",
            StopReason::TimeBudget => "time budget reached",
            StopReason::Interrupted => "interrupted",
        };
        println!(
            "{why}: {} updates ({} new), {} transitions, {} episodes in {:.1} s; last success \
             {}, last return {}, best score {}; run folder {}",
            summary.updates,
            summary.new_updates,
            summary.global_step,
            summary.episodes,
            summary.wall_s,
            fmt(summary.last_success_rate),
            fmt(summary.last_return),
            fmt(summary.best_score),
            summary.run_dir.display()
        );
    }
    if summary.stop == StopReason::Interrupted {
        use std::io::Write;
        let _ = std::io::stdout().flush();
        // 128 + SIGINT, as a shell reports a process ended by Ctrl-C.
        std::process::exit(130);
    }
    Ok(())
}
