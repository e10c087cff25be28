//! [`SimulatedArm`]: a hand-arm system whose world is simulated (the Rapier simulator of
//! [`super::sim_backend`], MuJoCo), so that `grasp run`'s session
//! ([`super::session`]), its calibration ([`super::calibrate::calibrate_simulated`]) and
//! its table of grasps over an object set ([`super::table`]) are written once for every
//! engine: a backend is one file that implements this trait.

use crate::hardware::{HwError, RawSensors};
use crate::perception::pointcloud::CloudError;
use crate::robot::Robot;
use crate::sim::{FailureReport, LiftOutcome, ObjectSpec, SimConfig};
use nalgebra::Point3;

use super::pipeline::ArmBase;
use super::raw_model::RawModelConfig;
use crate::perception::camera::CameraConfig;
use crate::robot::grasp_map::hand_grasp_frame;
use crate::robot::ur10e;
use nalgebra::{Isometry3, Vector3};

/// A hand-arm whose world is simulated: built around one object, it can show the object to simulated depth cameras, press a fingertip with a known force (calibration), let the object settle for a retry, and judge a lift (HandArm::lift_outcome).
pub trait SimulatedArm: crate::hardware::HandArm + Sized {
    /// Short lower-case name for reports: "sim", "mujoco".
    const NAME: &'static str;

    /// The hand of `robot` with `object` at rest where `cfg` places it (`object_xy`,
    /// `object_yaw`), the raw-sensor model of `cfg.raw`, the hand open above the object.
    fn build(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        cfg: SimBackendConfig,
    ) -> Result<Self, HwError>;

    /// The point cloud the depth cameras of `cam` see of the object as it lies now (world
    /// frame, m), with noise drawn from `seed`.
    fn camera_cloud(&self, cam: &CameraConfig, seed: u64) -> Result<Vec<Point3<f64>>, CloudError>;

    /// One reading while fingertip `finger` (0..5: FF, MF, RF, LF, TH) is pressed with
    /// `force_n` newtons.
    fn read_pressed(&mut self, finger: usize, force_n: f64) -> Result<RawSensors, HwError>;

    /// Opens the hand where the attempt left it and lets the object come to rest; later
    /// arm moves keep the object where it lies. An error says why there is no retry.
    fn settle_for_retry(&mut self) -> Result<(), HwError>;

    /// The physics failure of the episode so far, if the engine broke (counted in tables as `grasp eval` counts them).
    fn physics_failure(&self) -> Option<String>;

    /// The physics failure with its kind, bodies and step, where the engine reports one
    /// in the Rapier simulator's terms (tables list it as `grasp eval` does); `None`
    /// otherwise (a failure is then counted with kind `unknown`).
    fn failure_report(&self) -> Option<FailureReport> {
        None
    }

    /// How the last lift ended (height, turn, grip, object in the hand), where the engine
    /// measures it; tables fill `grasp eval`'s lift statistics from it (zeros without).
    fn lift_report(&self) -> Option<LiftOutcome> {
        None
    }

    /// The deepest penetration of the object by the hand or the table since the hand was
    /// last placed (m) and what the object touched there, where the engine measures it.
    fn deepest_contact(&self) -> Option<(f64, String)> {
        None
    }
}

/// Where the object lies and where the arm stands in the simulated world.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimBackendConfig {
    /// The raw-sensor model.
    pub raw: RawModelConfig,
    /// Object centre x, y on the table (m).
    pub object_xy: [f64; 2],
    /// Object yaw (rad).
    pub object_yaw: f64,
    /// The UR10e base in the world.
    pub arm_base: ArmBase,
    /// Height of the hand's grasp point above the object's top at construction (m).
    pub home_clearance: f64,
}

impl SimBackendConfig {
    /// Checks the raw-sensor model and that the object's place and the clearance are
    /// finite (the clearance non-negative); the error names the field.
    pub fn validate(&self) -> Result<(), HwError> {
        self.raw.validate()?;
        let finite = self.object_xy.iter().all(|v| v.is_finite())
            && self.object_yaw.is_finite()
            && self.home_clearance.is_finite()
            && self.home_clearance >= 0.0;
        if !finite {
            return Err(HwError::InvalidCommand {
                field: "object_xy/object_yaw/home_clearance".into(),
                detail: "must be finite (clearance >= 0)".into(),
            });
        }
        Ok(())
    }
}

impl Default for SimBackendConfig {
    fn default() -> Self {
        SimBackendConfig {
            raw: RawModelConfig::default(),
            object_xy: [0.0, 0.0],
            object_yaw: 0.0,
            arm_base: ArmBase::default(),
            home_clearance: 0.15,
        }
    }
}

/// Largest tilt of the palm normal from the vertical that the simulated robots accept (rad).
pub const MAX_PALM_TILT_RAD: f64 = 1e-3;
/// Step of the guarded placement (m).
pub const GUARD_STEP_M: f64 = 0.005;
/// Largest raise of the guarded placement (m).
pub const GUARD_MAX_M: f64 = 0.10;

/// Where the simulated robots put the hand for the arm at joint angles `q` (base at
/// `arm_base`, hand in posture `hand_q`): the grasp point (the TH/LF tip midpoint, world
/// frame) and the hand's yaw. They carry the hand palm down only, so a pose whose palm
/// normal is more than [`MAX_PALM_TILT_RAD`] from the vertical is refused.
pub fn top_down_placement(
    robot: &Robot,
    arm_base: &ArmBase,
    hand_q: &[f64; 24],
    q: &[f64; 6],
) -> Result<(Point3<f64>, f64), HwError> {
    let flange = arm_base.pose() * ur10e::fk(q);
    let palm = flange * robot.hand_fk_palm(hand_q)[robot.hand.forearm].inverse();
    let gf: Isometry3<f64> = palm
        * hand_grasp_frame(robot, hand_q).map_err(|e| HwError::InvalidCommand {
            field: "hand posture".into(),
            detail: e.to_string(),
        })?;
    let approach = gf.rotation * Vector3::x();
    let tilt = approach.angle(&-Vector3::z());
    if tilt.is_nan() || tilt > MAX_PALM_TILT_RAD {
        return Err(HwError::InvalidCommand {
            field: "arm joints".into(),
            detail: format!(
                "the simulator places the hand palm down only; this pose tilts the palm normal {tilt:.3} rad from the vertical"
            ),
        });
    }
    let y = gf.rotation * Vector3::y();
    Ok((Point3::from(gf.translation.vector), y.y.atan2(y.x)))
}

/// The guarded placement of the simulated robots: `place(raise)` resets the world with the
/// hand where it was last placed, first raised by [`GUARD_STEP_M`] when `raise`, and says
/// whether the hand overlaps the object; the hand is raised step by step until it does not
/// (as a guarded approach that stops at first contact would). The raise used, or an error
/// past [`GUARD_MAX_M`].
pub fn guarded_placement(
    mut place: impl FnMut(bool) -> Result<bool, HwError>,
) -> Result<f64, HwError> {
    let mut raised = 0.0;
    let mut overlaps = place(false)?;
    while overlaps {
        if raised >= GUARD_MAX_M - 1e-12 {
            return Err(HwError::InvalidCommand {
                field: "arm joints".into(),
                detail: format!(
                    "the hand overlaps the object even {:.0} mm above this pose",
                    GUARD_MAX_M * 1000.0
                ),
            });
        }
        raised += GUARD_STEP_M;
        overlaps = place(true)?;
    }
    Ok(raised)
}
