//! Subcommands, one module each. Each module has an `Args` struct (clap derive) and a
//! `run` function; this file only wires them together.

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};

mod bench;
mod calibrate;
mod eval;
mod experiment;
mod objects;
mod pca;
mod robot;
mod rollout;
mod run;
mod sim;
mod train;

/// Flags shared by every subcommand.
#[derive(Debug, Clone, Args)]
pub struct Global {
    /// Random seed (overrides the config's seed where a command uses one).
    #[arg(long, global = true)]
    pub seed: Option<u64>,
    /// Print only errors.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// More log output (-v info, -vv debug).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,
    /// Print results as JSON on stdout.
    #[arg(long, global = true)]
    pub json: bool,
}

/// `--record DIR` and `--record-every N`, shared by `eval` and `rollout`.
#[derive(Debug, Clone, Args)]
pub struct RecordArgs {
    /// Record every episode into this folder: a JSON file and a 3D replay page (HTML,
    /// opens offline) per episode, and index.html.
    #[arg(long)]
    pub record: Option<std::path::PathBuf>,
    /// Physics steps between two recorded frames.
    #[arg(long, default_value_t = 4)]
    pub record_every: u64,
    /// With --record, keep only the episodes that ended in a physics failure (each
    /// replay then shows the failure's kind, body pair, depth and step).
    #[arg(long, requires = "record")]
    pub record_failures: bool,
}

impl RecordArgs {
    /// Rejects `--record-every 0`, a `--record` folder that cannot be written (a file, a
    /// folder without write permission) and one that already holds recordings (its
    /// index.html), before the first episode.
    pub fn check(&self) -> anyhow::Result<()> {
        if self.record_every == 0 {
            anyhow::bail!("--record-every must be at least 1");
        }
        if let Some(dir) = &self.record {
            grasp::util::fsx::check_writable_dir(dir)
                .map_err(|e| anyhow::anyhow!("--record {}: {}", dir.display(), e.source))?;
            let index = dir.join(grasp::eval::record::INDEX_FILE);
            if index.exists() {
                anyhow::bail!(
                    "--record {}: the folder already holds recordings ({}); their files of \
                     the same names and the index would be overwritten: record into a new \
                     folder, or remove them first",
                    dir.display(),
                    index.display()
                );
            }
        }
        Ok(())
    }
}

/// Teach a Shadow hand on a UR10e arm to grasp unseen objects: hand synergies, a Rapier
/// simulation with tactile and torque sensing, PPO with a GRU policy, evaluation, and
/// execution on a real robot.
#[derive(Debug, Parser)]
#[command(name = "grasp", version, about, long_about = None)]
pub struct Cli {
    #[command(flatten)]
    pub global: Global,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Inspect the hand and arm model: joint table, coupling, fingertips, URDF, IK.
    Robot(robot::RobotArgs),
    /// Hand synergies: fit a PCA model to a pose dataset, draw the synergies.
    Pca(pca::PcaArgs),
    /// Run one scripted close-and-lift in the simulator and print the sensors per step.
    Sim(sim::SimArgs),
    /// Measure throughput (`grasp bench sim`).
    Bench(bench::BenchArgs),
    /// List, inspect and export the objects to grasp.
    Objects(objects::ObjectsArgs),
    /// Run baselines or a random agent on the grasping MDP, episode by episode.
    Rollout(rollout::RolloutArgs),
    /// Per-object success rates of policies and baselines (the paper's Table I).
    Eval(eval::EvalArgs),
    /// Train a policy with PPO from a config file into a run folder.
    Train(train::TrainArgs),
    /// Run a grasp attempt of a policy on the simulated or the real robot (Sec. V-B); with
    /// --attempts, more after a failed lift (sim backend).
    Run(run::RunArgs),
    /// Calibrate the fingertip tactile sensors (Sec. V-C) and save the calibration.
    Calibrate(calibrate::CalibrateArgs),
    /// Run the paper's ablations: a grid of (config, seed) training runs, summary, plots.
    Experiment(experiment::ExperimentArgs),
}

/// Sets up `tracing` output on stderr according to `-q`/`-v`.
pub fn init_logging(g: &Global) {
    let level = if g.quiet {
        "error"
    } else {
        match g.verbose {
            0 => "warn",
            1 => "info",
            _ => "debug",
        }
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("GRASP_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// Sets candle's thread counts once, before any other thread exists.
///
/// Element-wise ops stay on the calling thread unless the user chose otherwise
/// (`CANDLE_NUM_THREADS`). candle 0.11 splits element-wise ops of 64 k elements or more
/// (PPO's minibatches) over a pool of workers that spin up to 25,000 times waiting for
/// the next op: on 2 cores the spinning worker took 7 % of a training run's samples and
/// the main thread 4 % more waiting for it (perf), and under load an update's
/// optimisation took twice as long. Element-wise ops split into independent chunks, so
/// the results are the same to the bit (a base.toml run's metrics.csv identical but for
/// its timing columns).
///
/// Matrix products keep candle's own thread count, but computed once: without
/// `RAYON_NUM_THREADS` candle 0.11 counts the physical cores by reading and parsing
/// `/proc/cpuinfo` on every matrix product (13,255 times in one update of base.toml,
/// about 35 µs each: `strace`). `RAYON_NUM_THREADS` is set to that same count, so the
/// products split as before (the same metrics.csv, timing aside), and rayon's global
/// pool is built with its own default size (one thread per logical core), which the
/// variable would otherwise change on machines with two threads per core.
pub fn configure_candle_threads() {
    const ELEMENTWISE: &str = "CANDLE_NUM_THREADS";
    const PRODUCTS: &str = "RAYON_NUM_THREADS";
    // Called first thing in `main`, before any other thread exists.
    if std::env::var_os(ELEMENTWISE).is_none() {
        std::env::set_var(ELEMENTWISE, "1");
    }
    if std::env::var_os(PRODUCTS).is_none() {
        let products = candle_core::utils::get_num_threads();
        std::env::set_var(PRODUCTS, products.to_string());
        // Only fails when a global pool exists already, which then keeps its size.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(grasp::util::threads::available())
            .build_global();
    }
}

/// Makes a closed stdout (`grasp objects list | head -1`) end the process quietly with
/// status 0, as `rg ... | head` does, instead of the panic of `println!` ("failed printing
/// to stdout: Broken pipe"). Rust ignores SIGPIPE, so the write fails with `EPIPE` and
/// `print!` panics with that message; the hook recognises it and exits. Every other panic
/// goes to the default hook.
pub fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or_default();
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info)
    }));
}

/// Whether `err` is (caused by) a write into a closed pipe.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|e| {
        e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes joined by ": ", each said once: a cause whose text the
/// message before it already contains (library errors often print their source, e.g.
/// "cannot read x: No such file or directory (os error 2)") is left out.
pub fn error_text(err: &anyhow::Error) -> String {
    let mut out = String::new();
    let mut prev = String::new();
    for cause in err.chain() {
        let msg = cause.to_string();
        if !prev.is_empty() && prev.contains(&msg) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&msg);
        prev = msg;
    }
    out
}

/// Runs the chosen subcommand.
pub fn dispatch(cli: Cli) -> anyhow::Result<()> {
    let global = cli.global;
    match cli.command {
        Command::Robot(a) => robot::run(a, &global),
        Command::Pca(a) => pca::run(a, &global),
        Command::Sim(a) => sim::run(a, &global),
        Command::Bench(a) => bench::run(a, &global),
        Command::Rollout(a) => rollout::run(a, &global),
        Command::Eval(a) => eval::run(a, &global),
        Command::Objects(a) => objects::run(a, &global),
        Command::Train(a) => train::run(a, &global),
        Command::Run(a) => run::run(a, &global),
        Command::Calibrate(a) => calibrate::run(a, &global),
        Command::Experiment(a) => experiment::run(a, &global),
    }
}

/// Checks a `--difficulty` flag (the curriculum success rate r_s that sets the start-pose
/// range): a rate in [0, 1].
pub fn check_difficulty(d: f64) -> anyhow::Result<()> {
    if !(0.0..=1.0).contains(&d) {
        anyhow::bail!(
            "--difficulty must be in [0, 1], got {}",
            grasp::util::num::short(d)
        );
    }
    Ok(())
}

/// Ends a command that a SIGINT or SIGTERM stopped
/// ([`grasp::util::signal::stop_on_signal`]): stdout is flushed, `"interrupted (SIGINT or
/// SIGTERM): {what}"` is said on stderr unless `quiet`, and the exit status is 130 (128 +
/// SIGINT, as a shell reports a process ended by Ctrl-C).
pub fn exit_interrupted(what: &str, quiet: bool) -> ! {
    use std::io::Write;
    let _ = std::io::stdout().flush();
    if !quiet {
        eprintln!("interrupted (SIGINT or SIGTERM){what}");
    }
    std::process::exit(130);
}

/// Checks an `--attempts` flag ([`grasp::eval::check_attempts`]); `what` says what one
/// attempt is.
pub fn check_attempts(n: usize, what: &str) -> anyhow::Result<()> {
    grasp::eval::check_attempts(n, what).map_err(anyhow::Error::msg)
}

/// The simulator config of a `--sim-config`-style flag, by
/// [`grasp::sim::SimConfig::load_or_default`]'s one rule (the built-in defaults when
/// absent); errors name the file.
pub fn sim_config(path: Option<&std::path::PathBuf>) -> anyhow::Result<grasp::sim::SimConfig> {
    Ok(grasp::sim::SimConfig::load_flag(path.map(|p| p.as_path()))?)
}

// The helpers several commands share (the objects, synergy model, thread count and
// simulated robot of a command line), here rather than in one command's file.

/// Writes the index of a `--record` folder and says so on stderr (unless `quiet`); the
/// episodes that could not be written (`errors`) end the command with an error after the
/// results were printed. Shared by `grasp eval` and `grasp rollout`.
pub fn finish_recordings(
    dir: &std::path::Path,
    entries: &[grasp::eval::record::RecordingEntry],
    errors: &[String],
    quiet: bool,
) -> anyhow::Result<()> {
    let done = grasp::eval::record::finish(dir, entries, errors)
        .with_context(|| format!("writing the index of {}", dir.display()))?;
    if !quiet {
        eprintln!(
            "recorded {} episodes: open {}",
            done.episodes,
            done.index.display()
        );
    }
    match done.lost {
        Some(lost) => Err(anyhow::anyhow!(lost)),
        None => Ok(()),
    }
}

/// Resolves an `--objects` argument and builds its objects (hulls from the cache). Shared
/// by every command that takes `--objects`.
pub fn load_objects(arg: &str) -> anyhow::Result<Vec<grasp::objects::Object>> {
    let ctx = grasp::objects::BuildContext::from_env();
    grasp::objects::sets::load_objects(arg, &ctx)
        .with_context(|| format!("cannot load objects `{arg}`"))
}

/// Loads the synergy model (shipped one by default) with `n` components
/// ([`grasp::synergy::model_or_shipped`]).
pub fn load_synergy(
    path: Option<&std::path::PathBuf>,
    n: usize,
) -> anyhow::Result<grasp::synergy::SynergyModel> {
    Ok(grasp::synergy::model_or_shipped(
        path.map(|p| p.as_path()),
        n,
    )?)
}

/// Resolves `--objects` into the simulator's object descriptions
/// ([`grasp::sim::ObjectSpec::simulable_set`]).
pub fn sim_objects(arg: &str) -> anyhow::Result<Vec<(String, grasp::sim::ObjectSpec)>> {
    Ok(grasp::sim::ObjectSpec::simulable_set(arg)?)
}

/// Number of worker threads: the `--threads` flag (checked by the one rule of
/// [`grasp::util::threads`]) or the available cores.
pub fn threads(flag: Option<usize>) -> anyhow::Result<usize> {
    grasp::util::threads::from_flag(flag).map_err(anyhow::Error::msg)
}

/// Which hand-arm system to drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The simulator with a raw-sensor model.
    Sim,
    /// The Shadow hand's ROS 1 driver and the UR10e through rosbridge (feature `ros`).
    Ros,
    /// MuJoCo at simulated time behind the same interface (feature `mujoco`).
    Mujoco,
}

impl Backend {
    /// The name as `--backend` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Sim => "sim",
            Backend::Ros => "ros",
            Backend::Mujoco => "mujoco",
        }
    }
}

impl From<Backend> for grasp::run::request::RobotBackend {
    fn from(b: Backend) -> Self {
        use grasp::run::request::RobotBackend as R;
        match b {
            Backend::Sim => R::Sim,
            Backend::Ros => R::Ros,
            Backend::Mujoco => R::Mujoco,
        }
    }
}

/// The object for the sim backend: `box`, `cylinder` or one library object
/// ([`grasp::sim::ObjectSpec::simulable_one`]).
pub fn sim_object(name: &str) -> anyhow::Result<grasp::sim::ObjectSpec> {
    Ok(grasp::sim::ObjectSpec::simulable_one(name)?)
}

/// The simulated hand-arm `A` with the raw-sensor model seeded by `seed`.
pub fn sim_backend<A: grasp::run::simulated::SimulatedArm>(
    object: grasp::sim::ObjectSpec,
    sim_cfg: grasp::sim::SimConfig,
    seed: u64,
) -> anyhow::Result<A> {
    let mut cfg = grasp::run::sim_backend::SimBackendConfig::default();
    cfg.raw.seed = seed;
    let robot = grasp::robot::Robot::builtin(grasp::robot::Side::Left);
    A::build(&robot, object, sim_cfg, cfg).context("building the simulated robot")
}

/// Calibrates the simulated fingertips ([`grasp::run::calibrate::calibrate_simulated`]):
/// `still` readings 20 ms apart, then each fingertip pressed with a known force
/// (`press_n` newtons, `presses` readings each).
pub fn calibrate_sim<A: grasp::run::simulated::SimulatedArm>(
    arm: &mut A,
    still: usize,
    fraction: f64,
    press_n: f64,
    presses: usize,
) -> anyhow::Result<grasp::run::calibrate::CalibrationReport> {
    grasp::run::calibrate::calibrate_simulated(arm, still, fraction, press_n, presses)
        .context("calibrating the simulated fingertips")
}

/// Connects to the robot's rosbridge ([`grasp::run::request::connect_ros`]).
#[cfg(feature = "ros")]
pub fn connect_ros(url: &str) -> anyhow::Result<grasp::hardware::ros::RosHandArm> {
    Ok(grasp::run::request::connect_ros(url)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_text_says_each_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        let lib = grasp::util::fsx::WriteError {
            path: "x.json".into(),
            source: io,
        };
        let err = anyhow::Error::new(lib).context("writing the table");
        assert_eq!(
            error_text(&err),
            "writing the table: cannot write x.json: No such file"
        );
        let plain = anyhow::anyhow!("inner").context("outer");
        assert_eq!(error_text(&plain), "outer: inner");
        assert!(!is_broken_pipe(&plain));
        let pipe = anyhow::Error::new(std::io::Error::from(std::io::ErrorKind::BrokenPipe));
        assert!(is_broken_pipe(&pipe.context("printing")));
    }

    #[test]
    fn candle_thread_counts_are_set_once_and_a_users_choice_stays() {
        let users = std::env::var("RAYON_NUM_THREADS").ok();
        configure_candle_threads();
        let set = std::env::var("RAYON_NUM_THREADS").expect("RAYON_NUM_THREADS is set");
        if let Some(users) = users {
            assert_eq!(set, users);
        }
        // candle's matrix products now read the count from the variable.
        assert_eq!(candle_core::utils::get_num_threads().to_string(), set);
        assert!(std::env::var("CANDLE_NUM_THREADS").is_ok());
    }
}
