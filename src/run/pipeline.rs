//! The grasp pipeline of Sec. V-B on any [`HandArm`], through [`SafeHandArm`].
//!
//! **Planning** ([`plan_grasp`], in [`super::plan`] and re-exported here): the grasp, the
//! hand's preshape and the arm's pre-grasp and grasp configurations.
//!
//! **Attempt** ([`run_attempt`]):
//! 1. drift compensation: `tau_j0` is the mean of `baseline_readings` tendon readings with
//!    the empty hand, still, at the start of the attempt;
//! 2. the fingers take the preshape (in steps of at most the safety limiter's maximum
//!    change, each clamp logged), the arm moves to the pre-grasp and grasp poses;
//! 3. stage 1: the closing trajectory T of the environment ([`ClosingPath`], in the
//!    policy's closing space, from the preshape to the power grasp) until any fingertip is
//!    in contact (calibrated tactile threshold);
//! 4. stage 2: the policy acts on the SAME observation as in simulation
//!    ([`ObsLayout::frame`], [`FrameStack`]) built from the mapped sensors (calibrated
//!    contacts, drift-compensated torque levels, joint angles), and its action becomes
//!    hand targets through the SAME eq.-2 mapping ([`hand_targets`], from the same anchor:
//!    measured angles or the last command sent), until it decides to lift or `max_steps`
//!    pass (then, as in the policy's environment, the attempt either fails or lifts);
//! 5. the lift; the outcome is the backend's judgement where it has one (the simulator:
//!    object held after the lift), otherwise the fingertips: held when at least
//!    `held_min_contacts` report contact after the lift.
//!
//! Every reading, action, target and clamp event is a line of the [`AttemptLog`], and the
//! attempt ends with an outcome line, also when it fails with an error.

use super::RunError;
use crate::checkpoint::TrainedAgent;
use crate::env::action::{clip_unit, component_std, hand_targets, lift_targets, ActionConfig};
use crate::env::closing::{closing_target, ClosingPath};
use crate::env::grasp::{Agent, AtMaxSteps, EnvConfig};
use crate::env::obs::{FrameStack, Modality, ObsLayout, Sensing, N_SURFACE};
use crate::eval::PolicyAgent;
use crate::hardware::calibration::TactileCalibration;
use crate::hardware::log::{AttemptLog, OutcomeRecord, StepRecord};
use crate::hardware::safety::{SafeHandArm, SafetyConfig};
use crate::hardware::torque::{TorqueMapper, REAL_THRESHOLDS};
use crate::hardware::{ArmMotion, HandArm, RawSensors};
use crate::perception::pointcloud::AntipodalConfig;
use crate::perception::pregrasp::{DEFAULT_MAX_CANDIDATES, DEFAULT_MAX_TILT_RAD};
use crate::robot::joints::{N_ACTUATORS, N_JOINTS};
use crate::robot::{ur10e, Posture, Robot};
use crate::sim::script;
use crate::synergy::SynergyModel;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use super::plan::{
    load_grasp_file, plan_grasp, plan_grasp_avoiding, GraspFile, GraspPlan, GraspSource,
};

/// Pose of the UR10e base in the world: a position and a yaw about the vertical.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArmBase {
    /// Base position (m).
    pub xyz: [f64; 3],
    /// Base yaw about world z (rad).
    pub yaw: f64,
}

impl Default for ArmBase {
    /// The base 0.7 m from the object along world -y, on the table plane.
    fn default() -> Self {
        ArmBase {
            xyz: [0.0, -0.7, 0.0],
            yaw: 0.0,
        }
    }
}

impl ArmBase {
    /// The world-from-base transform.
    pub fn pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.xyz[0], self.xyz[1], self.xyz[2]),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.yaw),
        )
    }
}

/// Settings of the pipeline (the closing trajectory, history, step limit and action
/// scales come from the policy's environment config, see [`PolicyRunner`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineConfig {
    /// The UR10e base in the world frame of grasps and clouds.
    pub arm_base: ArmBase,
    /// Finger preshape before the approach: `policy` (the start posture of the policy's
    /// training environment; stage 1 then starts where it started in training), `c-shape`
    /// (the paper's preshape) or `open`.
    pub preshape: String,
    /// Distance of the pre-grasp pose behind the grasp pose, along the approach (m).
    pub pregrasp_offset_m: f64,
    /// Keep only (nearly) top-down cloud candidates and make them exactly top-down: for a
    /// backend that places the hand palm down only (the simulator).
    pub top_down_only: bool,
    /// Largest tilt of a candidate's approach from straight down kept by
    /// `top_down_only` (rad).
    pub max_tilt_rad: f64,
    /// Most cloud candidates tried (best score first) before giving up.
    pub max_candidates: usize,
    /// Empty-hand tendon readings averaged into `tau_j0`.
    pub baseline_readings: usize,
    /// Time between two baseline readings (s).
    pub baseline_period_s: f64,
    /// Duration of one policy action (s); the simulator's `control_period`.
    pub control_period_s: f64,
    /// Lift height (m).
    pub lift_height_m: f64,
    /// Lift duration (s).
    pub lift_duration_s: f64,
    /// Thresholds of the tendon levels (the paper's real-robot values by default).
    pub torque_thresholds: [f64; 5],
    /// Fingertips in contact after the lift for a sensor-judged success.
    pub held_min_contacts: usize,
    /// Most commands used to reach the preshape.
    pub preshape_commands: usize,
    /// The safety layer.
    pub safety: SafetyConfig,
    /// The antipodal sampler for clouds.
    pub antipodal: AntipodalConfig,
}

impl Default for PipelineConfig {
    fn default() -> Self {
        PipelineConfig {
            arm_base: ArmBase::default(),
            preshape: "policy".into(),
            pregrasp_offset_m: 0.10,
            top_down_only: false,
            max_tilt_rad: DEFAULT_MAX_TILT_RAD,
            max_candidates: DEFAULT_MAX_CANDIDATES,
            baseline_readings: crate::hardware::torque::DEFAULT_BASELINE_READINGS,
            baseline_period_s: 0.02,
            control_period_s: 0.2,
            lift_height_m: 0.15,
            lift_duration_s: 2.0,
            torque_thresholds: REAL_THRESHOLDS,
            held_min_contacts: 2,
            preshape_commands: 12,
            safety: SafetyConfig::default(),
            antipodal: AntipodalConfig::default(),
        }
    }
}

impl PipelineConfig {
    /// The preshape posture for a policy trained in `env`: `policy` (the default) is the
    /// start posture the policy was trained from (its stage 1 starts there, as in
    /// training), `c-shape` the paper's preshape, `open` the open hand. Errors on an
    /// unknown name.
    pub fn preshape_angles(&self, env: &EnvConfig) -> Result<[f64; 24], RunError> {
        match self.preshape.as_str() {
            "policy" => env
                .validate()
                .map(|p| p.angles())
                .map_err(|e| RunError::Config {
                    field: "preshape".into(),
                    detail: format!("the policy's start posture: {e}"),
                }),
            "c-shape" => Ok(Posture::CShape.angles()),
            "open" => Ok(Posture::Open.angles()),
            other => Err(RunError::Config {
                field: "preshape".into(),
                detail: format!("unknown posture '{other}': expected policy, c-shape or open"),
            }),
        }
    }

    /// Checks every range; the error names the field.
    pub fn validate(&self) -> Result<(), RunError> {
        let bad = |field: &str, detail: String| {
            Err(RunError::Config {
                field: field.into(),
                detail,
            })
        };
        self.preshape_angles(&EnvConfig::default())?;
        if !(self.arm_base.xyz.iter().all(|v| v.is_finite()) && self.arm_base.yaw.is_finite()) {
            return bad("arm_base", "must be finite".into());
        }
        for (name, v) in [
            ("pregrasp_offset_m", self.pregrasp_offset_m),
            ("max_tilt_rad", self.max_tilt_rad),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, format!("{v} must be finite and >= 0"));
            }
        }
        // Each bounded too: a wait of 1e300 s would be refused only after the arm had
        // moved (the backend's waits are at most a day), a lift of kilometres sent.
        for (name, v, max) in [
            ("baseline_period_s", self.baseline_period_s, 60.0),
            ("control_period_s", self.control_period_s, 60.0),
            ("lift_height_m", self.lift_height_m, 1.0),
            ("lift_duration_s", self.lift_duration_s, 600.0),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return bad(
                    name,
                    format!("{} must be in (0, {max}]", crate::util::num::short(v)),
                );
            }
        }
        if self.pregrasp_offset_m > 1.0 {
            return bad(
                "pregrasp_offset_m",
                format!(
                    "{} must be at most 1 m",
                    crate::util::num::short(self.pregrasp_offset_m)
                ),
            );
        }
        if self.max_candidates == 0 || self.baseline_readings == 0 || self.preshape_commands == 0 {
            return bad(
                "max_candidates/baseline_readings/preshape_commands",
                "must be at least 1".into(),
            );
        }
        if self.held_min_contacts == 0 || self.held_min_contacts > 5 {
            return bad(
                "held_min_contacts",
                format!("{} is outside 1..=5", self.held_min_contacts),
            );
        }
        TorqueMapper::new(self.torque_thresholds)?;
        Ok(())
    }
}

/// M3G's surface vectors on the robot: for each distal phalanx and the palm
/// ([`Robot::surface_points_palm`] at hand angles `q`), the vector to the nearest point of
/// the object's `cloud` (world frame), in the palm frame. `root` is the hand root's
/// (forearm's, the flange's) world pose.
pub fn cloud_surface_vectors(
    robot: &Robot,
    root: &Isometry3<f64>,
    q: &[f64; N_JOINTS],
    cloud: &[Point3<f64>],
) -> [f64; N_SURFACE] {
    let palm = root * robot.hand_fk_palm(q)[robot.hand.forearm].inverse();
    let to_palm = palm.rotation.inverse();
    let mut out = [0.0; N_SURFACE];
    for (k, p) in robot.surface_points_palm(q).iter().enumerate() {
        let w = palm * p;
        let nearest = cloud
            .iter()
            .min_by(|a, b| (*a - w).norm_squared().total_cmp(&(*b - w).norm_squared()));
        if let Some(n) = nearest {
            let v = to_palm * (n - w);
            out[3 * k..3 * k + 3].copy_from_slice(v.as_slice());
        }
    }
    out
}

/// A trained policy with everything needed to act on a robot exactly as in its
/// environment: the network and its observation normaliser, the synergy model, the
/// environment config (history, modality, closing trajectory, action scales) and the
/// observation layout.
pub struct PolicyRunner {
    agent: PolicyAgent,
    synergy: SynergyModel,
    eps_std: Vec<f64>,
    env: EnvConfig,
    layout: ObsLayout,
    dir: PathBuf,
    /// The object's points (world frame, m) an M3G policy measures its surface vectors
    /// against; the object is assumed still during the grasp.
    cloud: Option<Vec<Point3<f64>>>,
}

impl PolicyRunner {
    /// Gives the policy the object's point cloud (world frame, m): an M3G policy's surface
    /// vectors are measured to its nearest points. Other modalities ignore it.
    pub fn set_object_cloud(&mut self, cloud: Option<Vec<Point3<f64>>>) {
        self.cloud = cloud;
    }

    /// Loads the checkpoint folder `dir` ([`TrainedAgent::load`]: `checkpoint.safetensors`,
    /// and beside it the `config.toml` of its training run and its `synergy.json`;
    /// without them the environment defaults and the shipped synergy model are used).
    /// The policy acts deterministically (the mode of its distribution).
    pub fn load(dir: &Path) -> Result<PolicyRunner, RunError> {
        Ok(PolicyRunner::new(&Self::load_agent(dir)?))
    }

    /// The trained agent of checkpoint folder `dir` ([`TrainedAgent::load`]), loaded once
    /// for any number of runners ([`PolicyRunner::new`]); a warning where it acts in the
    /// shipped synergy model for want of its own.
    pub fn load_agent(dir: &Path) -> Result<TrainedAgent, RunError> {
        let trained = TrainedAgent::load(dir).map_err(|e| RunError::Policy {
            path: dir.to_path_buf(),
            detail: e.message,
        })?;
        if !trained.has_synergy_file() {
            tracing::warn!(
                "checkpoint {} has no synergy.json: its policy acts in the shipped synergy model",
                dir.display()
            );
        }
        Ok(trained)
    }

    /// The runner of a loaded agent, acting deterministically.
    pub fn new(trained: &TrainedAgent) -> PolicyRunner {
        let synergy = trained.synergy().clone();
        PolicyRunner {
            agent: PolicyAgent::new(trained.network().clone(), false, 0),
            eps_std: component_std(&synergy),
            layout: trained.env.layout(synergy.n_components()),
            synergy,
            env: trained.env.clone(),
            dir: trained.dir().to_path_buf(),
            cloud: None,
        }
    }

    /// The environment config the policy was trained in.
    pub fn env_config(&self) -> &EnvConfig {
        &self.env
    }

    /// The observation layout.
    pub fn layout(&self) -> &ObsLayout {
        &self.layout
    }

    /// The checkpoint folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// How an attempt ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AttemptOutcome {
    /// The object was held after the lift.
    pub success: bool,
    /// Why the attempt ended.
    pub reason: String,
    /// Who judged: `simulator` or `tactile sensors`.
    pub judged_by: String,
    /// Stage-1 target updates until the first touch (or the end of T).
    pub stage1_updates: usize,
    /// Stage 1 ended on a fingertip contact.
    pub touched: bool,
    /// Policy steps (the lift decision included).
    pub policy_steps: usize,
    /// The policy decided to lift.
    pub lifted: bool,
    /// Hand commands the safety limiter changed.
    pub clamped_commands: usize,
    /// Lines written to the attempt log.
    pub log_lines: u64,
    /// Backend time at the end (s).
    pub time_s: f64,
    /// The calibrated fingertip contacts (FF, MF, RF, LF, TH) of the last reading before
    /// the lift (all off where the attempt did not lift); not in the JSON report.
    #[serde(skip)]
    pub contacts_at_lift: [bool; 5],
}

/// The mapped view of one reading.
struct Mapped {
    raw: RawSensors,
    tactile: [bool; 5],
    torque_mapped: [f64; N_ACTUATORS],
    levels: [u8; N_ACTUATORS],
}

struct Attempt<'a, B: HandArm> {
    arm: &'a mut SafeHandArm<B>,
    calibration: &'a TactileCalibration,
    mapper: TorqueMapper,
    log: &'a mut AttemptLog,
    step: u64,
    clamped: usize,
    last_sent: [f64; N_JOINTS],
}

impl<B: HandArm> Attempt<'_, B> {
    fn read(&mut self) -> Result<Mapped, RunError> {
        let raw = self.arm.read()?;
        Ok(Mapped {
            tactile: self.calibration.contacts(&raw.tactile_raw),
            torque_mapped: self.mapper.mapped(&raw.tendon_raw)?,
            levels: self.mapper.levels(&raw.tendon_raw)?,
            raw,
        })
    }

    /// Sends `targets` through the safety layer, lets `wait_s` pass, reads and logs.
    fn command(
        &mut self,
        targets: &[f64; N_JOINTS],
        action: Vec<f64>,
        wait_s: f64,
    ) -> Result<Mapped, RunError> {
        self.arm.command_hand(targets)?;
        let events = self.arm.last_clamp_events().to_vec();
        let sent = applied(targets, &events);
        if !events.is_empty() {
            self.clamped += 1;
        }
        self.last_sent = sent;
        self.arm.wait(wait_s)?;
        let m = self.read()?;
        self.log_step(&m, action, sent, events)?;
        Ok(m)
    }

    /// The step that decides the lift: logged with the targets the lift holds, which are
    /// the last ones sent, or those squeezed towards the power grasp where
    /// `action.lift_squeeze` asks ([`lift_targets`]; sent at once, as the environment
    /// does before its lift).
    fn lift_command(
        &mut self,
        m: &Mapped,
        action: Vec<f64>,
        cfg: &ActionConfig,
        finger_limits: &[(f64, f64); 22],
    ) -> Result<(), RunError> {
        if cfg.lift_squeeze > 0.0 {
            let held = lift_targets(cfg, &self.last_sent, &script::power_grasp(), finger_limits);
            self.command(&held, action, 0.0)?;
        } else {
            let hold = self.last_sent;
            self.log_step(m, action, hold, Vec::new())?;
        }
        Ok(())
    }

    fn log_step(
        &mut self,
        m: &Mapped,
        action: Vec<f64>,
        targets: [f64; N_JOINTS],
        clamp_events: Vec<crate::hardware::safety::ClampEvent>,
    ) -> Result<(), RunError> {
        self.log.step(StepRecord {
            step: self.step,
            time_s: m.raw.stamp,
            joint_angles: m.raw.joint_angles,
            tactile_raw: m.raw.tactile_raw,
            tendon_raw: m.raw.tendon_raw,
            tactile: m.tactile,
            torque_mapped: m.torque_mapped,
            torque_levels: m.levels,
            action,
            targets,
            clamp_events,
        })?;
        self.step += 1;
        Ok(())
    }
}

/// The targets actually sent: the requested ones with the clamp events applied.
fn applied(
    targets: &[f64; N_JOINTS],
    events: &[crate::hardware::safety::ClampEvent],
) -> [f64; N_JOINTS] {
    let mut out = *targets;
    for e in events {
        if let Some(k) = crate::robot::joints::hand_index(&e.joint) {
            out[k] = e.applied;
        }
    }
    out
}

/// Who closes the hand and decides the lift in an attempt ([`run_attempt_with`]).
pub enum Controller<'a> {
    /// Stage 1 (the policy's closing trajectory T until a calibrated touch), then the
    /// trained policy until it lifts.
    Policy(&'a mut PolicyRunner),
    /// A scripted baseline of Sec. V-D in place of stage 1 and the policy, as
    /// [`GraspEnv::run_baseline`](crate::env::grasp::GraspEnv::run_baseline) runs it:
    /// every joint follows the joint-space closing trajectory
    /// ([`closing_target`]) from the plan's preshape towards the power grasp for
    /// `closing_time / closing_period` periods of [`EnvConfig::default`], then holds for
    /// a 0.3 s settle, and the arm lifts. Baseline 2 (`stop_on_touch`) freezes FF, MF and
    /// RF (joints 2..6, 6..10, 10..14) once their fingertip reports contact: the
    /// robot's CALIBRATED tactile contact, not the simulator's.
    Baseline {
        /// Baseline 2 (`true`) or baseline 1 (`false`).
        stop_on_touch: bool,
    },
}

impl Controller<'_> {
    /// The environment whose start posture, closing trajectory and step limit the
    /// controller acts in: the policy's training environment, the defaults for the
    /// baselines (whose start posture `grasp eval` also takes from them).
    pub fn env_config(&self) -> EnvConfig {
        match self {
            Controller::Policy(p) => p.env.clone(),
            Controller::Baseline { .. } => EnvConfig::default(),
        }
    }

    /// The preshape the plan gives the hand for this controller
    /// ([`PipelineConfig::preshape_angles`] of [`Controller::env_config`]).
    pub fn preshape(&self, cfg: &PipelineConfig) -> Result<[f64; N_JOINTS], RunError> {
        cfg.preshape_angles(&self.env_config())
    }
}

/// The finger joints baseline 2 freezes at a touch: FF, MF, RF (paper order).
pub const BASELINE_FROZEN_FINGERS: [std::ops::Range<usize>; 3] = [2..6, 6..10, 10..14];

/// Settle of the baselines after the closing trajectory, before the lift (s).
pub const BASELINE_SETTLE_S: f64 = 0.3;

/// Runs one grasp attempt of `plan` with `policy` on `arm` (see the module docs), logging
/// every step to `log`. On an error the outcome line records it before it is returned.
pub fn run_attempt<B: HandArm>(
    arm: &mut SafeHandArm<B>,
    robot: &Robot,
    plan: &GraspPlan,
    policy: &mut PolicyRunner,
    calibration: &TactileCalibration,
    cfg: &PipelineConfig,
    log: &mut AttemptLog,
) -> Result<AttemptOutcome, RunError> {
    let mut c = Controller::Policy(policy);
    run_attempt_with(arm, robot, plan, &mut c, calibration, cfg, log)
}

/// [`run_attempt`] with any [`Controller`]: the policy, or a scripted baseline in place of
/// stage 1 and the policy (the tendon baseline, preshape, approach, lift and judgement are
/// the same, every step logged alike).
pub fn run_attempt_with<B: HandArm>(
    arm: &mut SafeHandArm<B>,
    robot: &Robot,
    plan: &GraspPlan,
    controller: &mut Controller,
    calibration: &TactileCalibration,
    cfg: &PipelineConfig,
    log: &mut AttemptLog,
) -> Result<AttemptOutcome, RunError> {
    cfg.validate()?;
    calibration.validate()?;
    let mut at = Attempt {
        arm,
        calibration,
        mapper: TorqueMapper::new(cfg.torque_thresholds)?,
        log,
        step: 0,
        clamped: 0,
        last_sent: [0.0; N_JOINTS],
    };
    match attempt_body(&mut at, robot, plan, controller, cfg) {
        Ok(mut out) => {
            out.time_s = at.arm.now();
            at.log.outcome(OutcomeRecord {
                time_s: out.time_s,
                steps: out.policy_steps as u64,
                success: out.success,
                reason: out.reason.clone(),
            })?;
            out.clamped_commands = at.clamped;
            out.log_lines = at.log.lines_written();
            Ok(out)
        }
        Err(e) => {
            let _ = at.log.outcome(OutcomeRecord {
                time_s: at.arm.now(),
                steps: at.step,
                success: false,
                reason: format!("error: {e}"),
            });
            Err(e)
        }
    }
}

fn attempt_body<B: HandArm>(
    at: &mut Attempt<'_, B>,
    robot: &Robot,
    plan: &GraspPlan,
    controller: &mut Controller,
    cfg: &PipelineConfig,
) -> Result<AttemptOutcome, RunError> {
    let policy = match controller {
        Controller::Policy(p) => p,
        Controller::Baseline { stop_on_touch } => {
            return baseline_attempt(at, plan, *stop_on_touch, cfg);
        }
    };
    let env = policy.env.clone();
    if env.modality == Modality::M3G && policy.cloud.is_none() {
        return Err(RunError::Policy {
            path: policy.dir.clone(),
            detail: "modality M3G measures the object's surface in its point cloud: give \
                     --cloud FILE (or let the sim backend's cameras capture one) instead of a \
                     grasp without a cloud"
                .into(),
        });
    }
    // 1. tau_j0 with the empty, still hand.
    tendon_baseline(at, cfg)?;
    // 2. Preshape, pre-grasp, grasp.
    place_hand(at, plan, cfg)?;
    // 3. Stage 1: the closing trajectory T until a fingertip touches.
    let finger_limits = robot.finger_limits();
    let path = ClosingPath::new(
        env.closing,
        &plan.preshape,
        &script::power_grasp(),
        &policy.synergy,
        &finger_limits,
    );
    let (m, touched, updates) = stage1(at, &env, &path)?;
    // 4. Stage 2: the policy.
    let (m, steps, mut lifted) = stage2(at, robot, plan, policy, cfg, m)?;
    let base_out = AttemptOutcome {
        success: false,
        reason: String::new(),
        judged_by: String::new(),
        stage1_updates: updates,
        touched,
        policy_steps: steps,
        lifted,
        clamped_commands: 0,
        log_lines: 0,
        time_s: 0.0,
        contacts_at_lift: [false; 5],
    };
    if !lifted && env.at_max_steps == AtMaxSteps::Lift {
        // The policy was trained to lift at the step cap.
        lifted = true;
        at.lift_command(&m, Vec::new(), &env.action, &finger_limits)?;
    }
    if !lifted {
        return Ok(AttemptOutcome {
            reason: format!(
                "the policy did not decide to lift within {} steps",
                env.max_steps
            ),
            judged_by: "pipeline".into(),
            ..base_out
        });
    }
    // 5. Lift and judge.
    let (success, reason, judged_by) = lift_and_judge(at, cfg)?;
    Ok(AttemptOutcome {
        success,
        reason,
        judged_by: judged_by.into(),
        contacts_at_lift: m.tactile,
        ..base_out
    })
}

/// A scripted baseline's attempt ([`Controller::Baseline`]): the tendon baseline, the
/// preshape and approach of the policy's attempt, the joint-space closing with its settle
/// (FF, MF, RF frozen at their calibrated touch for baseline 2), the lift and the
/// judgement.
fn baseline_attempt<B: HandArm>(
    at: &mut Attempt<'_, B>,
    plan: &GraspPlan,
    stop_on_touch: bool,
    cfg: &PipelineConfig,
) -> Result<AttemptOutcome, RunError> {
    let env = EnvConfig::default();
    tendon_baseline(at, cfg)?;
    place_hand(at, plan, cfg)?;
    let (m, touched, updates) = baseline_close(at, &env, &plan.preshape, stop_on_touch)?;
    // The lift decision, logged with the targets the lift holds (no squeeze: the
    // environment's baselines lift as they closed).
    let hold = at.last_sent;
    at.log_step(&m, Vec::new(), hold, Vec::new())?;
    let (success, reason, judged_by) = lift_and_judge(at, cfg)?;
    Ok(AttemptOutcome {
        success,
        reason,
        judged_by: judged_by.into(),
        stage1_updates: updates,
        touched,
        policy_steps: 0,
        lifted: true,
        clamped_commands: 0,
        log_lines: 0,
        time_s: 0.0,
        contacts_at_lift: m.tactile,
    })
}

/// The baselines' closing: `n = closing_time / closing_period` target updates along the
/// joint-space trajectory from `start` to the power grasp and a 0.3 s settle at the power
/// grasp, one closing period each; with `stop_on_touch` the joints of FF, MF and RF keep
/// their last target once the finger's calibrated tactile contact is on. Returns the last
/// reading, whether any fingertip touched and the updates sent.
fn baseline_close<B: HandArm>(
    at: &mut Attempt<'_, B>,
    env: &EnvConfig,
    start: &[f64; N_JOINTS],
    stop_on_touch: bool,
) -> Result<(Mapped, bool, usize), RunError> {
    let n = (env.closing_time / env.closing_period).round().max(1.0) as usize;
    let settle = (BASELINE_SETTLE_S / env.closing_period).round() as usize;
    let closed = script::power_grasp();
    let mut frozen = [false; 3];
    let mut targets = *start;
    let mut touched = false;
    let mut m = at.read()?;
    for i in 1..=n + settle {
        for (j, t) in targets.iter_mut().enumerate() {
            let f = BASELINE_FROZEN_FINGERS.iter().position(|r| r.contains(&j));
            if f.is_some_and(|f| frozen[f]) {
                continue;
            }
            *t = closing_target(start, &closed, j, i, n);
        }
        m = at.command(&targets, Vec::new(), env.closing_period)?;
        touched |= m.tactile.contains(&true);
        if stop_on_touch {
            for (f, z) in frozen.iter_mut().enumerate() {
                *z |= m.tactile[f];
            }
        }
    }
    Ok((m, touched, n + settle))
}

/// Reads the empty, still hand's tendons `baseline_readings` times: tau_j0.
fn tendon_baseline<B: HandArm>(
    at: &mut Attempt<'_, B>,
    cfg: &PipelineConfig,
) -> Result<(), RunError> {
    let mut base = Vec::with_capacity(cfg.baseline_readings);
    for k in 0..cfg.baseline_readings {
        if k > 0 {
            at.arm.wait(cfg.baseline_period_s)?;
        }
        base.push(at.arm.read()?.tendon_raw);
    }
    at.mapper.set_baseline(base)?;
    Ok(())
}

/// Preshapes the hand (until within 0.05 rad), then moves the arm to the pre-grasp and the
/// grasp pose.
fn place_hand<B: HandArm>(
    at: &mut Attempt<'_, B>,
    plan: &GraspPlan,
    cfg: &PipelineConfig,
) -> Result<(), RunError> {
    let mut m = at.read()?;
    at.last_sent = m.raw.joint_angles;
    for _ in 0..cfg.preshape_commands {
        let far = m
            .raw
            .joint_angles
            .iter()
            .zip(&plan.preshape)
            .any(|(q, t)| (q - t).abs() > 0.05);
        if !far {
            break;
        }
        m = at.command(&plan.preshape, Vec::new(), cfg.control_period_s)?;
    }
    at.arm.move_arm(&ArmMotion::Joints(plan.pregrasp_q))?;
    at.arm.move_arm(&ArmMotion::Joints(plan.grasp_q))?;
    Ok(())
}

/// Stage 1: follows the closing trajectory until a fingertip touches; the last reading,
/// whether a touch ended it and the target updates sent.
fn stage1<B: HandArm>(
    at: &mut Attempt<'_, B>,
    env: &EnvConfig,
    path: &ClosingPath,
) -> Result<(Mapped, bool, usize), RunError> {
    let n = (env.closing_time / env.closing_period).round().max(1.0) as usize;
    let mut touched = false;
    let mut updates = 0;
    let mut m = at.read()?;
    for i in 1..=n {
        let t = path.target(i, n);
        m = at.command(&t, Vec::new(), env.closing_period)?;
        updates = i;
        if m.tactile.contains(&true) {
            touched = true;
            break;
        }
    }
    Ok((m, touched, updates))
}

/// Stage 2: the policy acts from reading `m` until it lifts or reaches the step cap; the
/// last reading, the steps and whether it decided to lift.
fn stage2<B: HandArm>(
    at: &mut Attempt<'_, B>,
    robot: &Robot,
    plan: &GraspPlan,
    policy: &mut PolicyRunner,
    cfg: &PipelineConfig,
    mut m: Mapped,
) -> Result<(Mapped, usize, bool), RunError> {
    let env = policy.env.clone();
    let finger_limits = robot.finger_limits();
    let hl = robot.hand_limits();
    let wrist_limits = [hl[0], hl[1]];
    let n_cont = env.action.continuous(policy.synergy.n_components());
    let closed = script::power_grasp();
    let mut stack = FrameStack::new(&policy.layout);
    policy.agent.reset();
    // M3G's surface vectors from the object's cloud, the arm still at the grasp pose.
    let root = cfg.arm_base.pose() * ur10e::fk(&plan.grasp_q);
    let cloud = match env.modality {
        Modality::M3G => policy.cloud.clone(),
        _ => None,
    };
    // What the hand senses, from the calibrated sensors (the simulator's counterpart is
    // in env::grasp).
    let sensed = |m: &Mapped| Sensing {
        tactile: m.tactile,
        torque_levels: m.levels,
        joint_angles: m.raw.joint_angles,
        surface: match &cloud {
            Some(c) => cloud_surface_vectors(robot, &root, &m.raw.joint_angles, c),
            None => [0.0; N_SURFACE],
        },
    };
    stack.push(policy.layout.frame(&vec![0.0; n_cont], &sensed(&m)));
    let mut steps = 0;
    let mut lifted = false;
    while steps < env.max_steps {
        let mut obs = stack.stacked();
        obs.resize(policy.layout.len(), 0.0);
        let a = policy.agent.act(&obs);
        steps += 1;
        let mut logged: Vec<f64> = a.cont.iter().map(|&x| f64::from(x)).collect();
        logged.push(if a.lift { 1.0 } else { 0.0 });
        if a.lift {
            lifted = true;
            at.lift_command(&m, logged, &env.action, &finger_limits)?;
            break;
        }
        let targets = hand_targets(
            &env.action,
            &policy.eps_std,
            &policy.synergy,
            &finger_limits,
            &wrist_limits,
            env.action.anchor.pick(&m.raw.joint_angles, &at.last_sent),
            &closed,
            &a.cont,
            steps,
        );
        m = at.command(&targets, logged, cfg.control_period_s)?;
        let prev: Vec<f32> = a.cont.iter().map(|&x| clip_unit(x) as f32).collect();
        stack.push(policy.layout.frame(&prev, &sensed(&m)));
    }
    Ok((m, steps, lifted))
}

/// Lifts the arm and judges the grasp: the simulator's verdict where the backend has one,
/// else at least `held_min_contacts` fingertips in contact.
fn lift_and_judge<B: HandArm>(
    at: &mut Attempt<'_, B>,
    cfg: &PipelineConfig,
) -> Result<(bool, String, &'static str), RunError> {
    at.arm.move_arm(&ArmMotion::Lift {
        height_m: cfg.lift_height_m,
        duration_s: cfg.lift_duration_s,
    })?;
    let after = at.read()?;
    let contacts = after.tactile.iter().filter(|&&c| c).count();
    let (success, judged_by) = match at.arm.lift_outcome() {
        Some(s) => (s, "simulator"),
        None => (contacts >= cfg.held_min_contacts, "tactile sensors"),
    };
    let reason = if success && contacts == 0 {
        // Held, yet no fingertip says so: the calibration's ranges do not fit the sensors.
        "held after the lift, but no fingertip sensor reports contact: the tactile \
         calibration does not fit the sensors (recalibrate)"
            .to_string()
    } else if success {
        format!("held after the lift ({contacts} fingertips in contact)")
    } else {
        format!("not held after the lift ({contacts} fingertips in contact)")
    };
    Ok((success, reason, judged_by))
}

#[cfg(test)]
mod tests;
