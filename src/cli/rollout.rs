//! `grasp rollout`: run a scripted or random agent on the grasping MDP, for debugging.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::env::curriculum::CurriculumConfig;
use grasp::env::grasp::{run_episode, EnvConfig, EpisodeSummary, GraspEnv, RandomAgent};
use grasp::eval::record::{
    record_agent_episode, record_baseline_episode, write_recording, RecordingEntry,
};
use grasp::robot::{Robot, Side};
use grasp::util::signal;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

use super::{load_synergy, sim_objects, threads, Global};

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

/// One episode's result: its index, its summary and its recording (with `--record`).
type Done = (usize, EpisodeSummary, Option<RecordingEntry>);

pub fn run(a: RolloutArgs, g: &Global) -> Result<()> {
    let kind = agent_kind(&a)?;
    let seed = g.seed.unwrap_or(0);
    let n_threads = threads(a.threads)?.min(a.episodes);
    let start = Instant::now();
    signal::stop_on_signal(
        "finishing the episodes in progress, then printing them",
        g.quiet,
    )
    .context("installing the Ctrl-C and SIGTERM handler")?;
    let record_errors = std::sync::Mutex::new(Vec::new());
    let mut done = run_episodes(&a, kind, seed, n_threads, &record_errors)?;
    let wall = start.elapsed().as_secs_f64();
    done.sort_by_key(|d| d.0);
    let interrupted = signal::stopped();
    if interrupted && done.is_empty() {
        super::exit_interrupted(" before any episode finished: nothing to report", false);
    }
    // The episodes are printed before any file is written: a failed write loses nothing.
    let all: Vec<(usize, EpisodeSummary)> = done.iter().map(|d| (d.0, d.1.clone())).collect();
    report(&a, g, seed, &all, wall, n_threads)?;
    if let Some(dir) = &a.rec.record {
        let entries: Vec<RecordingEntry> = done.iter().filter_map(|d| d.2.clone()).collect();
        let errors = record_errors.into_inner().unwrap_or_default();
        super::finish_recordings(dir, &entries, &errors, g.quiet)?;
    }
    if interrupted {
        super::exit_interrupted(
            &format!(
                ": {} of {} episodes finished, printed above",
                all.len(),
                a.episodes
            ),
            g.quiet,
        );
    }
    Ok(())
}

/// The agent of `--policy` (0: random, 1 and 2: the baselines), after checking the other
/// flags.
fn agent_kind(a: &RolloutArgs) -> Result<u8> {
    let kind = match a.policy.as_str() {
        "baseline1" => 1,
        "baseline2" => 2,
        "random" => 0,
        other => bail!("unknown policy '{other}': expected baseline1, baseline2 or random"),
    };
    if a.episodes == 0 {
        bail!("--episodes must be at least 1");
    }
    a.rec.check()?;
    super::check_difficulty(a.difficulty)?;
    Ok(kind)
}

/// Runs (and with `--record`, records) every episode on `n_threads` threads. Episode i
/// always runs the scene of seed (seed, i): outcomes do not depend on the number of
/// threads.
fn run_episodes(
    a: &RolloutArgs,
    kind: u8,
    seed: u64,
    n_threads: usize,
    record_errors: &std::sync::Mutex<Vec<String>>,
) -> Result<Vec<Done>> {
    let robot = Robot::builtin(Side::Left);
    let model = load_synergy(a.synergy.as_ref(), a.components)?;
    let sim_cfg = super::sim_config(a.sim_config.as_ref())?;
    let objects = sim_objects(&a.objects)?;
    let env_cfg = EnvConfig {
        curriculum: CurriculumConfig::fixed(a.difficulty),
        ..EnvConfig::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n_threads)
        .build()
        .context("building the thread pool")?;
    let chunks: Vec<Vec<usize>> = (0..n_threads)
        .map(|t| (t..a.episodes).step_by(n_threads).collect())
        .collect();
    let results: Vec<Vec<Done>> = pool.install(|| {
        chunks
            .par_iter()
            .map(|idx| -> Result<Vec<Done>> {
                let mut env = GraspEnv::new(
                    &robot,
                    objects.clone(),
                    model.clone(),
                    sim_cfg.clone(),
                    env_cfg.clone(),
                )?;
                let n = model.n_components() + 2;
                idx.iter()
                    .take_while(|_| !signal::stopped())
                    .map(|&i| {
                        let s = grasp::env::api::episode_seed(seed, 0, i as u64);
                        if let Some(dir) = &a.rec.record {
                            let rec = match kind {
                                0 => record_agent_episode(
                                    &mut env,
                                    &mut RandomAgent::new(n, 0.15, s),
                                    &a.policy,
                                    s,
                                    a.rec.record_every,
                                ),
                                k => record_baseline_episode(
                                    &mut env,
                                    k == 2,
                                    &a.policy,
                                    s,
                                    a.rec.record_every,
                                )?,
                            };
                            if a.rec.record_failures && !rec.summary.physics_failure {
                                return Ok((i, rec.summary, None));
                            }
                            // A recording that cannot be written (a full disk) does not
                            // end the rollout: said after the episodes are printed.
                            let entry = match write_recording(dir, &rec, i, 0) {
                                Ok(e) => Some(e),
                                Err(e) => {
                                    if let Ok(mut v) = record_errors.lock() {
                                        v.push(e.to_string());
                                    }
                                    None
                                }
                            };
                            return Ok((i, rec.summary, entry));
                        }
                        let r = match kind {
                            0 => run_episode(&mut env, &mut RandomAgent::new(n, 0.15, s), s),
                            k => env.run_baseline(k == 2, s)?,
                        };
                        Ok((i, r, None))
                    })
                    .collect()
            })
            .collect::<Result<Vec<_>>>()
    })?;
    Ok(results.into_iter().flatten().collect())
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
