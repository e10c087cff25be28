//! `grasp rollout`: run a scripted or random agent on the grasping MDP, for debugging.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::env::grasp::EpisodeSummary;
use grasp::eval::record::RecordOptions;
use grasp::eval::rollout::{rollout, RolloutRequest, ScriptedAgent};
use grasp::util::signal;
use std::path::PathBuf;
use std::time::Instant;

use super::Global;

/// Run episodes of a baseline or a random agent and print each outcome and a summary.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp rollout --policy baseline2 --objects train --episodes 20\n  grasp rollout --policy random --objects box_sugar,bottle_tall --episodes 8 --json\n  grasp rollout --policy baseline2 --objects can_soup --episodes 2 --record rec/ && xdg-open rec/index.html"
)]
pub struct RolloutArgs {
    /// The agent: baseline1, baseline2 or random.
    #[arg(long, default_value = "baseline2")]
    pub policy: String,
    /// Objects: train, unseen, all, a folder of OBJ/STL, a manifest.toml, or names.
    #[arg(long, default_value = "train")]
    pub objects: String,
    /// Number of episodes.
    #[arg(long, default_value_t = 10)]
    pub episodes: usize,
    /// Synergy model (JSON); the shipped model when absent.
    #[arg(long)]
    pub synergy: Option<PathBuf>,
    /// Number of synergy components the agent acts in (the model's first n).
    #[arg(long, default_value_t = 5)]
    pub components: usize,
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Curriculum success rate r_s that sets the start-pose randomisation (eq. 6).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub difficulty: f64,
    /// Worker threads (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub rec: super::RecordArgs,
}

pub fn run(a: RolloutArgs, g: &Global) -> Result<()> {
    let agent = check_flags(&a)?;
    let req = RolloutRequest {
        agent,
        name: a.policy.clone(),
        objects: a.objects.clone(),
        episodes: a.episodes,
        synergy: a.synergy.clone(),
        components: a.components,
        sim_config: a.sim_config.clone(),
        difficulty: a.difficulty,
        threads: a.threads,
        record: a.rec.record.as_ref().map(|dir| RecordOptions {
            dir: dir.clone(),
            every: a.rec.record_every,
            only_failures: a.rec.record_failures,
            name: None,
        }),
        seed: g.seed.unwrap_or(0),
    };
    let start = Instant::now();
    signal::stop_on_signal(
        "finishing the episodes in progress, then printing them",
        g.quiet,
    )
    .context("installing the Ctrl-C and SIGTERM handler")?;
    let out = rollout(&req, Some(&signal::STOP))?;
    let wall = start.elapsed().as_secs_f64();
    let interrupted = signal::stopped();
    if interrupted && out.episodes.is_empty() {
        super::exit_interrupted(" before any episode finished: nothing to report", false);
    }
    // The episodes are printed before any file is written: a failed write loses nothing.
    report(&a, g, req.seed, &out.episodes, wall, out.threads)?;
    if let Some(dir) = &a.rec.record {
        super::finish_recordings(dir, &out.recordings, &out.record_errors, g.quiet)?;
    }
    if interrupted {
        super::exit_interrupted(
            &format!(
                ": {} of {} episodes finished, printed above",
                out.episodes.len(),
                a.episodes
            ),
            g.quiet,
        );
    }
    Ok(())
}

/// The agent of `--policy`, after checking the other flags.
fn check_flags(a: &RolloutArgs) -> Result<ScriptedAgent> {
    let agent = ScriptedAgent::parse(&a.policy).map_err(anyhow::Error::msg)?;
    if a.episodes == 0 {
        bail!("--episodes must be at least 1");
    }
    a.rec.check()?;
    super::check_difficulty(a.difficulty)?;
    Ok(agent)
}

/// Prints the episodes and their totals (a table, or JSON with `--json`).
fn report(
    a: &RolloutArgs,
    g: &Global,
    seed: u64,
    all: &[(usize, EpisodeSummary)],
    wall: f64,
    n_threads: usize,
) -> Result<()> {
    let n = all.len() as f64;
    let successes = all.iter().filter(|(_, r)| r.success).count();
    let failures = all.iter().filter(|(_, r)| r.physics_failure).count();
    let mean_steps = all.iter().map(|(_, r)| r.steps as f64).sum::<f64>() / n;
    if g.json {
        let out = serde_json::json!({
            "policy": a.policy,
            "objects": a.objects,
            "seed": seed,
            "episodes": all.iter().map(|(i, r)| serde_json::json!({"episode": i, "result": r})).collect::<Vec<_>>(),
            "success_rate": successes as f64 / n,
            "physics_failures": failures,
            "mean_steps": mean_steps,
            "wall_s": wall,
            "episodes_per_s": n / wall,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "{:>4}  {:<22} {:>7} {:>5} {:>8} {:>6}",
        "ep", "object", "success", "steps", "return", "lifted"
    );
    for (i, r) in all {
        let flag = if r.physics_failure {
            "  (physics failure)"
        } else {
            ""
        };
        println!(
            "{:>4}  {:<22} {:>7} {:>5} {:>8.3} {:>6}{flag}",
            i, r.object, r.success, r.steps, r.episode_return, r.lifted
        );
    }
    println!(
        "{}: {successes}/{} successes ({:.1} %), {failures} physics failures, {:.2} steps per episode, {:.2} episodes/s on {n_threads} threads",
        a.policy,
        all.len(),
        100.0 * successes as f64 / n,
        mean_steps,
        n / wall
    );
    Ok(())
}
