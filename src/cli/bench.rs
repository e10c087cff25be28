//! `grasp bench`: throughput measurements.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::{Robot, Side};
use grasp::sim::bench::{self, BenchFigures};
use grasp::sim::SimConfig;
use grasp::util::assets;
use std::path::PathBuf;

use super::Global;

/// `bench regression`'s default reference, a shipped file found from any working
/// directory ([`grasp::util::assets`]).
const REFERENCE: &str = "ci/reference.json";
/// `bench regression`'s default policy (the one ci/reference.json was measured with).
const REGRESSION_POLICY: &str = "assets/policies/quick_gru_m3_pca5";

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
        after_help = "Examples:\n  grasp bench sim\n  grasp bench sim --envs 20 --seconds 10 --json\n  grasp bench sim --compare configs/levers/sim_rapier_rows.toml --rounds 3   # A/B in one run"
    )]
    Sim(BenchSimArgs),
    /// Grasping-environment throughput: --envs environments with a random agent stepped
    /// in one VecEnv (the learner's harness), environment steps per second.
    #[command(
        after_help = "Examples:\n  grasp bench env --envs 20 --seconds 20 --json\n  grasp bench env --envs 20 --compare configs/levers/sim_rapier_rows.toml --rounds 3"
    )]
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
    /// Cost of one `grasp run` attempt on a simulated robot (build, calibration, cameras,
    /// plan, attempt, lift) on one thread: the median wall seconds over --rounds trials,
    /// the backends of --backend alternating round by round (an A/B in one run).
    #[command(
        after_help = "Examples:\n  grasp bench run --backend sim --rounds 10 --json\n  grasp bench run --backend sim,mujoco --rounds 10   # needs the mujoco feature"
    )]
    Run(BenchRunArgs),
}

#[derive(Debug, Args)]
pub struct BenchRunArgs {
    /// Simulated robots, comma-separated: sim, mujoco.
    #[arg(long, value_delimiter = ',', default_value = "sim")]
    pub backend: Vec<super::Backend>,
    /// The object.
    #[arg(long, default_value = "box_gelatin")]
    pub object: String,
    /// The agent: a checkpoint folder, baseline1 or baseline2 (default: `grasp run`'s).
    #[arg(long, default_value = grasp::run::DEFAULT_POLICY)]
    pub policy: String,
    /// Trials per backend (trial k is the same scene on every backend).
    #[arg(long, default_value_t = 10)]
    pub rounds: usize,
}

#[derive(Debug, Args)]
pub struct BenchRegressionArgs {
    /// The reference figures (JSON).
    #[arg(long, default_value = REFERENCE)]
    pub reference: PathBuf,
    /// Write the measured figures as the new reference (atomically) instead of comparing.
    #[arg(long)]
    pub update: bool,
    /// The policy checkpoint folder.
    #[arg(long, default_value = REGRESSION_POLICY)]
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
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// A second simulator config measured in the same run, alternating with the first
    /// (A/B): prints both and their ratio.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// Measurements per config (medians are reported).
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
    /// Objects the environments draw from (`procedural`: the training stream, object builds
    /// included).
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
    /// A second simulator config measured in the same run, alternating with the first
    /// (A/B): prints both and their ratio.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// Measurements per config (medians are reported).
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
}

pub fn run(a: BenchArgs, g: &Global) -> Result<()> {
    match a.command {
        BenchCommand::Sim(a) => sim(a, g),
        BenchCommand::Env(a) => env(a, g),
        BenchCommand::Regression(a) => regression(a, g),
        BenchCommand::Run(a) => run_attempts(a, g),
    }
}

/// `grasp bench run`.
fn run_attempts(a: BenchRunArgs, g: &Global) -> Result<()> {
    use grasp::run::table::{time_trials, TableAgent, TableConfig, TimedTrial};
    if !(1..=1000).contains(&a.rounds) {
        anyhow::bail!("--rounds {} must be in 1..=1000", a.rounds);
    }
    let agent = match a.policy.as_str() {
        "baseline1" => TableAgent::Baseline1,
        "baseline2" => TableAgent::Baseline2,
        p => TableAgent::Policy {
            dir: assets::default_or_given(
                std::path::Path::new(p),
                grasp::run::DEFAULT_POLICY,
                "--policy",
            )?,
            label: p.to_string(),
        },
    };
    let robot = Robot::builtin(Side::Left);
    let object = (a.object.clone(), super::sim_object(&a.object)?);
    let sim = SimConfig::default();
    let mut pipeline = grasp::run::pipeline::PipelineConfig::default();
    grasp::run::session::fit_to_simulator(&mut pipeline, &sim);
    let cfg = TableConfig {
        trials: a.rounds,
        seed: g.seed.unwrap_or(0),
        threads: 1,
        sim,
        pipeline,
        backend: grasp::run::sim_backend::SimBackendConfig::default(),
        cameras: grasp::run::sim_backend::CameraConfig::default(),
        calibration: None,
    };
    let mut times: Vec<Vec<TimedTrial>> = vec![Vec::new(); a.backend.len()];
    for t in 0..a.rounds {
        for (b, backend) in a.backend.iter().enumerate() {
            let r = t..t + 1;
            let one = match backend {
                super::Backend::Sim => time_trials::<grasp::run::sim_backend::SimHandArm>(
                    &robot, &object, &agent, &cfg, r,
                )?,
                #[cfg(feature = "mujoco")]
                super::Backend::Mujoco => time_trials::<grasp::run::mujoco_backend::MujocoHandArm>(
                    &robot, &object, &agent, &cfg, r,
                )?,
                #[cfg(not(feature = "mujoco"))]
                super::Backend::Mujoco => anyhow::bail!(grasp::run::request::NO_MUJOCO),
                super::Backend::Ros => {
                    anyhow::bail!("--backend ros: the bench runs simulated robots (sim, mujoco)")
                }
            };
            times[b].extend(one);
        }
    }
    let rows: Vec<serde_json::Value> = a
        .backend
        .iter()
        .zip(&times)
        .map(|(b, t)| {
            let s: Vec<f64> = t.iter().map(|x| x.seconds).collect();
            serde_json::json!({
                "backend": b.name(),
                "seconds": s,
                "median_s": med(&s, |x| *x),
                "successes": t.iter().filter(|x| x.success).count(),
            })
        })
        .collect();
    if g.json {
        let out = serde_json::json!({
            "object": a.object,
            "agent": agent.label(),
            "rounds": a.rounds,
            "threads": 1,
            "backends": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        for r in &rows {
            println!(
                "{}: median {:.3} s per attempt on one thread ({} rounds on {}, {} held)",
                r["backend"].as_str().unwrap_or_default(),
                r["median_s"].as_f64().unwrap_or(f64::NAN),
                a.rounds,
                a.object,
                r["successes"]
            );
        }
    }
    Ok(())
}

fn regression(a: BenchRegressionArgs, g: &Global) -> Result<()> {
    use grasp::eval::regression::{compare, measure, Reference, RegressionSetup};
    if a.trials == 0 || a.envs == 0 || a.steps == 0 {
        anyhow::bail!("--trials, --envs and --steps must be at least 1");
    }
    // Read the reference first: a broken file is reported before minutes of measuring.
    // --update writes where it is told (created if need be); a read finds the default.
    let reference = if a.update {
        None
    } else {
        let path = assets::default_or_given(&a.reference, REFERENCE, "--reference")
            .unwrap_or_else(|_| a.reference.clone());
        let text = grasp::util::fsx::read_to_string_bounded(&path, grasp::util::fsx::limits::DATA)
            .with_context(|| {
                format!(
                    "reading the reference {} (create it with --update)",
                    path.display()
                )
            })?;
        let r: Reference = serde_json::from_str(&text)
            .with_context(|| format!("parsing the reference {}", path.display()))?;
        Some(r)
    };
    let policy = assets::default_or_given(&a.policy, REGRESSION_POLICY, "--policy")?;
    let setup = RegressionSetup {
        objects: super::sim_objects(&a.objects)?,
        trials: a.trials,
        seed: g.seed.unwrap_or(0),
        policy: policy.clone(),
        threads: super::threads(a.threads)?,
        throughput_envs: a.envs,
        throughput_steps: a.steps,
    };
    let figures =
        measure(&setup).with_context(|| format!("measuring with {}", policy.display()))?;
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

use super::sim_config;

/// The configs of a run: A (`--config`) and, with `--compare`, B.
fn ab_configs(
    config: Option<&PathBuf>,
    compare: Option<&PathBuf>,
    rounds: usize,
) -> Result<Vec<(String, SimConfig)>> {
    if rounds == 0 || rounds > 100 {
        anyhow::bail!("--rounds = {rounds}: must be in 1..=100");
    }
    let name = |p: Option<&PathBuf>| p.map_or("built-in".to_string(), |p| p.display().to_string());
    let mut out = vec![(name(config), sim_config(config)?)];
    if let Some(b) = compare {
        out.push((name(Some(b)), sim_config(Some(b))?));
    }
    Ok(out)
}

/// Runs `measure` for each config in turn, `rounds` times (A, B, A, B, ...), and returns
/// each config's measurements; an error names the config.
fn alternate<T>(
    configs: &[(String, SimConfig)],
    rounds: usize,
    mut measure: impl FnMut(&SimConfig) -> Result<T>,
) -> Result<Vec<Vec<T>>> {
    let mut out: Vec<Vec<T>> = configs.iter().map(|_| Vec::new()).collect();
    for _ in 0..rounds {
        for (k, (name, cfg)) in configs.iter().enumerate() {
            out[k].push(measure(cfg).with_context(|| format!("measuring with {name}"))?);
        }
    }
    Ok(out)
}

/// Refuses figures that measure nothing: no finished episode (or step) in the time
/// given, or only episodes that ended in a physics failure. `(what, count, failures)`.
fn check_measured(name: &str, seconds: f64, what: &str, count: u64, failures: u64) -> Result<()> {
    if count == 0 {
        anyhow::bail!(
            "{name}: no {what} finished in --seconds {}: there is no throughput to report \
             (raise --seconds)",
            grasp::util::num::short(seconds)
        );
    }
    if failures >= count {
        anyhow::bail!(
            "{name}: every one of the {count} episodes ended in a physics failure: the \
             figures would time broken physics (check the simulator config)"
        );
    }
    Ok(())
}

/// Checks `--seconds`, `--envs` shared by `bench sim` and `bench env`.
fn check_sizes(envs: usize, seconds: f64) -> Result<()> {
    let max = bench::MAX_ENVS;
    if envs == 0 || envs > max {
        anyhow::bail!("--envs {envs} must be in 1..={max}");
    }
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 3600.0) {
        anyhow::bail!(
            "--seconds {} must be in (0, 3600]",
            grasp::util::num::short(seconds)
        );
    }
    Ok(())
}

/// The median of one figure over a config's measurements.
fn med<T>(runs: &[T], f: impl Fn(&T) -> f64) -> f64 {
    grasp::util::stats::median(&runs.iter().map(f).collect::<Vec<_>>())
}

fn sim(a: BenchSimArgs, g: &Global) -> Result<()> {
    check_sizes(a.envs, a.seconds)?;
    let configs = ab_configs(a.config.as_ref(), a.compare.as_ref(), a.rounds)?;
    let threads = super::threads(a.threads)?;
    let robot = Robot::builtin(Side::Left);
    let runs = alternate(&configs, a.rounds, |cfg| {
        let one = bench::run(&robot, cfg, 1, 1, a.seconds)?;
        let many = bench::run(&robot, cfg, a.envs, threads, a.seconds)?;
        Ok((one, many))
    })?;
    for ((name, _), r) in configs.iter().zip(&runs) {
        for f in r.iter().flat_map(|(one, many)| [one, many]) {
            let envs = format!("{name} ({} envs)", f.envs);
            check_measured(&envs, a.seconds, "episode", f.episodes, f.physics_failures)?;
        }
    }
    let summary = |r: &[(BenchFigures, BenchFigures)], many: bool| {
        let pick = |x: &(BenchFigures, BenchFigures)| if many { x.1.clone() } else { x.0.clone() };
        let figs: Vec<BenchFigures> = r.iter().map(pick).collect();
        serde_json::json!({
            "envs": figs[0].envs,
            "threads": figs[0].threads,
            "physics_steps": figs.iter().map(|f| f.physics_steps).sum::<u64>(),
            "episodes": figs.iter().map(|f| f.episodes).sum::<u64>(),
            "physics_failures": figs.iter().map(|f| f.physics_failures).sum::<u64>(),
            "physics_steps_per_s": med(&figs, |f| f.physics_steps_per_s),
            "sim_seconds_per_s": med(&figs, |f| f.sim_seconds_per_s),
            "control_steps_per_s": med(&figs, |f| f.control_steps_per_s),
            "episodes_per_s": med(&figs, |f| f.episodes as f64 / f.wall_seconds),
            "runs": figs,
        })
    };
    let per_config: Vec<serde_json::Value> = configs
        .iter()
        .zip(&runs)
        .map(|((name, cfg), r)| {
            serde_json::json!({
                "config": name,
                "dt": cfg.dt,
                "substeps": cfg.substeps,
                "drive": cfg.drive,
                "limit_rows": cfg.limit_rows,
                "control_period": cfg.control_period,
                "single": summary(r, false),
                "parallel": summary(r, true),
            })
        })
        .collect();
    let ratio = |key: &str, what: &str| {
        per_config[0][key][what].as_f64().unwrap_or(f64::NAN)
            / per_config[1][key][what].as_f64().unwrap_or(f64::NAN)
    };
    let ratios = (per_config.len() == 2).then(|| {
        serde_json::json!({
            "single_sim_seconds_per_s": ratio("single", "sim_seconds_per_s"),
            "single_episodes_per_s": ratio("single", "episodes_per_s"),
            "parallel_sim_seconds_per_s": ratio("parallel", "sim_seconds_per_s"),
            "parallel_episodes_per_s": ratio("parallel", "episodes_per_s"),
        })
    });
    if g.json {
        let mut out = per_config[0].clone();
        out["rounds"] = a.rounds.into();
        out["mujoco_reference_sim_seconds_per_s"] = serde_json::json!([55.0, 78.0]);
        if let Some(r) = &ratios {
            out["compare"] = per_config[1].clone();
            out["ratio"] = r.clone();
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    for c in &per_config {
        println!(
            "{}: dt {:.5} s, {} substeps, drive {:?}, limit rows {:?}, control period {} s; \
             scripted close-and-lift episodes (median of {} rounds)",
            c["config"].as_str().unwrap_or("?"),
            c["dt"].as_f64().unwrap_or(f64::NAN),
            c["substeps"],
            c["drive"].as_str().unwrap_or("?"),
            c["limit_rows"].as_str().unwrap_or("?"),
            c["control_period"],
            a.rounds
        );
        for key in ["single", "parallel"] {
            let f = &c[key];
            let num = |k: &str| f[k].as_f64().unwrap_or(f64::NAN);
            println!(
                "  {:>3} envs on {:>2} threads: {:>9.0} physics steps/s  {:>7.1} simulated s/s  {:>8.1} control steps/s  {:>6.2} episodes/s  ({} of {} episodes ended in a physics failure)",
                f["envs"],
                f["threads"],
                num("physics_steps_per_s"),
                num("sim_seconds_per_s"),
                num("control_steps_per_s"),
                num("episodes_per_s"),
                f["physics_failures"],
                f["episodes"],
            );
        }
    }
    if let Some(r) = ratios {
        println!(
            "ratio first/second: single {:.2}x simulated s/s ({:.2}x episodes/s), parallel {:.2}x ({:.2}x episodes/s)",
            r["single_sim_seconds_per_s"].as_f64().unwrap_or(f64::NAN),
            r["single_episodes_per_s"].as_f64().unwrap_or(f64::NAN),
            r["parallel_sim_seconds_per_s"].as_f64().unwrap_or(f64::NAN),
            r["parallel_episodes_per_s"].as_f64().unwrap_or(f64::NAN),
        );
    }
    println!("reference: MuJoCo steps the Shadow hand with a block at 55-78 simulated s per wall s on one core");
    Ok(())
}

fn env(a: BenchEnvArgs, g: &Global) -> Result<()> {
    use grasp::env::api::{Env, VecEnv};
    use grasp::env::bench::{random_agent, EnvFigures, Until};
    use grasp::env::grasp::{EnvConfig, GraspEnv};
    check_sizes(a.envs, a.seconds)?;
    let configs = ab_configs(a.config.as_ref(), a.compare.as_ref(), a.rounds)?;
    let robot = Robot::builtin(Side::Left);
    let model = super::load_synergy(None, 5)?;
    // `procedural`: each env builds a fresh stream object every few episodes, as training
    // on the stream does, so the figure includes the objects' build cost.
    let on_stream = a.objects == grasp::objects::stream::STREAM_SET;
    let objects = if on_stream {
        use grasp::env::stream::{ObjectStream, StreamConfig};
        let first = ObjectStream::new(StreamConfig::default()).first_object();
        vec![first.map_err(|m| anyhow::anyhow!("procedural stream: {m}"))?]
    } else {
        super::sim_objects(&a.objects)?
    };
    let threads = super::threads(a.threads)?;
    let seed = g.seed.unwrap_or(0);
    let runs = alternate(&configs, a.rounds, |cfg| -> Result<EnvFigures> {
        let envs = (0..a.envs)
            .map(|_| -> Result<Box<dyn Env>> {
                let env = GraspEnv::new(
                    &robot,
                    objects.clone(),
                    model.clone(),
                    cfg.clone(),
                    EnvConfig::default(),
                )?;
                Ok(Box::new(if on_stream { env.with_stream() } else { env }))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut venv = VecEnv::new(envs, threads, seed)?;
        Ok(random_agent(&mut venv, seed, Until::Seconds(a.seconds))?)
    })?;
    for ((name, _), r) in configs.iter().zip(&runs) {
        for f in r {
            check_measured(name, a.seconds, "environment step", f.env_steps, 0)?;
            if f.episodes > 0 {
                check_measured(name, a.seconds, "episode", f.episodes, f.physics_failures)?;
            }
        }
    }
    let per_config: Vec<serde_json::Value> = configs
        .iter()
        .zip(&runs)
        .map(|((name, _), r)| {
            serde_json::json!({
                "config": name,
                "envs": a.envs,
                "threads": threads,
                "objects": a.objects,
                "env_steps_per_s": med(r, |f| f.env_steps_per_s),
                "episodes_per_s": med(r, |f| f.episodes_per_s),
                "env_steps": r.iter().map(|f| f.env_steps).sum::<u64>(),
                "episodes": r.iter().map(|f| f.episodes).sum::<u64>(),
                "physics_failures": r.iter().map(|f| f.physics_failures).sum::<u64>(),
                "wall_s": r.iter().map(|f| f.wall_s).sum::<f64>(),
                "phases": summed_phases(r),
                "runs": r,
            })
        })
        .collect();
    let ratio = (per_config.len() == 2).then(|| {
        let v = |k: usize| {
            per_config[k]["env_steps_per_s"]
                .as_f64()
                .unwrap_or(f64::NAN)
        };
        v(0) / v(1)
    });
    if g.json {
        let mut out = per_config[0].clone();
        out["rounds"] = a.rounds.into();
        if let Some(r) = ratio {
            out["compare"] = per_config[1].clone();
            out["ratio_env_steps_per_s"] = r.into();
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    for (c, r) in per_config.iter().zip(&runs) {
        let num = |k: &str| c[k].as_f64().unwrap_or(f64::NAN);
        println!(
            "{}: grasp env, random agent, {} envs on {threads} threads, objects {}: {:.1} env steps/s, {:.2} episodes/s (median of {} rounds; {} steps, {} episodes ({} ended in a physics failure) in {:.1} s; reset and stage 1 included)",
            c["config"].as_str().unwrap_or("?"),
            a.envs,
            a.objects,
            num("env_steps_per_s"),
            num("episodes_per_s"),
            a.rounds,
            c["env_steps"],
            c["episodes"],
            c["physics_failures"],
            num("wall_s"),
        );
        print_phases(r);
    }
    if let Some(r) = ratio {
        println!("ratio first/second: {r:.2}x env steps/s");
    }
    Ok(())
}

/// The phase tallies of one config's rounds, summed (`None` without grasping envs).
fn summed_phases(runs: &[grasp::env::bench::EnvFigures]) -> Option<grasp::env::phases::PhaseTally> {
    runs.iter()
        .filter_map(|f| f.phases)
        .reduce(|a, b| a.plus(&b))
}

/// The phase split of one config's rounds: per phase the physics steps per episode and
/// the share of the physics steps and of the environments' time.
fn print_phases(runs: &[grasp::env::bench::EnvFigures]) {
    let Some(t) = summed_phases(runs) else {
        return;
    };
    let episodes = runs.iter().map(|f| f.episodes).sum::<u64>().max(1) as f64;
    let total = t.total();
    let share = |x: f64, of: f64| if of > 0.0 { 100.0 * x / of } else { 0.0 };
    for (name, p) in t.phases() {
        println!(
            "  {name:8} {:6.1} physics steps per episode ({:4.1} % of the steps), {:4.1} % of the time",
            p.physics_steps as f64 / episodes,
            share(p.physics_steps as f64, total.physics_steps as f64),
            share(p.wall_s, total.wall_s),
        );
    }
}
