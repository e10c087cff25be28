//! `grasp run`: a grasp attempt of a trained policy on the simulated or the real robot
//! (Sec. V-B): plan a two-finger grasp, map it to the hand, stage 1, the policy, the lift.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::hardware::calibration::TactileCalibration;
use grasp::hardware::log::AttemptLog;
use grasp::hardware::safety::SafeHandArm;
use grasp::hardware::HandArm;
use grasp::perception::pointcloud::{write_pcd, PcdData, PointCloud};
use grasp::robot::{Robot, Side};
use grasp::run::pipeline::{
    load_grasp_file, AttemptOutcome, Controller, GraspFile, GraspPlan, GraspSource, PipelineConfig,
    PolicyRunner,
};
use grasp::run::session::{
    fit_to_simulator, object_cloud, plan_attempt, AttemptReport, Session, SessionConfig,
};
use grasp::run::sim_backend::{CameraConfig, SimBackendConfig, SimHandArm};
use grasp::run::simulated::SimulatedArm;
use grasp::run::table::{run_table, TableAgent, TableConfig};
use grasp::sim::SimConfig;
use grasp::util::{assets, signal};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::{sim_config, sim_object, sim_objects, threads, Backend, Global, NO_ROS};

/// The attempt log of a single run when `--log` is not given.
const DEFAULT_LOG: &str = "attempt.jsonl";

/// Run a grasp attempt of a trained policy on the simulated or the real robot (with
/// --attempts, more after a failed lift: sim backend).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  grasp run --backend sim --object box_gelatin
  grasp run --backend sim --object box_gelatin --cloud scan.pcd --log attempt.jsonl --json
  grasp run --backend sim --center 0,0,0.02 --closing 1,0,0 --calibration tactile.json
  grasp run --backend ros --ros-url ws://robot:9090 --grasp grasp.toml --calibration tactile.json
  grasp run --backend sim --objects unseen --trials 10 --policy assets/policies/fig5_gru_m3_pca8,baseline1,baseline2 --json

With the sim backend and no grasp or cloud, the cloud is what four simulated depth
camera views (one from each side) see of the object (noisy, partial); --save-cloud
writes it as PCD. Where the cloud holds no usable antipodal pair, the hand closes across
the cloud's narrowest horizontal extent. Without
--calibration the sim backend calibrates its fingertips first (as `grasp calibrate`).
A grasp file is TOML or JSON: center = [x, y, z], closing = [x, y, z], and optionally
approach = [x, y, z] (default [0, 0, -1]), world frame, metres. Every step is appended
to the attempt log (JSON lines). The sim backend places the hand palm down only, so its
grasps are made top-down.

With --objects (a simulated backend), the command makes Table I through the robot path:
every agent of --policy (checkpoint folders, baseline1, baseline2) on --trials scenes of
each object (scene t of object o seeded as `grasp eval` seeds it from --seed: the object's
offset and yaw, the raw sensors' noise), each trial the whole pipeline on a fresh
simulated robot (calibration, cameras, plan, attempt, lift) judged by the simulator. It
prints per-object success with Wilson intervals as `grasp eval` does; --json has the shape
of `grasp eval --json` (plus each agent's backend and the trials that ended in an error),
so `grasp eval --from-json` reads it. Attempt logs are written only with --log (all trials
into that file).")]
pub struct RunArgs {
    /// The robot: sim, ros or mujoco.
    #[arg(long, value_enum, default_value = "sim")]
    pub backend: Backend,
    /// Checkpoint folder of the policy (default: the shipped policy that lifted the most
    /// validation objects from the pre-grasp, the placement `grasp run` plans; found from
    /// any working directory, see docs/robot-hardware.md). With --objects, a comma list
    /// of agents: checkpoint folders, baseline1 and baseline2.
    #[arg(long, default_value = grasp::run::DEFAULT_POLICY)]
    pub policy: String,
    /// Two-finger grasp file (TOML or JSON).
    #[arg(long, conflicts_with_all = ["cloud", "center"])]
    pub grasp: Option<PathBuf>,
    /// Point cloud of the object (PCD or PLY, world frame) to plan the grasp on.
    #[arg(long, conflicts_with = "center")]
    pub cloud: Option<PathBuf>,
    /// Grasp centre x,y,z (m): a grasp given on the command line (with --closing).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "closing"
    )]
    pub center: Option<Vec<f64>>,
    /// Closing direction x,y,z of a command-line grasp.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "center"
    )]
    pub closing: Option<Vec<f64>>,
    /// Approach direction x,y,z of a command-line grasp (default straight down).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "center"
    )]
    pub approach: Option<Vec<f64>>,
    /// Tactile calibration file (from `grasp calibrate`).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Object in the simulator: box, cylinder or a library object name.
    #[arg(long, default_value = "box_gelatin")]
    pub object: String,
    /// Table I through the robot path on this object set (a set name, a manifest or a
    /// comma list of objects, as `grasp eval --objects`): every --policy agent on --trials
    /// scenes of each object (simulated backends).
    #[arg(long, conflicts_with_all = ["object", "grasp", "cloud", "center", "save_cloud"])]
    pub objects: Option<String>,
    /// With --objects: trials per object.
    #[arg(long, default_value_t = 10, requires = "objects")]
    pub trials: usize,
    /// With --objects: worker threads (default: available cores).
    #[arg(long, requires = "objects")]
    pub threads: Option<usize>,
    /// Attempt log (JSON lines, appended; default attempt.jsonl). With --objects, every
    /// trial's attempt is appended to it, and none is written without it.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Pipeline config (TOML, see `PipelineConfig`); defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// MuJoCo engine settings (TOML, mujoco backend); configs/mujoco.toml's when absent.
    #[arg(long)]
    pub mujoco_settings: Option<PathBuf>,
    /// Write the point cloud the grasp was planned on (sim cameras or --cloud) as PCD.
    #[arg(long)]
    pub save_cloud: Option<PathBuf>,
    /// rosbridge websocket of the robot (ros backend).
    #[arg(long, default_value = "ws://localhost:9090")]
    pub ros_url: String,
    /// Attempts (sim backend, planned on the cameras' cloud): after a failed lift the hand
    /// opens, the object settles where the attempt left it, the cameras look again and
    /// the next best grasp that was not tried yet is planned, as `grasp eval --attempts`.
    #[arg(long, default_value_t = 1)]
    pub attempts: usize,
}

fn pipeline_config(a: &RunArgs, sim: Option<&SimConfig>) -> Result<PipelineConfig> {
    let mut cfg: PipelineConfig = match &a.config {
        Some(p) => grasp::util::config::load_toml(p)
            .with_context(|| format!("loading pipeline config {}", p.display()))?,
        None => PipelineConfig::default(),
    };
    if let Some(s) = sim {
        // The simulator's hand goes palm down only, acts for its control period and
        // lifts as configured.
        fit_to_simulator(&mut cfg, s);
    }
    cfg.validate().with_context(|| match &a.config {
        Some(p) => format!("pipeline config {}", p.display()),
        None => "pipeline config".into(),
    })?;
    Ok(cfg)
}

fn given_source(a: &RunArgs) -> Result<Option<GraspSource>> {
    if let Some(p) = &a.grasp {
        let g = load_grasp_file(p)?;
        return Ok(Some(GraspSource::Given(g)));
    }
    if let Some(p) = &a.cloud {
        let c =
            PointCloud::load(p).with_context(|| format!("loading point cloud {}", p.display()))?;
        return Ok(Some(GraspSource::Cloud(c.points)));
    }
    if let (Some(c), Some(cl)) = (&a.center, &a.closing) {
        let v3 = |v: &Vec<f64>, name: &str| -> Result<[f64; 3]> {
            match v.as_slice() {
                &[x, y, z] => Ok([x, y, z]),
                other => bail!(
                    "--{name} takes three numbers x,y,z, got {}: {}",
                    other.len(),
                    v.iter()
                        .map(|x| grasp::util::num::short(*x))
                        .collect::<Vec<_>>()
                        .join(",")
                ),
            }
        };
        let f = GraspFile {
            center: v3(c, "center")?,
            closing: v3(cl, "closing")?,
            approach: match &a.approach {
                Some(ap) => v3(ap, "approach")?,
                None => [0.0, 0.0, -1.0],
            },
        };
        return Ok(Some(GraspSource::Given(
            f.grasp().context("the command-line grasp")?,
        )));
    }
    Ok(None)
}

fn save_cloud(path: &Path, source: &GraspSource) -> Result<()> {
    if let GraspSource::Cloud(points) = source {
        write_pcd(path, points, PcdData::Ascii)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Refuses a `--log` or `--save-cloud` that is an input (the policies' files, `--grasp`,
/// `--cloud`, `--calibration`, `--config`, `--sim-config`, the objects' files) or the
/// other output.
fn check_overlaps(a: &RunArgs, policies: &[PathBuf], log: Option<&Path>) -> Result<()> {
    use grasp::util::fsx::{check_outputs, Named};
    let mut inputs: Vec<Named> = Vec::new();
    let ckpt: Vec<PathBuf> = policies
        .iter()
        .flat_map(|p| super::checkpoint_files(p))
        .collect();
    inputs.extend(ckpt.iter().map(|p| Named::new("--policy", p)));
    for (flag, p) in [
        ("--grasp", &a.grasp),
        ("--cloud", &a.cloud),
        ("--calibration", &a.calibration),
        ("--config", &a.config),
        ("--sim-config", &a.sim_config),
    ] {
        if let Some(p) = p {
            inputs.push(Named::new(flag, p));
        }
    }
    let (flag, arg) = match &a.objects {
        Some(o) => ("--objects", o.as_str()),
        None => ("--object", a.object.as_str()),
    };
    let objects = super::object_files(arg);
    inputs.extend(objects.iter().map(|p| Named::new(flag, p)));
    let mut outputs = Vec::new();
    if let Some(p) = log {
        outputs.push(Named::new("--log", p));
    }
    if let Some(p) = &a.save_cloud {
        outputs.push(Named::new("--save-cloud", p));
    }
    check_outputs(&inputs, &outputs, &[])?;
    Ok(())
}

pub fn run(a: RunArgs, g: &Global) -> Result<()> {
    super::check_attempts(a.attempts, "grasp attempts on the object")?;
    if let Some(p) = &a.mujoco_settings {
        if a.backend != Backend::Mujoco {
            bail!("--mujoco-settings is for --backend mujoco");
        }
        grasp::run::mjcf::MujocoSettings::load(p)
            .and_then(|s| s.use_for_process())
            .with_context(|| format!("--mujoco-settings {}", p.display()))?;
    }
    if a.objects.is_some() {
        return match a.backend {
            Backend::Sim => table::<SimHandArm>(&a, g),
            #[cfg(feature = "mujoco")]
            Backend::Mujoco => table::<grasp::run::mujoco_backend::MujocoHandArm>(&a, g),
            #[cfg(not(feature = "mujoco"))]
            Backend::Mujoco => bail!(super::NO_MUJOCO),
            Backend::Ros => bail!(
                "--objects runs every trial on a simulated robot: use --backend sim or mujoco"
            ),
        };
    }
    let log = a.log.clone().unwrap_or_else(|| PathBuf::from(DEFAULT_LOG));
    let policy_arg = PathBuf::from(&a.policy);
    check_overlaps(&a, std::slice::from_ref(&policy_arg), Some(&log))?;
    let seed = g.seed.unwrap_or(0);
    let robot = Robot::builtin(Side::Left);
    let policy_dir = assets::default_or_given(&policy_arg, grasp::run::DEFAULT_POLICY, "--policy")?;
    let mut policy = PolicyRunner::load(&policy_dir)
        .with_context(|| format!("loading policy {}", policy_dir.display()))?;
    let calibration = match &a.calibration {
        Some(p) => Some(TactileCalibration::load(p)?),
        None => None,
    };
    let source = given_source(&a)?;
    if let Some(s) = &source {
        grasp::run::plan::check_source(s)?;
    }
    let one = One {
        a: &a,
        g,
        robot: &robot,
        log: &log,
        seed,
    };
    match a.backend {
        Backend::Sim => one.sim::<SimHandArm>(&mut policy, calibration, source),
        #[cfg(feature = "mujoco")]
        Backend::Mujoco => {
            one.sim::<grasp::run::mujoco_backend::MujocoHandArm>(&mut policy, calibration, source)
        }
        #[cfg(not(feature = "mujoco"))]
        Backend::Mujoco => bail!(super::NO_MUJOCO),
        Backend::Ros => {
            if !cfg!(feature = "ros") {
                bail!(NO_ROS);
            }
            let Some(calibration) = calibration else {
                bail!("the ros backend needs --calibration FILE (make one with `grasp calibrate --backend ros --out FILE`)");
            };
            let Some(source) = source else {
                bail!("the ros backend needs a grasp: --grasp FILE, --cloud FILE or --center/--closing");
            };
            if let Some(p) = &a.save_cloud {
                save_cloud(p, &source)?;
            }
            if a.attempts > 1 {
                bail!(
                    "--attempts {}: the ros backend makes one attempt (a retry needs a new \
                     cloud of where the object lies)",
                    a.attempts
                );
            }
            let cfg = pipeline_config(&a, None)?;
            let plan = plan_attempt(
                &robot,
                &source,
                &cfg,
                &Controller::Policy(&mut policy),
                seed,
                &[],
            )?;
            policy.set_object_cloud(object_cloud(&source));
            #[cfg(feature = "ros")]
            {
                let mut arm = safe_arm(super::connect_ros(&a.ros_url)?, &robot, &cfg)?;
                let mut log = AttemptLog::open(&log)?;
                let out = grasp::run::pipeline::run_attempt(
                    &mut arm,
                    &robot,
                    &plan,
                    &mut policy,
                    &calibration,
                    &cfg,
                    &mut log,
                )
                .context("grasp attempt failed")?;
                let report = one.report(&plan, &out, false, None);
                print_reports(vec![report], g)?;
            }
            #[cfg(not(feature = "ros"))]
            let _ = (plan, calibration, &one);
            Ok(())
        }
    }
}

/// What one `grasp run` (no --objects) prints its attempts with.
struct One<'a> {
    a: &'a RunArgs,
    g: &'a Global,
    robot: &'a Robot,
    log: &'a Path,
    seed: u64,
}

impl One<'_> {
    /// A session on the simulated backend `A`: the library's set-up, calibration,
    /// cameras and attempts, each attempt printed as it ends.
    fn sim<A: SimulatedArm>(
        &self,
        policy: &mut PolicyRunner,
        calibration: Option<TactileCalibration>,
        source: Option<GraspSource>,
    ) -> Result<()> {
        let (a, g) = (self.a, self.g);
        let sim_cfg = sim_config(a.sim_config.as_ref())?;
        let cfg = pipeline_config(a, Some(&sim_cfg))?;
        let object = sim_object(&a.object)?;
        if a.attempts > 1 && source.is_some() {
            bail!(
                "--attempts {} plans each attempt on the simulated cameras' cloud: drop \
                 --grasp, --cloud and --center",
                a.attempts
            );
        }
        let mut backend = SimBackendConfig::default();
        backend.raw.seed = self.seed;
        let mut session = Session::<A>::start(
            self.robot,
            object,
            sim_cfg,
            SessionConfig {
                pipeline: cfg,
                backend,
                calibration,
                source,
                cameras: CameraConfig::default(),
                seed: self.seed,
                attempts: a.attempts,
            },
        )?;
        if let Some(p) = &a.save_cloud {
            save_cloud(p, session.source())?;
        }
        let calibrated_now = session.calibrated_now();
        let mut log = AttemptLog::open(self.log)?;
        let mut reports = Vec::new();
        let numbered = a.attempts > 1;
        let out = session.run(
            self.robot,
            &mut Controller::Policy(policy),
            &mut log,
            |r: &AttemptReport| {
                let number = numbered.then_some(r.number);
                reports.push(self.report(&r.plan, &r.outcome, calibrated_now, number));
            },
        )?;
        if let Some((k, e)) = &out.stopped {
            if !g.quiet {
                eprintln!("no attempt {k}: {e}");
            }
        }
        print_reports(reports, g)
    }

    /// Prints one attempt's text report (unless `--json`) and returns its JSON report.
    fn report(
        &self,
        plan: &GraspPlan,
        out: &AttemptOutcome,
        calibrated_now: bool,
        number: Option<usize>,
    ) -> serde_json::Value {
        let a = self.a;
        let simulated = a.backend != Backend::Ros;
        let report = serde_json::json!({
            "backend": a.backend.name(),
            "policy": a.policy,
            "object": simulated.then_some(&a.object),
            "calibrated_now": calibrated_now,
            "plan": plan,
            "outcome": out,
            "log": self.log,
        });
        if !self.g.json {
            if let Some(n) = number {
                println!("attempt {n}:");
            }
            let where_ = if simulated {
                format!(" on {}", a.object)
            } else {
                String::new()
            };
            println!(
                "grasp at ({:.3}, {:.3}, {:.3}) m, closing ({:.2}, {:.2}, {:.2}){}",
                plan.center[0],
                plan.center[1],
                plan.center[2],
                plan.closing[0],
                plan.closing[1],
                plan.closing[2],
                match plan.score {
                    Some(s) => format!(
                        ", score {s:.3} (best reachable of {} candidates)",
                        plan.candidates
                    ),
                    None if plan.fallback => format!(
                        ", across the cloud's narrow axis (no usable antipodal candidate of {})",
                        plan.candidates
                    ),
                    None => String::new(),
                }
            );
            println!(
                "stage 1: {} updates, {}; policy: {} steps, {}; {} clamped commands",
                out.stage1_updates,
                if out.touched { "touched" } else { "no touch" },
                out.policy_steps,
                if out.lifted { "lifted" } else { "no lift" },
                out.clamped_commands
            );
            println!(
                "{}{}: {} ({}; judged by the {}), {:.2} s, {} log lines in {}",
                if out.success { "SUCCESS" } else { "FAILURE" },
                where_,
                out.reason,
                if calibrated_now {
                    "calibrated now"
                } else {
                    "calibration file"
                },
                out.judged_by,
                out.time_s,
                out.log_lines,
                self.log.display()
            );
        }
        report
    }
}

/// `backend` behind the safety layer: joint limits, rate limits, the sensor watchdog.
#[cfg_attr(not(feature = "ros"), allow(dead_code))]
fn safe_arm<B: HandArm>(backend: B, robot: &Robot, cfg: &PipelineConfig) -> Result<SafeHandArm<B>> {
    Ok(SafeHandArm::new(
        backend,
        robot.hand_limits(),
        cfg.safety,
        Arc::new(AtomicBool::new(false)),
    )?)
}

/// With `--json`: one attempt's report as it is, several as `{"attempts": [...],
/// "success": ...}`.
fn print_reports(mut reports: Vec<serde_json::Value>, g: &Global) -> Result<()> {
    if !g.json {
        return Ok(());
    }
    let j = if reports.len() == 1 {
        reports.remove(0)
    } else {
        let success = reports
            .last()
            .is_some_and(|r| r["outcome"]["success"] == serde_json::Value::Bool(true));
        serde_json::json!({ "attempts": reports, "success": success })
    };
    println!("{}", serde_json::to_string_pretty(&j)?);
    Ok(())
}

/// The agents of `--policy` with `--objects`: `baseline1`, `baseline2` or a checkpoint
/// folder (the shipped default found from any working directory), named as given.
fn table_agents(arg: &str) -> Result<Vec<TableAgent>> {
    let names: Vec<&str> = arg.split(',').map(str::trim).collect();
    if names.iter().any(|n| n.is_empty()) {
        bail!("--policy `{arg}`: an empty agent name in the list");
    }
    if let Some(n) = grasp::util::seq::first_repeat(&names) {
        bail!("--policy `{arg}`: `{n}` is listed twice");
    }
    names
        .iter()
        .map(|&n| {
            Ok(match n {
                "baseline1" => TableAgent::Baseline1,
                "baseline2" => TableAgent::Baseline2,
                path => TableAgent::Policy {
                    dir: assets::default_or_given(
                        Path::new(path),
                        grasp::run::DEFAULT_POLICY,
                        "--policy",
                    )?,
                    label: path.to_string(),
                },
            })
        })
        .collect()
}

/// Table I through the robot path on the simulated backend `A` (`--objects`).
fn table<A: SimulatedArm>(a: &RunArgs, g: &Global) -> Result<()> {
    let objects_arg = a.objects.as_deref().unwrap_or_default();
    if a.attempts > 1 {
        bail!(
            "--attempts {} with --objects: a table makes one attempt per trial (the paper's \
             protocol)",
            a.attempts
        );
    }
    if a.trials == 0 || a.trials > grasp::eval::MAX_TRIALS {
        bail!(
            "--trials {} must be in 1..={}",
            a.trials,
            grasp::eval::MAX_TRIALS
        );
    }
    let agents = table_agents(&a.policy)?;
    let dirs: Vec<PathBuf> = agents
        .iter()
        .filter_map(|ag| match ag {
            TableAgent::Policy { dir, .. } => Some(dir.clone()),
            _ => None,
        })
        .collect();
    check_overlaps(a, &dirs, a.log.as_deref())?;
    let calibration = match &a.calibration {
        Some(p) => Some(TactileCalibration::load(p)?),
        None => None,
    };
    let sim_cfg = sim_config(a.sim_config.as_ref())?;
    let pipeline = pipeline_config(a, Some(&sim_cfg))?;
    let objects = sim_objects(objects_arg)?;
    let cfg = TableConfig {
        trials: a.trials,
        seed: g.seed.unwrap_or(0),
        threads: threads(a.threads)?,
        sim: sim_cfg,
        pipeline,
        backend: SimBackendConfig::default(),
        cameras: CameraConfig::default(),
        calibration,
    };
    let total = (agents.len() * objects.len() * a.trials) as u64;
    let bar = progress_bar(total, !(g.quiet || g.json));
    // Installed before the table is announced: a signal from then on stops it cleanly.
    signal::stop_on_signal(
        "finishing the trials in progress, then printing the finished ones",
        g.quiet,
    )
    .context("installing the Ctrl-C and SIGTERM handler")?;
    if !g.quiet && !g.json {
        eprintln!(
            "running {} agents on {} objects x {} trials through the {} robot ...",
            agents.len(),
            objects.len(),
            a.trials,
            A::NAME
        );
    }
    let robot = Robot::builtin(Side::Left);
    let tick = || bar.inc(1);
    let mut results = run_table::<A>(
        &robot,
        &objects,
        &agents,
        &cfg,
        a.log.as_deref(),
        &tick,
        Some(&signal::STOP),
    )
    .context("running the table")?;
    bar.finish_and_clear();
    let interrupted = signal::stopped();
    // An agent none of whose trials finished before a signal has nothing to report.
    results.retain(|r| !r.result.objects.is_empty());
    if interrupted && results.is_empty() {
        super::exit_interrupted(" before any trial finished: nothing to report", false);
    }
    if g.json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else {
        print_table(&results);
    }
    if let Some(p) = a.log.as_ref().filter(|_| !g.json) {
        eprintln!("attempt logs appended to {}", p.display());
    }
    if interrupted {
        super::exit_interrupted(
            ": the results above are of the trials that finished",
            g.quiet,
        );
    }
    Ok(())
}

/// The table's text: `grasp eval`'s table, physics and paired lines, and each failed
/// trial's reason.
fn print_table(results: &[grasp::run::table::TableAgentResult]) {
    let plain: Vec<grasp::eval::AgentResult> = results.iter().map(|r| r.result.clone()).collect();
    print!("{}", grasp::eval::text_table(&plain));
    for r in &plain {
        print!("{}", grasp::eval::physics_line(r));
        if r.interrupted {
            println!(
                "{}: interrupted (SIGINT or SIGTERM): only the trials that finished are counted",
                r.agent
            );
        }
    }
    for r in results {
        for e in &r.trial_errors {
            println!(
                "{}: {} trial {} failed: {}",
                r.result.agent, e.object, e.trial, e.reason
            );
        }
    }
    let pairs = grasp::eval::paired_lines(&grasp::eval::paired_with_first(&plain))
        + &grasp::eval::unpaired_lines(&plain);
    print!("{pairs}");
}

/// A progress bar of `total` trials on stderr when `show` and stderr is a terminal.
fn progress_bar(total: u64, show: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if show && std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(total);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} trials, {elapsed} (eta {eta})",
        ) {
            b.set_style(style);
        }
        b
    } else {
        indicatif::ProgressBar::hidden()
    }
}
