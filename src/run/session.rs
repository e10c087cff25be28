//! `grasp run` on a simulated backend, written once for every [`SimulatedArm`]: the hand
//! built around the object, its fingertips calibrated (unless a calibration is given),
//! the cameras' cloud (unless a grasp or cloud is given), then attempts until one lifts
//! the object: after a failed lift the object settles where the attempt left it, the
//! cameras look again and the next best grasp not tried yet is planned (as
//! `grasp eval --attempts`).
//!
//! [`Session::start`] sets the hand up, [`Session::run`] makes the attempts (with any
//! [`Controller`]: the policy or a scripted baseline), reporting each one as it ends.

use super::calibrate::calibrate_simulated;
use super::pipeline::{
    plan_grasp_avoiding, run_attempt_with, AttemptOutcome, Controller, GraspPlan, GraspSource,
    PipelineConfig,
};
use super::sim_backend::{CameraConfig, SimBackendConfig};
use super::simulated::SimulatedArm;
use super::RunError;
use crate::hardware::calibration::{TactileCalibration, DEFAULT_THRESHOLD_FRACTION};
use crate::hardware::log::AttemptLog;
use crate::hardware::safety::SafeHandArm;
use crate::hardware::HwError;
use crate::perception::pointcloud::CloudError;
use crate::robot::Robot;
use crate::sim::{ObjectSpec, SimConfig};
use nalgebra::Point3;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Still readings of the session's calibration.
pub const CALIBRATION_STILL_READINGS: usize = 10;
/// The known force of a calibration press (N).
pub const CALIBRATION_PRESS_N: f64 = 10.0;
/// Readings per pressed fingertip.
pub const CALIBRATION_PRESSES: usize = 5;

/// Error of a session; each stage's error says which stage failed, its cause follows.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The backend could not be built around the object.
    #[error("building the simulated robot")]
    Build(#[source] HwError),
    /// The fingertips could not be calibrated.
    #[error("calibrating the simulated fingertips")]
    Calibrate(#[source] RunError),
    /// The simulated depth cameras gave no usable cloud.
    #[error("simulating the depth cameras")]
    Cameras(#[source] CloudError),
    /// No grasp could be planned.
    #[error("planning the grasp")]
    Plan(#[source] RunError),
    /// The attempt failed with an error (its log's outcome line records it).
    #[error("grasp attempt failed")]
    Attempt(#[source] RunError),
    /// Anything else of the set-up (the safety layer's config, the preshape).
    #[error(transparent)]
    Run(#[from] RunError),
}

impl SessionError {
    /// Whether the simulated physics broke (a [`HwError::Disconnected`] of the backend):
    /// such a trial counts as a physics failure, as in `grasp eval`.
    pub fn is_physics_failure(&self) -> bool {
        let hw = match self {
            SessionError::Build(e) => Some(e),
            SessionError::Calibrate(RunError::Hw(e))
            | SessionError::Attempt(RunError::Hw(e))
            | SessionError::Plan(RunError::Hw(e))
            | SessionError::Run(RunError::Hw(e)) => Some(e),
            _ => None,
        };
        matches!(hw, Some(HwError::Disconnected(_)))
    }

    /// The error and its causes joined by ": ", as the command line prints it.
    pub fn text(&self) -> String {
        let mut out = self.to_string();
        let mut prev = out.clone();
        let mut cur: Option<&dyn std::error::Error> = std::error::Error::source(self);
        while let Some(e) = cur {
            let msg = e.to_string();
            if !prev.contains(&msg) {
                out.push_str(": ");
                out.push_str(&msg);
            }
            prev = msg;
            cur = e.source();
        }
        out
    }
}

/// Makes `cfg` fit a simulated hand: palm-down grasps only, the simulator's control period
/// and its lift (height, ramp plus hold).
pub fn fit_to_simulator(cfg: &mut PipelineConfig, sim: &SimConfig) {
    cfg.top_down_only = true;
    cfg.control_period_s = sim.control_period;
    cfg.lift_height_m = sim.lift.height;
    cfg.lift_duration_s = sim.lift.ramp_time + sim.lift.hold_time;
}

/// What a session is given.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The pipeline (fitted to the simulator: [`fit_to_simulator`]).
    pub pipeline: PipelineConfig,
    /// Where the object lies and the raw-sensor model (its seed).
    pub backend: SimBackendConfig,
    /// A calibration to use; `None`: calibrate the fingertips first (as `grasp
    /// calibrate`).
    pub calibration: Option<TactileCalibration>,
    /// A grasp or cloud to plan on; `None`: the cameras' cloud.
    pub source: Option<GraspSource>,
    /// The simulated depth cameras.
    pub cameras: CameraConfig,
    /// The seed of the first cloud's noise and of the grasp sampler; attempt `k`'s cloud
    /// is seeded by [`crate::eval::trial::attempt_seed`].
    pub seed: u64,
    /// Attempts at most (1..=[`crate::eval::MAX_ATTEMPTS`]); more than one needs the
    /// cameras (no `source`).
    pub attempts: usize,
}

/// One attempt's plan and outcome, reported as it ends.
#[derive(Debug, Clone)]
pub struct AttemptReport {
    /// The attempt (1 = the first).
    pub number: usize,
    /// Its plan.
    pub plan: GraspPlan,
    /// How it ended.
    pub outcome: AttemptOutcome,
}

/// How a session ended.
#[derive(Debug)]
pub struct SessionOutcome {
    /// The attempts made, in order.
    pub attempts: Vec<AttemptReport>,
    /// Why a failed session stopped before its last allowed attempt: the attempt that
    /// was not made and the backend's reason (the object did not settle, the physics
    /// failed).
    pub stopped: Option<(usize, HwError)>,
}

impl SessionOutcome {
    /// Whether the last attempt lifted the object.
    pub fn success(&self) -> bool {
        self.attempts.last().is_some_and(|a| a.outcome.success)
    }
}

/// A simulated hand-arm behind the safety layer, calibrated, with the source of its first
/// plan.
pub struct Session<A: SimulatedArm> {
    arm: SafeHandArm<A>,
    calibration: TactileCalibration,
    calibrated_now: bool,
    source: GraspSource,
    cfg: SessionConfig,
}

impl<A: SimulatedArm> Session<A> {
    /// Builds the backend around `object` (`cfg.backend`), calibrates its fingertips
    /// unless `cfg.calibration` is given, takes the cameras' cloud (seed `cfg.seed`)
    /// unless `cfg.source` is given and puts the backend behind the safety layer.
    pub fn start(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        mut cfg: SessionConfig,
    ) -> Result<Session<A>, SessionError> {
        let mut arm =
            A::build(robot, object, sim_cfg, cfg.backend.clone()).map_err(SessionError::Build)?;
        let (calibration, calibrated_now) = match cfg.calibration.take() {
            Some(c) => (c, false),
            None => (
                calibrate_simulated(
                    &mut arm,
                    CALIBRATION_STILL_READINGS,
                    DEFAULT_THRESHOLD_FRACTION,
                    CALIBRATION_PRESS_N,
                    CALIBRATION_PRESSES,
                )
                .map_err(SessionError::Calibrate)?
                .calibration,
                true,
            ),
        };
        let source = match cfg.source.take() {
            Some(s) => s,
            None => GraspSource::Cloud(
                arm.camera_cloud(&cfg.cameras, cfg.seed)
                    .map_err(SessionError::Cameras)?,
            ),
        };
        let arm = SafeHandArm::new(
            arm,
            robot.hand_limits(),
            cfg.pipeline.safety,
            Arc::new(AtomicBool::new(false)),
        )
        .map_err(RunError::from)?;
        Ok(Session {
            arm,
            calibration,
            calibrated_now,
            source,
            cfg,
        })
    }

    /// The source of the next plan (the cameras' cloud or the given grasp or cloud).
    pub fn source(&self) -> &GraspSource {
        &self.source
    }

    /// The calibration in use.
    pub fn calibration(&self) -> &TactileCalibration {
        &self.calibration
    }

    /// Whether the session calibrated the fingertips itself.
    pub fn calibrated_now(&self) -> bool {
        self.calibrated_now
    }

    /// The backend behind the safety layer.
    pub fn arm(&self) -> &SafeHandArm<A> {
        &self.arm
    }

    /// Makes up to `cfg.attempts` attempts with `controller`, each logged to `log` and
    /// handed to `on_attempt` as it ends, until one lifts the object. The first error ends
    /// the session.
    pub fn run(
        &mut self,
        robot: &Robot,
        controller: &mut Controller,
        log: &mut AttemptLog,
        mut on_attempt: impl FnMut(&AttemptReport),
    ) -> Result<SessionOutcome, SessionError> {
        let mut tried: Vec<GraspPlan> = Vec::new();
        let mut out = SessionOutcome {
            attempts: Vec::new(),
            stopped: None,
        };
        let seed = self.cfg.seed;
        for k in 0..self.cfg.attempts.max(1) {
            if k > 0 {
                if let Err(e) = self.arm.backend_mut().settle_for_retry() {
                    out.stopped = Some((k + 1, e));
                    break;
                }
                let s = crate::eval::trial::attempt_seed(seed, k);
                let cloud = self.arm.backend().camera_cloud(&self.cfg.cameras, s);
                self.source = GraspSource::Cloud(cloud.map_err(SessionError::Cameras)?);
            }
            let plan = plan_attempt(
                robot,
                &self.source,
                &self.cfg.pipeline,
                controller,
                seed,
                &tried,
            )?;
            if let Controller::Policy(p) = controller {
                p.set_object_cloud(object_cloud(&self.source));
            }
            let outcome = run_attempt_with(
                &mut self.arm,
                robot,
                &plan,
                controller,
                &self.calibration,
                &self.cfg.pipeline,
                log,
            )
            .map_err(SessionError::Attempt)?;
            let report = AttemptReport {
                number: k + 1,
                plan,
                outcome,
            };
            on_attempt(&report);
            let success = report.outcome.success;
            tried.push(report.plan.clone());
            out.attempts.push(report);
            if success {
                break;
            }
        }
        Ok(out)
    }
}

/// The object's points of a cloud source (what an M3G policy measures its surface
/// vectors against); none for a given grasp.
pub fn object_cloud(source: &GraspSource) -> Option<Vec<Point3<f64>>> {
    match source {
        GraspSource::Cloud(c) => Some(c.clone()),
        GraspSource::Given(_) => None,
    }
}

/// Plans a grasp on `source` for `controller` (its preshape, the sampler seeded by
/// `seed`), avoiding the grasps already `tried`.
pub fn plan_attempt(
    robot: &Robot,
    source: &GraspSource,
    cfg: &PipelineConfig,
    controller: &Controller,
    seed: u64,
    tried: &[GraspPlan],
) -> Result<GraspPlan, SessionError> {
    let mut cfg = cfg.clone();
    cfg.antipodal.seed = seed;
    let preshape = controller.preshape(&cfg)?;
    plan_grasp_avoiding(robot, source, &preshape, &cfg, tried).map_err(SessionError::Plan)
}
