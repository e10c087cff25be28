//! `grasp eval`: per-object success rates of trained policies and baselines (Table I).

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::env::api::Env;
use grasp::env::curriculum::CurriculumConfig;
use grasp::env::grasp::{EnvConfig, GraspEnv};
use grasp::env::obs::Modality;
use grasp::eval::{csv_table, evaluate, markdown_table, AgentSpec};
use grasp::robot::{Robot, Side};
use grasp::sim::SimConfig;
use grasp::util::fsx::write_atomic;
use std::path::PathBuf;

use super::rollout::{load_synergy, sim_objects, threads};
use super::Global;

/// Evaluate agents per object on identical initial poses and print a Table-I-style table.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp eval --policy baseline1,baseline2 --objects unseen --trials 10 --markdown\n  grasp eval --policy runs/quick/checkpoints/best --policy baseline2 --objects train --csv table.csv\n  grasp eval --policy assets/policy --objects unseen --json"
)]
pub struct EvalArgs {
    /// Agents: baseline1, baseline2, or a checkpoint folder; repeat or separate by commas.
    #[arg(long, value_delimiter = ',', required = true)]
    pub policy: Vec<String>,
    /// Objects: train, unseen, all, a folder of OBJ/STL, a manifest.toml, or names.
    #[arg(long, default_value = "unseen")]
    pub objects: String,
    /// Trials per object.
    #[arg(long, default_value_t = 10)]
    pub trials: usize,
    /// Print a Markdown table.
    #[arg(long)]
    pub markdown: bool,
    /// Also write one CSV row per (agent, object) to this file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Synergy model (JSON); the shipped model when absent.
    #[arg(long)]
    pub synergy: Option<PathBuf>,
    /// Synergy components the policies act in.
    #[arg(long, default_value_t = 5)]
    pub components: usize,
    /// Sensing modality the policies observe (M1, M2, M3).
    #[arg(long, default_value = "M3")]
    pub modality: Modality,
    /// Curriculum success rate r_s that sets the start-pose randomisation (eq. 6).
    #[arg(long, default_value_t = 1.0)]
    pub difficulty: f64,
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Worker threads (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

fn agent_spec(s: &str) -> Result<AgentSpec> {
    Ok(match s {
        "baseline1" => AgentSpec::Baseline1,
        "baseline2" => AgentSpec::Baseline2,
        path => {
            let p = PathBuf::from(path);
            if !p.join(grasp::ppo::CHECKPOINT_FILE).is_file() {
                bail!(
                    "unknown policy '{path}': expected baseline1, baseline2 or a checkpoint folder containing {}",
                    grasp::ppo::CHECKPOINT_FILE
                );
            }
            AgentSpec::Checkpoint(p)
        }
    })
}

pub fn run(a: EvalArgs, g: &Global) -> Result<()> {
    if a.trials == 0 {
        bail!("--trials must be at least 1");
    }
    if !(0.0..=1.0).contains(&a.difficulty) {
        bail!("--difficulty must be in [0, 1], got {}", a.difficulty);
    }
    let specs = a
        .policy
        .iter()
        .map(|s| agent_spec(s))
        .collect::<Result<Vec<_>>>()?;
    let robot = Robot::builtin(Side::Left);
    let model = load_synergy(a.synergy.as_ref(), a.components)?;
    let sim_cfg = match &a.sim_config {
        Some(p) => SimConfig::load(p).with_context(|| format!("loading {}", p.display()))?,
        None => SimConfig::default(),
    };
    let objects = sim_objects(&a.objects)?;
    let names: Vec<String> = objects.iter().map(|o| o.0.clone()).collect();
    let env_cfg = EnvConfig {
        modality: a.modality,
        curriculum: CurriculumConfig {
            enabled: false,
            fixed_rate: a.difficulty,
            ..CurriculumConfig::default()
        },
        ..EnvConfig::default()
    };
    let make_env = |o: usize| {
        GraspEnv::new(
            &robot,
            vec![objects[o].clone()],
            model.clone(),
            sim_cfg.clone(),
            env_cfg.clone(),
        )
    };
    // A checkpoint must match the observation layout it will see.
    let probe = make_env(0)?;
    for s in &specs {
        if let AgentSpec::Checkpoint(dir) = s {
            let p = grasp::ppo::load_policy(dir)
                .with_context(|| format!("loading checkpoint {}", dir.display()))?;
            if p.policy.obs_dim() != probe.obs_dim() {
                bail!(
                    "checkpoint {} expects observations of length {}, but {:?} with {} components gives {}: pass the --modality and --components it was trained with",
                    dir.display(),
                    p.policy.obs_dim(),
                    a.modality,
                    a.components,
                    probe.obs_dim()
                );
            }
        }
    }
    drop(probe);
    let seed = g.seed.unwrap_or(0);
    let n_threads = threads(a.threads);
    let mut results = Vec::new();
    for s in &specs {
        if !g.quiet {
            eprintln!(
                "evaluating {} on {} objects x {} trials ...",
                s.label(),
                names.len(),
                a.trials
            );
        }
        results.push(evaluate(&names, a.trials, seed, n_threads, &make_env, s)?);
    }
    if let Some(p) = &a.csv {
        write_atomic(p, csv_table(&results).as_bytes())?;
    }
    if g.json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else if a.markdown {
        print!("{}", markdown_table(&results));
    } else {
        for r in &results {
            println!(
                "{}: mean success {:.1} % (95 % CI {:.1}-{:.1}), {:.2} steps per episode, {:.1} control steps/s",
                r.agent,
                100.0 * r.mean_rate,
                100.0 * r.ci95.0,
                100.0 * r.ci95.1,
                r.mean_steps,
                r.control_steps_per_s
            );
            for o in &r.objects {
                println!(
                    "  {:<22} {:>3}/{:<3} {:>5.0} %  [{:>3.0}, {:>3.0}]",
                    o.object,
                    o.successes,
                    o.trials,
                    100.0 * o.rate,
                    100.0 * o.ci95.0,
                    100.0 * o.ci95.1
                );
            }
        }
    }
    Ok(())
}
