//! `grasp run` as one request: [`RunRequest`] holds what the command line names (the
//! robot, the policy or a table's agents, the grasp, the calibration, the configs, the
//! object or object set, the log); [`execute`] checks it, loads what it names and carries
//! it out: one session of attempts ([`super::session`]) or Table I through the robot path
//! ([`super::table`]). The caller hears each attempt and trial as it ends
//! ([`RunEvent`]) and prints what comes back ([`RunOutput`]). Errors name the command
//! line's flags.

use super::pipeline::{
    load_grasp_file, AttemptOutcome, Controller, GraspFile, GraspPlan, GraspSource, PipelineConfig,
    PolicyRunner,
};
use super::session::{fit_to_simulator, Session, SessionConfig, SessionError};
use super::sim_backend::{CameraConfig, SimBackendConfig, SimHandArm};
use super::simulated::SimulatedArm;
use super::table::{run_table, TableAgent, TableAgentResult, TableConfig};
use super::RunError;
use crate::hardware::calibration::TactileCalibration;
use crate::hardware::log::AttemptLog;
use crate::perception::pointcloud::{write_pcd, PcdData, PointCloud};
use crate::robot::{Robot, Side};
use crate::sim::{ObjectSpec, SimConfig};
use crate::util::fsx::{check_outputs, Named};
use crate::util::step::{StepContext, StepError};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// The attempt log of a single run when the request names none.
pub const DEFAULT_LOG: &str = "attempt.jsonl";

/// The error of the ros backend in a build without the `ros` feature.
pub const NO_ROS: &str =
    "the ros backend is not part of this build: rebuild with `cargo build --release --features ros`";

/// The error of the mujoco backend in a build without the `mujoco` feature.
pub const NO_MUJOCO: &str = "the mujoco backend is not part of this build: rebuild with `cargo build --release --features mujoco` (see docs/robot-hardware.md)";

/// The robot a request runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RobotBackend {
    /// The Rapier simulator with a raw-sensor model.
    Sim,
    /// The real robot through rosbridge (feature `ros`).
    Ros,
    /// MuJoCo at simulated time (feature `mujoco`).
    Mujoco,
}

impl RobotBackend {
    /// The name as `--backend` spells it.
    pub fn name(self) -> &'static str {
        match self {
            RobotBackend::Sim => "sim",
            RobotBackend::Ros => "ros",
            RobotBackend::Mujoco => "mujoco",
        }
    }
}

/// A grasp the request gives instead of the simulated cameras' cloud.
#[derive(Debug, Clone, PartialEq)]
pub enum GraspInput {
    /// A two-finger grasp file, TOML or JSON (`--grasp`).
    File(PathBuf),
    /// A point cloud to plan on, PCD or PLY (`--cloud`).
    Cloud(PathBuf),
    /// A grasp on the command line (`--center`, `--closing`, `--approach`; straight down
    /// without an approach), as given: each must hold three numbers.
    Given {
        /// The grasp centre (m).
        center: Vec<f64>,
        /// The closing direction.
        closing: Vec<f64>,
        /// The approach direction.
        approach: Option<Vec<f64>>,
    },
}

/// What `grasp run` is asked to do (see the module docs). A table (`objects`) runs on a
/// simulated robot, every agent of `policy` on `trials` scenes of each object; otherwise
/// one session of up to `attempts` attempts on `object` (or on the real robot).
#[derive(Debug, Clone)]
pub struct RunRequest {
    /// The robot.
    pub backend: RobotBackend,
    /// A checkpoint folder; for a table a comma list of agents (checkpoint folders,
    /// `baseline1`, `baseline2`). [`super::DEFAULT_POLICY`] is found from any folder.
    pub policy: String,
    /// The grasp to make; `None`: plan on the simulated cameras' cloud.
    pub grasp: Option<GraspInput>,
    /// A tactile calibration file; `None`: a simulated backend calibrates first.
    pub calibration: Option<PathBuf>,
    /// The simulated object of a single run.
    pub object: String,
    /// A table's object set (a set name, a manifest or a comma list).
    pub objects: Option<String>,
    /// A table's trials per object.
    pub trials: usize,
    /// A table's worker threads (`None`: the available cores).
    pub threads: Option<usize>,
    /// The attempt log (a single run: [`DEFAULT_LOG`] when `None`; a table writes none
    /// without it).
    pub log: Option<PathBuf>,
    /// The pipeline config (TOML); the defaults when `None`.
    pub config: Option<PathBuf>,
    /// The simulator config (TOML); the built-in defaults when `None`.
    pub sim_config: Option<PathBuf>,
    /// MuJoCo's engine settings (TOML, the mujoco backend).
    pub mujoco_settings: Option<PathBuf>,
    /// Where to write the cloud the grasp was planned on (PCD).
    pub save_cloud: Option<PathBuf>,
    /// The rosbridge websocket (the ros backend).
    pub ros_url: String,
    /// Attempts at most of a single run (a retry replans on the cameras' new cloud).
    pub attempts: usize,
    /// The seed (`grasp --seed`).
    pub seed: u64,
}

/// One attempt of a single run as reported (its JSON is `grasp run --json`'s).
#[derive(Debug, Clone, Serialize)]
pub struct RunAttempt {
    /// The robot's name.
    pub backend: &'static str,
    /// Whether the fingertips were calibrated in this run (not read from a file).
    pub calibrated_now: bool,
    /// The attempt log.
    pub log: PathBuf,
    /// The simulated object (`None` on the real robot).
    pub object: Option<String>,
    /// How it ended.
    pub outcome: AttemptOutcome,
    /// Its plan.
    pub plan: GraspPlan,
    /// The policy as the request names it.
    pub policy: String,
    /// Its number where the run may make several attempts.
    #[serde(skip)]
    pub number: Option<usize>,
}

/// What [`execute`] tells its caller as the work goes on (from worker threads too).
#[derive(Debug)]
pub enum RunEvent<'a> {
    /// A table starts: its agents, objects and trials per object on the named robot.
    TableStarts {
        /// Agents.
        agents: usize,
        /// Objects.
        objects: usize,
        /// Trials per object.
        trials: usize,
        /// The simulated robot's name.
        backend: &'static str,
    },
    /// A trial of the table ended.
    TrialDone,
    /// An attempt of a single run ended.
    Attempt(&'a RunAttempt),
}

/// What a request gave.
#[derive(Debug)]
pub enum RunOutput {
    /// A single run's attempts, in order.
    Attempts {
        /// The attempts made.
        attempts: Vec<RunAttempt>,
        /// Why a failed run made no further attempt (`no attempt K: reason`).
        stopped: Option<String>,
    },
    /// A table: the agents with at least one finished trial.
    Table {
        /// Per agent, as `grasp eval --json` has it (plus the backend and failed trials).
        results: Vec<TableAgentResult>,
        /// Whether `stop` ended it before every trial ran.
        interrupted: bool,
    },
}

/// Error of a request: a refused flag, a failed step with its cause, or the attempt's own.
#[derive(Debug, thiserror::Error)]
pub enum RequestError {
    /// A flag's value, or flags that do not go together.
    #[error("{0}")]
    Flags(String),
    /// A step of the set-up or of the work failed; the cause follows.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The grasp pipeline refused something.
    #[error(transparent)]
    Run(#[from] RunError),
    /// A simulated session failed.
    #[error(transparent)]
    Session(#[from] SessionError),
    /// An output would replace an input or another output.
    #[error(transparent)]
    Overlap(#[from] crate::util::fsx::OverlapError),
    /// The shipped policy named is not found.
    #[error(transparent)]
    Shipped(#[from] crate::util::assets::NotShipped),
    /// The object or object set cannot be simulated.
    #[error(transparent)]
    Objects(#[from] crate::sim::ObjectSetError),
}

/// `Err(what)` for a refused flag.
fn refuse<T>(what: String) -> Result<T, RequestError> {
    Err(RequestError::Flags(what))
}

/// Carries out `req` (see the module docs), telling `on_event` of each attempt and trial
/// as it ends; a set `stop` starts no new trial of a table.
pub fn execute(
    req: &RunRequest,
    on_event: &(dyn Fn(RunEvent<'_>) + Sync),
    stop: Option<&AtomicBool>,
) -> Result<RunOutput, RequestError> {
    crate::eval::check_attempts(req.attempts, "grasp attempts on the object")
        .map_err(RequestError::Flags)?;
    if let Some(p) = &req.mujoco_settings {
        if req.backend != RobotBackend::Mujoco {
            return refuse("--mujoco-settings is for --backend mujoco".into());
        }
        super::mjcf::MujocoSettings::load(p)
            .and_then(|s| s.use_for_process())
            .step(|| format!("--mujoco-settings {}", p.display()))?;
    }
    let robot = Robot::builtin(Side::Left);
    if req.objects.is_some() {
        return match req.backend {
            RobotBackend::Sim => table::<SimHandArm>(req, &robot, on_event, stop),
            #[cfg(feature = "mujoco")]
            RobotBackend::Mujoco => {
                table::<super::mujoco_backend::MujocoHandArm>(req, &robot, on_event, stop)
            }
            #[cfg(not(feature = "mujoco"))]
            RobotBackend::Mujoco => refuse(NO_MUJOCO.into()),
            RobotBackend::Ros => refuse(
                "--objects runs every trial on a simulated robot: use --backend sim or mujoco"
                    .into(),
            ),
        };
    }
    let one = One::load(req, robot)?;
    match req.backend {
        RobotBackend::Sim => one.simulated::<SimHandArm>(on_event),
        #[cfg(feature = "mujoco")]
        RobotBackend::Mujoco => one.simulated::<super::mujoco_backend::MujocoHandArm>(on_event),
        #[cfg(not(feature = "mujoco"))]
        RobotBackend::Mujoco => refuse(NO_MUJOCO.into()),
        RobotBackend::Ros => one.real(on_event),
    }
}

/// The pipeline config of `req` (its file or the defaults), fitted to the simulator
/// `sim` where the robot is simulated, and checked.
fn pipeline_config(
    req: &RunRequest,
    sim: Option<&SimConfig>,
) -> Result<PipelineConfig, RequestError> {
    let mut cfg: PipelineConfig = match &req.config {
        Some(p) => crate::util::config::load_toml(p)
            .step(|| format!("loading pipeline config {}", p.display()))?,
        None => PipelineConfig::default(),
    };
    if let Some(s) = sim {
        // The simulator's hand goes palm down only, acts for its control period and
        // lifts as configured.
        fit_to_simulator(&mut cfg, s);
    }
    cfg.validate().step(|| match &req.config {
        Some(p) => format!("pipeline config {}", p.display()),
        None => "pipeline config".into(),
    })?;
    Ok(cfg)
}

/// The calibration file of `req`, loaded.
fn calibration(req: &RunRequest) -> Result<Option<TactileCalibration>, RequestError> {
    Ok(match &req.calibration {
        Some(p) => Some(TactileCalibration::load(p).map_err(RunError::from)?),
        None => None,
    })
}

impl GraspInput {
    /// The grasp or cloud it names, loaded and checked.
    pub fn source(&self) -> Result<GraspSource, RequestError> {
        let source = match self {
            GraspInput::File(p) => GraspSource::Given(load_grasp_file(p)?),
            GraspInput::Cloud(p) => GraspSource::Cloud(
                PointCloud::load(p)
                    .step(|| format!("loading point cloud {}", p.display()))?
                    .points,
            ),
            GraspInput::Given {
                center,
                closing,
                approach,
            } => {
                let f = GraspFile {
                    center: three(center, "center")?,
                    closing: three(closing, "closing")?,
                    approach: match approach {
                        Some(a) => three(a, "approach")?,
                        None => [0.0, 0.0, -1.0],
                    },
                };
                GraspSource::Given(f.grasp().step(|| "the command-line grasp".into())?)
            }
        };
        super::plan::check_source(&source)?;
        Ok(source)
    }
}

/// The three numbers of flag `--name`.
fn three(v: &[f64], name: &str) -> Result<[f64; 3], RequestError> {
    match v {
        &[x, y, z] => Ok([x, y, z]),
        other => refuse(format!(
            "--{name} takes three numbers x,y,z, got {}: {}",
            other.len(),
            v.iter()
                .map(|x| crate::util::num::short(*x))
                .collect::<Vec<_>>()
                .join(",")
        )),
    }
}

/// Writes a cloud source as PCD.
fn save_cloud(path: &Path, source: &GraspSource) -> Result<(), RequestError> {
    if let GraspSource::Cloud(points) = source {
        write_pcd(path, points, PcdData::Ascii).step(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Refuses a `--log` or `--save-cloud` that is an input (the policies' files, `--grasp`,
/// `--cloud`, `--calibration`, `--config`, `--sim-config`, the objects' files) or the
/// other output.
fn check_overlaps(
    req: &RunRequest,
    policies: &[PathBuf],
    log: Option<&Path>,
) -> Result<(), RequestError> {
    let ckpt: Vec<PathBuf> = policies
        .iter()
        .flat_map(|p| crate::checkpoint::files::read_by_commands(p))
        .collect();
    let mut inputs: Vec<Named> = ckpt.iter().map(|p| Named::new("--policy", p)).collect();
    let (grasp, cloud) = match &req.grasp {
        Some(GraspInput::File(p)) => (Some(p), None),
        Some(GraspInput::Cloud(p)) => (None, Some(p)),
        _ => (None, None),
    };
    for (flag, p) in [
        ("--grasp", grasp),
        ("--cloud", cloud),
        ("--calibration", req.calibration.as_ref()),
        ("--config", req.config.as_ref()),
        ("--sim-config", req.sim_config.as_ref()),
    ] {
        if let Some(p) = p {
            inputs.push(Named::new(flag, p));
        }
    }
    let (flag, arg) = match &req.objects {
        Some(o) => ("--objects", o.as_str()),
        None => ("--object", req.object.as_str()),
    };
    let objects = crate::objects::sets::files_read(arg);
    inputs.extend(objects.iter().map(|p| Named::new(flag, p)));
    let mut outputs = Vec::new();
    if let Some(p) = log {
        outputs.push(Named::new("--log", p));
    }
    if let Some(p) = &req.save_cloud {
        outputs.push(Named::new("--save-cloud", p));
    }
    Ok(check_outputs(&inputs, &outputs, &[])?)
}

/// A shipped policy or the folder given.
fn policy_dir(given: &str) -> Result<PathBuf, RequestError> {
    Ok(crate::util::assets::default_or_given(
        Path::new(given),
        super::DEFAULT_POLICY,
        "--policy",
    )?)
}

/// The report of one attempt of `req`'s single run, logged to `log`.
fn report(
    req: &RunRequest,
    log: &Path,
    plan: &GraspPlan,
    outcome: &AttemptOutcome,
    calibrated_now: bool,
    number: Option<usize>,
) -> RunAttempt {
    let simulated = req.backend != RobotBackend::Ros;
    RunAttempt {
        backend: req.backend.name(),
        calibrated_now,
        log: log.to_path_buf(),
        object: simulated.then(|| req.object.clone()),
        outcome: outcome.clone(),
        plan: plan.clone(),
        policy: req.policy.clone(),
        number,
    }
}

/// A single run, loaded: the policy, the calibration and the grasp given.
struct One<'r> {
    req: &'r RunRequest,
    robot: Robot,
    log: PathBuf,
    policy: PolicyRunner,
    calibration: Option<TactileCalibration>,
    source: Option<GraspSource>,
}

impl<'r> One<'r> {
    fn load(req: &'r RunRequest, robot: Robot) -> Result<One<'r>, RequestError> {
        let log = req
            .log
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_LOG));
        check_overlaps(req, &[PathBuf::from(&req.policy)], Some(&log))?;
        let dir = policy_dir(&req.policy)?;
        let policy =
            PolicyRunner::load(&dir).step(|| format!("loading policy {}", dir.display()))?;
        let calibration = calibration(req)?;
        let source = req.grasp.as_ref().map(GraspInput::source).transpose()?;
        Ok(One {
            req,
            robot,
            log,
            policy,
            calibration,
            source,
        })
    }

    /// A session on the simulated backend `A`: set-up, calibration, cameras and attempts.
    fn simulated<A: SimulatedArm>(
        mut self,
        on_event: &(dyn Fn(RunEvent<'_>) + Sync),
    ) -> Result<RunOutput, RequestError> {
        let req = self.req;
        let sim_cfg = SimConfig::load_flag(req.sim_config.as_deref())?;
        let cfg = pipeline_config(req, Some(&sim_cfg))?;
        let object = ObjectSpec::simulable_one(&req.object)?;
        if req.attempts > 1 && self.source.is_some() {
            return refuse(format!(
                "--attempts {} plans each attempt on the simulated cameras' cloud: drop \
                 --grasp, --cloud and --center",
                req.attempts
            ));
        }
        let mut backend = SimBackendConfig::default();
        backend.raw.seed = req.seed;
        let mut session = Session::<A>::start(
            &self.robot,
            object,
            sim_cfg,
            SessionConfig {
                pipeline: cfg,
                backend,
                calibration: self.calibration.take(),
                source: self.source.take(),
                cameras: CameraConfig::default(),
                seed: req.seed,
                attempts: req.attempts,
            },
        )?;
        if let Some(p) = &req.save_cloud {
            save_cloud(p, session.source())?;
        }
        let calibrated_now = session.calibrated_now();
        let mut log = AttemptLog::open(&self.log).map_err(RunError::from)?;
        let numbered = req.attempts > 1;
        let mut attempts = Vec::new();
        let out = session.run(
            &self.robot,
            &mut Controller::Policy(&mut self.policy),
            &mut log,
            |r| {
                let number = numbered.then_some(r.number);
                let done = report(req, &self.log, &r.plan, &r.outcome, calibrated_now, number);
                on_event(RunEvent::Attempt(&done));
                attempts.push(done);
            },
        )?;
        Ok(RunOutput::Attempts {
            attempts,
            stopped: out.stopped.map(|(k, e)| format!("no attempt {k}: {e}")),
        })
    }

    /// One attempt on the real robot (feature `ros`) with the given grasp and
    /// calibration.
    fn real(mut self, on_event: &(dyn Fn(RunEvent<'_>) + Sync)) -> Result<RunOutput, RequestError> {
        let req = self.req;
        if !cfg!(feature = "ros") {
            return refuse(NO_ROS.into());
        }
        let Some(calibration) = self.calibration.take() else {
            return refuse("the ros backend needs --calibration FILE (make one with `grasp calibrate --backend ros --out FILE`)".into());
        };
        let Some(source) = self.source.take() else {
            return refuse(
                "the ros backend needs a grasp: --grasp FILE, --cloud FILE or --center/--closing"
                    .into(),
            );
        };
        if let Some(p) = &req.save_cloud {
            save_cloud(p, &source)?;
        }
        if req.attempts > 1 {
            return refuse(format!(
                "--attempts {}: the ros backend makes one attempt (a retry needs a new \
                 cloud of where the object lies)",
                req.attempts
            ));
        }
        let cfg = pipeline_config(req, None)?;
        let plan = super::session::plan_attempt(
            &self.robot,
            &source,
            &cfg,
            &Controller::Policy(&mut self.policy),
            req.seed,
            &[],
        )?;
        self.policy
            .set_object_cloud(super::session::object_cloud(&source));
        #[cfg(feature = "ros")]
        {
            use crate::hardware::safety::SafeHandArm;
            let ros = connect_ros(&req.ros_url)?;
            let mut arm = SafeHandArm::new(
                ros,
                self.robot.hand_limits(),
                cfg.safety,
                std::sync::Arc::new(AtomicBool::new(false)),
            )
            .map_err(RunError::from)?;
            let mut log = AttemptLog::open(&self.log).map_err(RunError::from)?;
            let out = super::pipeline::run_attempt(
                &mut arm,
                &self.robot,
                &plan,
                &mut self.policy,
                &calibration,
                &cfg,
                &mut log,
            )
            .step(|| "grasp attempt failed".into())?;
            let done = report(req, &self.log, &plan, &out, false, None);
            on_event(RunEvent::Attempt(&done));
            Ok(RunOutput::Attempts {
                attempts: vec![done],
                stopped: None,
            })
        }
        #[cfg(not(feature = "ros"))]
        {
            let _ = (plan, calibration, on_event);
            refuse(NO_ROS.into())
        }
    }
}

/// Connects to the robot's rosbridge at `url`.
#[cfg(feature = "ros")]
pub fn connect_ros(url: &str) -> Result<crate::hardware::ros::RosHandArm, RequestError> {
    use crate::hardware::ros::{RosConfig, RosHandArm};
    Ok(RosHandArm::connect(url, RosConfig::default())
        .step(|| format!("connecting to rosbridge at {url}"))?)
}

/// The agents of a table's `policy`: `baseline1`, `baseline2` or a checkpoint folder (the
/// shipped default found from any working directory), named as given.
fn table_agents(arg: &str) -> Result<Vec<TableAgent>, RequestError> {
    let names: Vec<&str> = arg.split(',').map(str::trim).collect();
    if names.iter().any(|n| n.is_empty()) {
        return refuse(format!("--policy `{arg}`: an empty agent name in the list"));
    }
    if let Some(n) = crate::util::seq::first_repeat(&names) {
        return refuse(format!("--policy `{arg}`: `{n}` is listed twice"));
    }
    names
        .iter()
        .map(|&n| {
            Ok(match n {
                "baseline1" => TableAgent::Baseline1,
                "baseline2" => TableAgent::Baseline2,
                path => TableAgent::Policy {
                    dir: policy_dir(path)?,
                    label: path.to_string(),
                },
            })
        })
        .collect()
}

/// Table I through the robot path on the simulated backend `A`.
fn table<A: SimulatedArm>(
    req: &RunRequest,
    robot: &Robot,
    on_event: &(dyn Fn(RunEvent<'_>) + Sync),
    stop: Option<&AtomicBool>,
) -> Result<RunOutput, RequestError> {
    let objects_arg = req.objects.as_deref().unwrap_or_default();
    if req.attempts > 1 {
        return refuse(format!(
            "--attempts {} with --objects: a table makes one attempt per trial (the paper's \
             protocol)",
            req.attempts
        ));
    }
    if req.trials == 0 || req.trials > crate::eval::MAX_TRIALS {
        return refuse(format!(
            "--trials {} must be in 1..={}",
            req.trials,
            crate::eval::MAX_TRIALS
        ));
    }
    let agents = table_agents(&req.policy)?;
    let dirs: Vec<PathBuf> = agents
        .iter()
        .filter_map(|ag| match ag {
            TableAgent::Policy { dir, .. } => Some(dir.clone()),
            _ => None,
        })
        .collect();
    check_overlaps(req, &dirs, req.log.as_deref())?;
    let calibration = calibration(req)?;
    let sim = SimConfig::load_flag(req.sim_config.as_deref())?;
    let pipeline = pipeline_config(req, Some(&sim))?;
    let objects = ObjectSpec::simulable_set(objects_arg)?;
    let cfg = TableConfig {
        trials: req.trials,
        seed: req.seed,
        threads: crate::util::threads::from_flag(req.threads).map_err(RequestError::Flags)?,
        sim,
        pipeline,
        backend: SimBackendConfig::default(),
        cameras: CameraConfig::default(),
        calibration,
    };
    on_event(RunEvent::TableStarts {
        agents: agents.len(),
        objects: objects.len(),
        trials: req.trials,
        backend: A::NAME,
    });
    let tick = || on_event(RunEvent::TrialDone);
    let mut results = run_table::<A>(
        robot,
        &objects,
        &agents,
        &cfg,
        req.log.as_deref(),
        &tick,
        stop,
    )
    .step(|| "running the table".into())?;
    let interrupted = crate::util::signal::is_set(stop);
    // An agent none of whose trials finished before a stop has nothing to report.
    results.retain(|r| !r.result.objects.is_empty());
    Ok(RunOutput::Table {
        results,
        interrupted,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> RunRequest {
        RunRequest {
            backend: RobotBackend::Sim,
            policy: super::super::DEFAULT_POLICY.into(),
            grasp: None,
            calibration: None,
            object: "box_gelatin".into(),
            objects: None,
            trials: 10,
            threads: None,
            log: None,
            config: None,
            sim_config: None,
            mujoco_settings: None,
            save_cloud: None,
            ros_url: "ws://localhost:9090".into(),
            attempts: 1,
            seed: 0,
        }
    }

    fn refused(req: &RunRequest) -> String {
        match execute(req, &|_| {}, None) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("the request ran"),
        }
    }

    #[test]
    fn a_command_line_grasp_takes_three_numbers_each() {
        let g = GraspInput::Given {
            center: vec![0.0, 0.1],
            closing: vec![1.0, 0.0, 0.0],
            approach: None,
        };
        let e = g.source().err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(e, "--center takes three numbers x,y,z, got 2: 0,0.1");
        let g = GraspInput::Given {
            center: vec![0.0, 0.0, 0.05],
            closing: vec![1.0, 0.0, 0.0],
            approach: None,
        };
        match g.source() {
            Ok(GraspSource::Given(t)) => {
                assert_eq!(t.approach, nalgebra::Vector3::new(0.0, 0.0, -1.0));
            }
            other => panic!("expected a given grasp, got {other:?}"),
        }
    }

    #[test]
    fn flags_that_do_not_go_together_are_refused_before_any_work() {
        let mut r = request();
        r.mujoco_settings = Some("configs/mujoco.toml".into());
        assert_eq!(refused(&r), "--mujoco-settings is for --backend mujoco");
        let mut r = request();
        r.objects = Some("unseen".into());
        r.backend = RobotBackend::Ros;
        assert!(refused(&r).starts_with("--objects runs every trial on a simulated robot"));
        r.backend = RobotBackend::Sim;
        r.attempts = 2;
        assert!(refused(&r).starts_with("--attempts 2 with --objects"));
        r.attempts = 1;
        r.trials = 0;
        assert!(refused(&r).starts_with("--trials 0 must be in 1..="));
        r.trials = 1;
        r.policy = "baseline1,,baseline2".into();
        assert_eq!(
            refused(&r),
            "--policy `baseline1,,baseline2`: an empty agent name in the list"
        );
        r.policy = "baseline1,baseline1".into();
        assert_eq!(
            refused(&r),
            "--policy `baseline1,baseline1`: `baseline1` is listed twice"
        );
        let mut r = request();
        r.attempts = 0;
        assert!(refused(&r).starts_with("--attempts 0 must be in 1..="));
    }
}
