//! `grasp bench`: throughput measurements.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::{Robot, Side};
use grasp::sim::bench::{self, BenchFigures};
use grasp::sim::SimConfig;
use std::path::PathBuf;

use super::Global;

/// Measure throughput.
#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub command: BenchCommand,
}

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Simulator throughput: scripted close-and-lift episodes on one env, then on --envs
    /// envs in one rayon pool of --threads threads (default: the number of cores).
    #[command(
        after_help = "Examples:\n  grasp bench sim\n  grasp bench sim --envs 20 --seconds 10 --json"
    )]
    Sim(BenchSimArgs),
    /// Grasping-environment throughput: --envs environments with a random agent stepped
    /// in one VecEnv (the learner's harness), environment steps per second.
    #[command(after_help = "Example:\n  grasp bench env --envs 20 --seconds 20 --json")]
    Env(BenchEnvArgs),
    /// CI regression check: a fixed-seed evaluation of baseline 2 and the shipped policy
    /// on a few objects plus the environment throughput, printed as JSON and compared
    /// with the committed reference (success counts within ±1 episode per agent,
    /// throughput at least 0.3x when measured in the same build profile as the reference:
    /// .ci/run uses the dev profile); exits non-zero naming each regressed figure.
    #[command(
        after_help = "Examples:\n  cargo run -- bench regression            # as .ci/run does (dev profile)\n  cargo run -- bench regression --update   # rewrite ci/reference.json after an intended change"
    )]
    Regression(BenchRegressionArgs),
}

#[derive(Debug, Args)]
pub struct BenchRegressionArgs {
    /// The reference figures (JSON).
    #[arg(long, default_value = "ci/reference.json")]
    pub reference: PathBuf,
    /// Write the measured figures as the new reference (atomically) instead of comparing.
    #[arg(long)]
    pub update: bool,
    /// The policy checkpoint folder.
    #[arg(long, default_value = "assets/policies/quick_gru_m3_pca5")]
    pub policy: PathBuf,
    /// Objects.
    #[arg(long, default_value = "box_gelatin,cylinder_wood,can_soup,apple")]
    pub objects: String,
    /// Trials per object.
    #[arg(long, default_value_t = 3)]
    pub trials: usize,
    /// Threads (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Environments of the throughput measurement.
    #[arg(long, default_value_t = 4)]
    pub envs: usize,
    /// Environment steps of the throughput measurement.
    #[arg(long, default_value_t = 200)]
    pub steps: usize,
}

#[derive(Debug, Args)]
pub struct BenchEnvArgs {
    /// Objects the environments draw from.
    #[arg(long, default_value = "train")]
    pub objects: String,
    /// Environments stepped in parallel.
    #[arg(long, default_value_t = 20)]
    pub envs: usize,
    /// Threads of the pool (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Wall seconds to measure.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
}

#[derive(Debug, Args)]
pub struct BenchSimArgs {
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Environments stepped in parallel for the second measurement.
    #[arg(long, default_value_t = 20)]
    pub envs: usize,
    /// Threads of the pool (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Wall seconds per measurement.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
}

pub fn run(a: BenchArgs, g: &Global) -> Result<()> {
    match a.command {
        BenchCommand::Sim(a) => sim(a, g),
        BenchCommand::Env(a) => env(a, g),
        BenchCommand::Regression(a) => regression(a, g),
    }
}

fn regression(a: BenchRegressionArgs, g: &Global) -> Result<()> {
    use grasp::eval::regression::{compare, measure, Reference, RegressionSetup};
    if a.trials == 0 || a.envs == 0 || a.steps == 0 {
        anyhow::bail!("--trials, --envs and --steps must be at least 1");
    }
    // Read the reference first: a broken file is reported before minutes of measuring.
    let reference = if a.update {
        None
    } else {
        let text = std::fs::read_to_string(&a.reference).with_context(|| {
            format!(
                "reading the reference {} (create it with --update)",
                a.reference.display()
            )
        })?;
        let r: Reference = serde_json::from_str(&text)
            .with_context(|| format!("parsing the reference {}", a.reference.display()))?;
        Some(r)
    };
    let setup = RegressionSetup {
        objects: super::rollout::sim_objects(&a.objects)?,
        trials: a.trials,
        seed: g.seed.unwrap_or(0),
        policy: a.policy.clone(),
        threads: super::rollout::threads(a.threads)?,
        throughput_envs: a.envs,
        throughput_steps: a.steps,
    };
    let figures =
        measure(&setup).with_context(|| format!("measuring with {}", a.policy.display()))?;
    let Some(reference) = reference else {
        let r = Reference::from_figures(figures);
        let text = serde_json::to_string_pretty(&r)? + "\n";
        grasp::util::fsx::write_atomic(&a.reference, text.as_bytes())
            .with_context(|| format!("writing {}", a.reference.display()))?;
        println!("{text}");
        if !g.quiet {
            eprintln!("wrote the new reference {}", a.reference.display());
        }
        return Ok(());
    };
    let regressions = compare(&figures, &reference);
    let out = serde_json::json!({
        "figures": figures,
        "reference": reference.figures,
        "regressions": regressions,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    if !regressions.is_empty() {
        anyhow::bail!(
            "regression against {}: {}",
            a.reference.display(),
            regressions.join("; ")
        );
    }
    if !g.quiet {
        if !reference.compares_throughput(&figures) {
            eprintln!(
                "throughput not compared: the reference was measured in a {} build, this is \
                 a {} build",
                reference.figures.build, figures.build
            );
        }
        eprintln!("no regression against {}", a.reference.display());
    }
    Ok(())
}

fn sim(a: BenchSimArgs, g: &Global) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => SimConfig::load(p).with_context(|| format!("loading {}", p.display()))?,
        None => SimConfig::default(),
    };
    let threads = super::rollout::threads(a.threads)?;
    let robot = Robot::builtin(Side::Left);
    let one = bench::run(&robot, &cfg, 1, 1, a.seconds)?;
    let many = bench::run(&robot, &cfg, a.envs, threads, a.seconds)?;
    if g.json {
        let out = serde_json::json!({
            "dt": cfg.dt,
            "substeps": cfg.substeps,
            "control_period": cfg.control_period,
            "single": one,
            "parallel": many,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "simulator: dt {:.5} s, {} substeps, control period {} s; scripted close-and-lift episodes",
        cfg.dt, cfg.substeps, cfg.control_period
    );
    let row = |f: &BenchFigures| {
        println!(
            "{:>3} envs on {:>2} threads: {:>9.0} physics steps/s  {:>7.1} simulated s/s  {:>8.1} control steps/s  ({} episodes in {:.1} s)",
            f.envs,
            f.threads,
            f.physics_steps_per_s,
            f.sim_seconds_per_s,
            f.control_steps_per_s,
            f.episodes,
            f.wall_seconds
        )
    };
    row(&one);
    row(&many);
    println!("reference: MuJoCo steps the Shadow hand with a block at 55-78 simulated s per wall s on one core");
    Ok(())
}

fn env(a: BenchEnvArgs, g: &Global) -> Result<()> {
    use grasp::env::api::{Action, Env, VecEnv};
    use grasp::env::grasp::{EnvConfig, GraspEnv};
    use rand::SeedableRng;
    use rand_distr::Distribution;
    if a.envs == 0 || !(a.seconds > 0.0 && a.seconds.is_finite()) {
        anyhow::bail!("--envs must be at least 1 and --seconds positive");
    }
    let robot = Robot::builtin(Side::Left);
    let model = super::rollout::load_synergy(None, 5)?;
    let objects = super::rollout::sim_objects(&a.objects)?;
    let threads = super::rollout::threads(a.threads)?;
    let envs = (0..a.envs)
        .map(|_| -> Result<Box<dyn Env>> {
            Ok(Box::new(GraspEnv::new(
                &robot,
                objects.clone(),
                model.clone(),
                SimConfig::default(),
                EnvConfig::default(),
            )?))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut venv = VecEnv::new(envs, threads, g.seed.unwrap_or(0))?;
    let n = venv.action_spec().continuous;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(g.seed.unwrap_or(0));
    let start = std::time::Instant::now();
    venv.reset(g.seed.unwrap_or(0))?;
    let (mut steps, mut episodes) = (0u64, 0u64);
    while start.elapsed().as_secs_f64() < a.seconds {
        let actions: Vec<Action> = (0..a.envs)
            .map(|_| Action {
                cont: (0..n)
                    .map(|_| rand_distr::StandardNormal.sample(&mut rng))
                    .collect(),
                lift: rand::Rng::random_bool(&mut rng, 0.15),
            })
            .collect();
        let s = venv.step(&actions)?;
        steps += a.envs as u64;
        episodes += s
            .terminated
            .iter()
            .zip(&s.truncated)
            .filter(|(t, u)| **t || **u)
            .count() as u64;
    }
    let wall = start.elapsed().as_secs_f64();
    let out = serde_json::json!({
        "envs": a.envs,
        "threads": threads,
        "objects": a.objects,
        "env_steps": steps,
        "episodes": episodes,
        "wall_s": wall,
        "env_steps_per_s": steps as f64 / wall,
        "episodes_per_s": episodes as f64 / wall,
    });
    if g.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!(
            "grasp env, random agent, {} envs on {threads} threads, objects {}: {:.1} env steps/s, {:.2} episodes/s ({steps} steps, {episodes} episodes in {wall:.1} s; reset and stage 1 included)",
            a.envs,
            a.objects,
            steps as f64 / wall,
            episodes as f64 / wall
        );
    }
    Ok(())
}
