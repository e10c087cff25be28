//! Table I through the robot path (`grasp run --objects SET --trials N`): every agent (a
//! policy or a scripted baseline) on the same scenes, each trial a whole [`Session`] on a
//! fresh simulated backend: the object placed as the trial's seed draws it, the fingertips
//! calibrated, the cameras' cloud, the plan, the attempt and the lift, judged by the
//! backend. The results have the shape of `grasp eval --json` ([`AgentResult`], built by
//! [`crate::eval::aggregate`]), so that `grasp eval --from-json`, its plots and its paired
//! comparisons read them.
//!
//! # Scenes
//! Trial `t` of object `o` is seeded by [`trial_seed`]`(seed, o, t)` as in `grasp eval`
//! (common random numbers: every agent meets the same scene). From that seed a
//! `ChaCha8Rng` draws, in order, the object's offset on the table `dx`, `dy` (uniform in
//! +-`delta_p` of eq. 6 at `grasp eval`'s default difficulty 1: 14.4 mm), its yaw (uniform
//! in [-pi, pi)) and the raw-sensor model's seed; the cameras' noise and the grasp
//! sampler take the trial seed itself.
//!
//! # Failures
//! A trial whose physics broke (the backend's [`SimulatedArm::physics_failure`], or a
//! [`HwError::Disconnected`](crate::hardware::HwError::Disconnected) of the physics) is a
//! failed trial counted as a physics failure, as `grasp eval` counts them; any other error
//! of a trial (no grasp on the cloud, the arm cannot reach it) is a failed trial whose
//! reason is kept in [`TableAgentResult::trial_errors`]. Neither stops the table.
//!
//! # What a trial records
//! Success, lift and steps from the attempt's outcome (stage-2 policy steps; 1 for a
//! baseline's lift, as `grasp eval` counts it), the lift's height, turn, grip and object
//! in hand from the backend's [`SimulatedArm::lift_report`], the deepest contact from
//! [`SimulatedArm::deepest_contact`], and the thumb's contact at the lift from the robot's
//! CALIBRATED tactile reading (the simulator's own bit in `grasp eval`).

use super::pipeline::{Controller, PipelineConfig, PolicyRunner};
use super::session::{Session, SessionConfig, SessionError};
use super::sim_backend::{CameraConfig, SimBackendConfig};
use super::simulated::SimulatedArm;
use super::RunError;
use crate::env::curriculum::ranges;
use crate::env::grasp::EpisodeSummary;
use crate::eval::{aggregate, trial_seed, AgentResult, TrialOutcome, TrialPlan};
use crate::hardware::calibration::TactileCalibration;
use crate::hardware::log::{AttemptLog, LogError};
use crate::robot::Robot;
use crate::sim::{ObjectSpec, SimConfig};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `grasp eval`'s default difficulty, whose eq.-6 range the object offsets are drawn in.
pub const SCENE_DIFFICULTY: f64 = 1.0;

/// An agent of the table.
#[derive(Debug, Clone, PartialEq)]
pub enum TableAgent {
    /// Scripted baseline 1 (close all fingers).
    Baseline1,
    /// Scripted baseline 2 (FF, MF, RF stop at their calibrated touch).
    Baseline2,
    /// A trained policy: its checkpoint folder and its name in the table (the path as
    /// the user gave it).
    Policy {
        /// The checkpoint folder.
        dir: PathBuf,
        /// The name in the table.
        label: String,
    },
}

impl TableAgent {
    /// The agent's name in the table: `Baseline 1`, `Baseline 2` (as `grasp eval` names
    /// them) or the policy's label.
    pub fn label(&self) -> String {
        match self {
            TableAgent::Baseline1 => "Baseline 1".into(),
            TableAgent::Baseline2 => "Baseline 2".into(),
            TableAgent::Policy { label, .. } => label.clone(),
        }
    }
}

/// Settings of a table.
#[derive(Debug, Clone)]
pub struct TableConfig {
    /// Trials per object (1..=[`crate::eval::MAX_TRIALS`]).
    pub trials: usize,
    /// The seed of the scenes (`grasp --seed`).
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// The simulator.
    pub sim: SimConfig,
    /// The pipeline, fitted to the simulator ([`super::session::fit_to_simulator`]).
    pub pipeline: PipelineConfig,
    /// The backend's set-up (arm base, clearance, raw-sensor model); each trial sets the
    /// object's place and the raw model's seed.
    pub backend: SimBackendConfig,
    /// The simulated depth cameras.
    pub cameras: CameraConfig,
    /// A calibration for every trial; `None`: each trial calibrates its fingertips, as
    /// `grasp run` does without `--calibration`.
    pub calibration: Option<TactileCalibration>,
}

/// Where trial `seed`'s object lies and the seed of its raw-sensor model (see the module
/// docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrialScene {
    /// Object centre x, y on the table (m).
    pub object_xy: [f64; 2],
    /// Object yaw (rad).
    pub object_yaw: f64,
    /// Seed of the raw-sensor model.
    pub raw_seed: u64,
}

impl TrialScene {
    /// The scene of trial seed `seed`.
    pub fn draw(seed: u64) -> TrialScene {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (dp, _) = ranges(SCENE_DIFFICULTY);
        let dx = rng.random_range(-dp..=dp);
        let dy = rng.random_range(-dp..=dp);
        let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        TrialScene {
            object_xy: [dx, dy],
            object_yaw: yaw,
            raw_seed: rng.random(),
        }
    }
}

/// A trial that ended in an error other than a physics failure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialError {
    /// The object.
    pub object: String,
    /// The trial (same scene for every agent).
    pub trial: usize,
    /// The error and its causes.
    pub reason: String,
}

/// One agent's results in `grasp eval --json`'s shape (flattened: the same fields), with
/// the backend and the trials that ended in an error.
#[derive(Debug, Clone, Serialize)]
pub struct TableAgentResult {
    /// The results as `grasp eval` gives them.
    #[serde(flatten)]
    pub result: AgentResult,
    /// The backend that ran the trials (`sim`, `mujoco`).
    pub backend: String,
    /// The trials that ended in an error other than a physics failure (failed trials).
    pub trial_errors: Vec<TrialError>,
}

/// Error that stops a table before its trials (a failed trial does not).
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// A policy could not be loaded.
    #[error("loading policy {path}")]
    Policy {
        /// The checkpoint folder.
        path: PathBuf,
        /// Why.
        #[source]
        source: RunError,
    },
    /// A setting is out of range.
    #[error("invalid {field}: {detail}")]
    Config {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        detail: String,
    },
    /// The attempt logs could not be written.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The worker pool could not be built.
    #[error("worker pool: {0}")]
    Pool(String),
}

/// One trial's result.
struct TrialResult {
    summary: EpisodeSummary,
    error: Option<String>,
}

/// Runs the table: every agent of `agents` on `cfg.trials` trials of every object of
/// `objects` (name, simulator description), each trial a [`Session`] on a fresh backend
/// `A`, over `cfg.threads` workers (one (agent, object) pair at a time each).
/// `on_trial` is called as each trial ends (a progress bar). With `log`, every attempt's
/// log lines are appended to that JSON-lines file, agent by agent, object by object,
/// trial by trial; without, none is written. The same `cfg` gives the same results (wall
/// times aside). Once `stop` is set (a signal) no trial starts: the trials in progress
/// finish, and each agent's result holds the finished ones, marked `interrupted`
/// ([`crate::eval::aggregate`]).
pub fn run_table<A: SimulatedArm>(
    robot: &Robot,
    objects: &[(String, ObjectSpec)],
    agents: &[TableAgent],
    cfg: &TableConfig,
    log: Option<&Path>,
    on_trial: &(dyn Fn() + Sync),
    stop: Option<&std::sync::atomic::AtomicBool>,
) -> Result<Vec<TableAgentResult>, TableError> {
    let stopped = || crate::util::signal::is_set(stop);
    if cfg.trials == 0 || cfg.trials > crate::eval::MAX_TRIALS {
        return Err(TableError::Config {
            field: "trials",
            detail: format!("{} must be in 1..={}", cfg.trials, crate::eval::MAX_TRIALS),
        });
    }
    // Every checkpoint loads once, before any trial runs; each job acts through a runner
    // of its own (its recurrent state) on the shared network.
    let trained = agents
        .iter()
        .map(|a| match a {
            TableAgent::Policy { dir, .. } => {
                PolicyRunner::load_agent(dir)
                    .map(Some)
                    .map_err(|source| TableError::Policy {
                        path: dir.clone(),
                        source,
                    })
            }
            _ => Ok(None),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let logs = tempfile::tempdir().map_err(|e| {
        TableError::Log(LogError::Io {
            path: std::env::temp_dir(),
            source: e,
        })
    })?;
    let log_path = |a: usize, o: usize, t: usize| logs.path().join(format!("{a}_{o}_{t}.jsonl"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(cfg.threads.max(1))
        .build()
        .map_err(|e| TableError::Pool(e.to_string()))?;
    let jobs: Vec<(usize, usize)> = (0..agents.len())
        .flat_map(|a| (0..objects.len()).map(move |o| (a, o)))
        .collect();
    let start = std::time::Instant::now();
    let done: Vec<Vec<TrialResult>> = pool.install(|| {
        jobs.par_iter()
            .map(|&(a, o)| -> Result<Vec<TrialResult>, TableError> {
                let mut runner = trained[a].as_ref().map(PolicyRunner::new);
                let mut out = Vec::with_capacity(cfg.trials);
                for t in 0..cfg.trials {
                    if stopped() {
                        break;
                    }
                    let mut controller = controller(&agents[a], runner.as_mut());
                    let mut file = AttemptLog::open(&log_path(a, o, t))?;
                    out.push(run_trial::<A>(
                        robot,
                        &objects[o],
                        t,
                        cfg,
                        &mut controller,
                        &mut file,
                    ));
                    on_trial();
                }
                Ok(out)
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    let wall_s = start.elapsed().as_secs_f64();
    if let Some(path) = log {
        let mut all = AttemptLog::open(path)?;
        for &(a, o) in &jobs {
            for t in 0..cfg.trials {
                let p = log_path(a, o, t);
                if p.is_file() {
                    for record in crate::hardware::log::read_log(&p)? {
                        all.append(&record)?;
                    }
                }
            }
        }
        all.sync()?;
    }
    let names: Vec<String> = objects.iter().map(|o| o.0.clone()).collect();
    let plan = TrialPlan::once(cfg.trials, cfg.seed);
    let mut done = done.into_iter();
    let mut results = Vec::with_capacity(agents.len());
    for agent in agents {
        let mut per_object = Vec::with_capacity(objects.len());
        let mut trial_errors = Vec::new();
        for name in &names {
            let trials = done.next().unwrap_or_default();
            for (t, r) in trials.iter().enumerate() {
                if let Some(reason) = &r.error {
                    trial_errors.push(TrialError {
                        object: name.clone(),
                        trial: t,
                        reason: reason.clone(),
                    });
                }
            }
            per_object.push(
                trials
                    .into_iter()
                    .map(|r| TrialOutcome {
                        summary: r.summary,
                        attempts: 1,
                        stopped: None,
                        recordings: Vec::new(),
                        record_errors: Vec::new(),
                    })
                    .collect(),
            );
        }
        // The wall time of the whole table: the agents ran side by side.
        let result = aggregate(agent.label(), &names, per_object, &plan, wall_s);
        results.push(TableAgentResult {
            result,
            backend: A::NAME.to_string(),
            trial_errors,
        });
    }
    Ok(results)
}

/// Trial `trial` of `object` with `controller`: a session on the trial's scene, judged by
/// the backend; errors become a failed trial.
/// The controller of `agent`: a scripted baseline, or the policy `runner` (loaded for a
/// policy agent).
fn controller<'a>(agent: &TableAgent, runner: Option<&'a mut PolicyRunner>) -> Controller<'a> {
    match (agent, runner) {
        (TableAgent::Baseline1, _) => Controller::Baseline {
            stop_on_touch: false,
        },
        (TableAgent::Baseline2, _) => Controller::Baseline {
            stop_on_touch: true,
        },
        (TableAgent::Policy { .. }, Some(p)) => Controller::Policy(p),
        (TableAgent::Policy { .. }, None) => {
            unreachable!("a policy agent's runner is loaded before its trials")
        }
    }
}

/// One trial's wall time and outcome ([`time_trials`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimedTrial {
    /// Wall-clock seconds of the whole trial: building the backend, calibrating, the
    /// cameras, the plan, the attempt and the lift.
    pub seconds: f64,
    /// Whether the object was held.
    pub success: bool,
}

/// Runs the trials `trials` of `agent` on `object` one after another on the calling thread
/// (as [`run_table`] runs each; logs into a temporary folder) and times each: what one
/// attempt of `grasp run` costs on one core (`grasp bench run`).
pub fn time_trials<A: SimulatedArm>(
    robot: &Robot,
    object: &(String, ObjectSpec),
    agent: &TableAgent,
    cfg: &TableConfig,
    trials: std::ops::Range<usize>,
) -> Result<Vec<TimedTrial>, TableError> {
    let mut runner = match agent {
        TableAgent::Policy { dir, .. } => {
            Some(
                PolicyRunner::load(dir).map_err(|source| TableError::Policy {
                    path: dir.clone(),
                    source,
                })?,
            )
        }
        _ => None,
    };
    let logs = tempfile::tempdir().map_err(|e| {
        TableError::Log(LogError::Io {
            path: std::env::temp_dir(),
            source: e,
        })
    })?;
    let mut out = Vec::with_capacity(trials.len());
    for t in trials {
        let mut controller = controller(agent, runner.as_mut());
        let mut log = AttemptLog::open(&logs.path().join(format!("{t}.jsonl")))?;
        let start = std::time::Instant::now();
        let r = run_trial::<A>(robot, object, t, cfg, &mut controller, &mut log);
        out.push(TimedTrial {
            seconds: start.elapsed().as_secs_f64(),
            success: r.summary.success,
        });
    }
    Ok(out)
}

fn run_trial<A: SimulatedArm>(
    robot: &Robot,
    (name, object): &(String, ObjectSpec),
    trial: usize,
    cfg: &TableConfig,
    controller: &mut Controller,
    log: &mut AttemptLog,
) -> TrialResult {
    let seed = trial_seed(cfg.seed, name, trial);
    let scene = TrialScene::draw(seed);
    let mut backend = cfg.backend.clone();
    backend.object_xy = scene.object_xy;
    backend.object_yaw = scene.object_yaw;
    backend.raw.seed = scene.raw_seed;
    let session_cfg = SessionConfig {
        pipeline: cfg.pipeline.clone(),
        backend,
        calibration: cfg.calibration,
        source: None,
        cameras: cfg.cameras.clone(),
        seed,
        attempts: 1,
    };
    let mut summary = EpisodeSummary {
        object: name.clone(),
        success: false,
        steps: 0,
        episode_return: 0.0,
        lifted: false,
        physics_failure: false,
        failure: None,
        deepest_contact: 0.0,
        deepest_contact_with: None,
        touched_in_stage1: false,
        thumb_contact_at_lift: false,
        grip_effort: 0.0,
        object_height: 0.0,
        in_hand: false,
        object_turn: 0.0,
    };
    let mut session = match Session::<A>::start(robot, object.clone(), cfg.sim.clone(), session_cfg)
    {
        Ok(s) => s,
        Err(e) => return failed(summary, &e),
    };
    let ran = session.run(robot, controller, log, |_| {});
    let arm = session.arm().backend();
    if let Some((depth, with)) = arm.deepest_contact() {
        summary.deepest_contact = depth;
        summary.deepest_contact_with = Some(with);
    }
    if arm.physics_failure().is_some() {
        summary.physics_failure = true;
        summary.failure = arm.failure_report();
    }
    let baseline = matches!(controller, Controller::Baseline { .. });
    match ran {
        Ok(out) => {
            if let Some(last) = out.attempts.last() {
                let o = &last.outcome;
                summary.success = o.success && !summary.physics_failure;
                summary.lifted = o.lifted;
                summary.steps = if baseline {
                    usize::from(o.lifted)
                } else {
                    o.policy_steps
                };
                summary.episode_return = f64::from(u8::from(summary.success));
                summary.touched_in_stage1 = o.touched;
                // The robot's calibrated thumb contact (the simulator's own tactile bit
                // in `grasp eval`).
                summary.thumb_contact_at_lift = o.lifted && o.contacts_at_lift[4];
                if let (true, Some(l)) = (o.lifted, arm.lift_report()) {
                    summary.grip_effort = l.grip_effort;
                    summary.object_height = l.object_lowest_z;
                    summary.in_hand = l.in_contact;
                    summary.object_turn = l.object_turn;
                }
            }
            TrialResult {
                summary,
                error: None,
            }
        }
        Err(e) => failed(summary, &e),
    }
}

/// A trial that ended in error `e`: a failed trial, counted as a physics failure where
/// the physics broke, else with its reason.
fn failed(mut summary: EpisodeSummary, e: &SessionError) -> TrialResult {
    summary.success = false;
    summary.physics_failure |= e.is_physics_failure();
    let error = (!summary.physics_failure).then(|| e.text());
    TrialResult { summary, error }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trial_scene_follows_its_seed() {
        let a = TrialScene::draw(3);
        assert_eq!(a, TrialScene::draw(3));
        assert_ne!(a, TrialScene::draw(4));
        let (dp, _) = ranges(SCENE_DIFFICULTY);
        assert!(a.object_xy.iter().all(|v| v.abs() <= dp));
        assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(&a.object_yaw));
    }
}
