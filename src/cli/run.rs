//! `grasp run`: a grasp attempt of a trained policy on the simulated or the real robot
//! (Sec. V-B): plan a two-finger grasp, map it to the hand, stage 1, the policy, the lift.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::hardware::calibration::{TactileCalibration, DEFAULT_THRESHOLD_FRACTION};
use grasp::hardware::log::AttemptLog;
use grasp::hardware::pointcloud::{write_pcd, PcdData, PointCloud};
use grasp::hardware::safety::SafeHandArm;
use grasp::hardware::HandArm;
use grasp::robot::{Robot, Side};
use grasp::run::pipeline::{
    load_grasp_file, plan_grasp_avoiding, run_attempt, AttemptOutcome, GraspFile, GraspPlan,
    GraspSource, PipelineConfig, PolicyRunner,
};
use grasp::run::sim_backend::CameraConfig;
use grasp::sim::SimConfig;
use grasp::util::assets;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::{calibrate_sim, sim_backend, sim_config, sim_object, Backend, Global, NO_ROS};

/// Run a grasp attempt of a trained policy on the simulated or the real robot (with
/// --attempts, more after a failed lift: sim backend).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  grasp run --backend sim --object box_gelatin
  grasp run --backend sim --object box_gelatin --cloud scan.pcd --log attempt.jsonl --json
  grasp run --backend sim --center 0,0,0.02 --closing 1,0,0 --calibration tactile.json
  grasp run --backend ros --ros-url ws://robot:9090 --grasp grasp.toml --calibration tactile.json

With the sim backend and no grasp or cloud, the cloud is what four simulated depth
camera views (one from each side) see of the object (noisy, partial); --save-cloud
writes it as PCD. Where the cloud holds no usable antipodal pair, the hand closes across
the cloud's narrowest horizontal extent. Without
--calibration the sim backend calibrates its fingertips first (as `grasp calibrate`).
A grasp file is TOML or JSON: center = [x, y, z], closing = [x, y, z], and optionally
approach = [x, y, z] (default [0, 0, -1]), world frame, metres. Every step is appended
to the attempt log (JSON lines). The sim backend places the hand palm down only, so its
grasps are made top-down.")]
pub struct RunArgs {
    /// The robot: sim or ros.
    #[arg(long, value_enum, default_value = "sim")]
    pub backend: Backend,
    /// Checkpoint folder of the policy (default: the shipped policy that lifted the most
    /// validation objects from the pre-grasp, the placement `grasp run` plans; found from
    /// any working directory, see docs/robot-hardware.md).
    #[arg(long, default_value = grasp::run::DEFAULT_POLICY)]
    pub policy: PathBuf,
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
    /// Attempt log (JSON lines, appended).
    #[arg(long, default_value = "attempt.jsonl")]
    pub log: PathBuf,
    /// Pipeline config (TOML, see `PipelineConfig`); defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
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
        cfg.top_down_only = true;
        cfg.control_period_s = s.control_period;
        cfg.lift_height_m = s.lift.height;
        cfg.lift_duration_s = s.lift.ramp_time + s.lift.hold_time;
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

/// Refuses a `--log` or `--save-cloud` that is an input (the policy's files, `--grasp`,
/// `--cloud`, `--calibration`, `--config`, `--sim-config`) or the other output.
fn check_overlaps(a: &RunArgs) -> Result<()> {
    use grasp::util::fsx::{check_outputs, Named};
    let ckpt = super::checkpoint_files(&a.policy);
    let mut inputs: Vec<Named> = ckpt.iter().map(|p| Named::new("--policy", p)).collect();
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
    let objects = super::object_files(&a.object);
    inputs.extend(objects.iter().map(|p| Named::new("--object", p)));
    let mut outputs = vec![Named::new("--log", &a.log)];
    if let Some(p) = &a.save_cloud {
        outputs.push(Named::new("--save-cloud", p));
    }
    check_outputs(&inputs, &outputs, &[])?;
    Ok(())
}

pub fn run(a: RunArgs, g: &Global) -> Result<()> {
    super::check_attempts(a.attempts, "grasp attempts on the object")?;
    check_overlaps(&a)?;
    let seed = g.seed.unwrap_or(0);
    let robot = Robot::builtin(Side::Left);
    let policy_dir = assets::default_or_given(&a.policy, grasp::run::DEFAULT_POLICY, "--policy")?;
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
    match a.backend {
        Backend::Sim => {
            let sim_cfg = sim_config(a.sim_config.as_ref())?;
            let cfg = pipeline_config(&a, Some(&sim_cfg))?;
            let mut arm = sim_backend(sim_object(&a.object)?, sim_cfg, seed)?;
            let (calibration, calibrated_now) = match calibration {
                Some(c) => (c, false),
                None => (
                    calibrate_sim(&mut arm, 10, DEFAULT_THRESHOLD_FRACTION, 10.0, 5)?.calibration,
                    true,
                ),
            };
            if a.attempts > 1 && source.is_some() {
                bail!(
                    "--attempts {} plans each attempt on the simulated cameras' cloud: drop \
                     --grasp, --cloud and --center",
                    a.attempts
                );
            }
            let cameras = CameraConfig::default();
            let mut source = match source {
                Some(s) => s,
                None => GraspSource::Cloud(
                    arm.camera_cloud(&cameras, seed)
                        .context("simulating the depth cameras")?,
                ),
            };
            if let Some(p) = &a.save_cloud {
                save_cloud(p, &source)?;
            }
            let mut arm = safe_arm(arm, &robot, &cfg)?;
            let mut log = AttemptLog::open(&a.log)?;
            let mut tried: Vec<GraspPlan> = Vec::new();
            let mut reports = Vec::new();
            for k in 0..a.attempts {
                if k > 0 {
                    if let Err(e) = arm.backend_mut().settle_for_retry() {
                        if !g.quiet {
                            eprintln!("no attempt {}: {e}", k + 1);
                        }
                        break;
                    }
                    let s = grasp::eval::trial::attempt_seed(seed, k);
                    let cloud = arm.backend().camera_cloud(&cameras, s);
                    source = GraspSource::Cloud(cloud.context("simulating the depth cameras")?);
                }
                let plan = plan(&robot, &source, &cfg, &policy, seed, &tried)?;
                policy.set_object_cloud(object_cloud(&source));
                let at = Attempt {
                    plan: &plan,
                    calibration: &calibration,
                    cfg: &cfg,
                    calibrated_now,
                    number: (a.attempts > 1).then_some(k + 1),
                };
                let (out, report) = attempt(&mut arm, &robot, &at, &mut policy, &mut log, &a, g)?;
                reports.push(report);
                tried.push(plan);
                if out.success {
                    break;
                }
            }
            print_reports(reports, g)
        }
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
            let plan = plan(&robot, &source, &cfg, &policy, seed, &[])?;
            policy.set_object_cloud(object_cloud(&source));
            #[cfg(feature = "ros")]
            {
                let mut arm = safe_arm(super::connect_ros(&a.ros_url)?, &robot, &cfg)?;
                let mut log = AttemptLog::open(&a.log)?;
                let at = Attempt {
                    plan: &plan,
                    calibration: &calibration,
                    cfg: &cfg,
                    calibrated_now: false,
                    number: None,
                };
                let (_, report) = attempt(&mut arm, &robot, &at, &mut policy, &mut log, &a, g)?;
                print_reports(vec![report], g)?;
            }
            #[cfg(not(feature = "ros"))]
            let _ = (plan, calibration);
            Ok(())
        }
    }
}

/// The object's points of a cloud source (what an M3G policy measures its surface
/// vectors against); none for a given grasp.
fn object_cloud(source: &GraspSource) -> Option<Vec<nalgebra::Point3<f64>>> {
    match source {
        GraspSource::Cloud(c) => Some(c.clone()),
        GraspSource::Given(_) => None,
    }
}

fn plan(
    robot: &Robot,
    source: &GraspSource,
    cfg: &PipelineConfig,
    policy: &PolicyRunner,
    seed: u64,
    tried: &[GraspPlan],
) -> Result<GraspPlan> {
    let mut cfg = cfg.clone();
    cfg.antipodal.seed = seed;
    let preshape = cfg.preshape_angles(policy.env_config())?;
    plan_grasp_avoiding(robot, source, &preshape, &cfg, tried).context("planning the grasp")
}

/// `backend` behind the safety layer: joint limits, rate limits, the sensor watchdog.
fn safe_arm<B: HandArm>(backend: B, robot: &Robot, cfg: &PipelineConfig) -> Result<SafeHandArm<B>> {
    Ok(SafeHandArm::new(
        backend,
        robot.hand_limits(),
        cfg.safety,
        Arc::new(AtomicBool::new(false)),
    )?)
}

/// One attempt's plan and settings.
struct Attempt<'a> {
    plan: &'a GraspPlan,
    calibration: &'a TactileCalibration,
    cfg: &'a PipelineConfig,
    calibrated_now: bool,
    /// The attempt's number when `--attempts` allows more than one.
    number: Option<usize>,
}

/// Runs one attempt, prints its text report (unless `--json`) and returns its outcome with
/// its JSON report.
fn attempt<B: HandArm>(
    arm: &mut SafeHandArm<B>,
    robot: &Robot,
    at: &Attempt,
    policy: &mut PolicyRunner,
    log: &mut AttemptLog,
    a: &RunArgs,
    g: &Global,
) -> Result<(AttemptOutcome, serde_json::Value)> {
    let plan = at.plan;
    let out = run_attempt(arm, robot, plan, policy, at.calibration, at.cfg, log)
        .context("grasp attempt failed")?;
    let report = serde_json::json!({
        "backend": format!("{:?}", a.backend).to_lowercase(),
        "policy": a.policy,
        "object": (a.backend == Backend::Sim).then_some(&a.object),
        "calibrated_now": at.calibrated_now,
        "plan": plan,
        "outcome": out,
        "log": a.log,
    });
    if !g.json {
        if let Some(n) = at.number {
            println!("attempt {n}:");
        }
        let where_ = if a.backend == Backend::Sim {
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
            if at.calibrated_now {
                "calibrated now"
            } else {
                "calibration file"
            },
            out.judged_by,
            out.time_s,
            out.log_lines,
            a.log.display()
        );
    }
    Ok((out, report))
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
