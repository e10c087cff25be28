//! Grasp attempts on a hand-arm system: the simulator behind the hardware interface and
//! the grasp pipeline of Sec. V-B that runs on any [`HandArm`](crate::hardware::HandArm).
//!
//! The dependencies flow `cli -> run -> {env, sim, hardware, ppo}`: [`crate::hardware`]
//! knows nothing of the physics engine, so the simulator backend lives here.
//!
//! - [`sim_backend`]: [`SimHandArm`](sim_backend::SimHandArm), the Rapier simulation
//!   with a raw-sensor model (tactile offsets, gains and noise, drifting tendon forces),
//!   a simulated clock and a sensor-dropout switch for the watchdog.
//! - [`raw_model`]: [`RawModel`](raw_model::RawModel), the raw-sensor model every
//!   simulated backend shares.
//! - [`simulated`]: [`SimulatedArm`](simulated::SimulatedArm), what a simulated backend
//!   offers beyond [`HandArm`](crate::hardware::HandArm) (cameras, a known press, a
//!   settle for a retry, the physics failure); implemented by `SimHandArm`.
//! - [`calibrate`]: the tactile calibration procedure of Sec. V-C on any backend.
//! - [`pipeline`]: grasp planning (a given two-finger grasp or antipodal candidates on a
//!   point cloud, the hand mapping, UR10e IK) and the attempt (stage 1, the policy, the
//!   lift), logged step by step; the scripted baselines in place of stage 1 and the
//!   policy ([`Controller`](pipeline::Controller)).
//! - [`request`]: `grasp run` as one request ([`RunRequest`](request::RunRequest)):
//!   checked, loaded and carried out here; the command prints what it reports.
//! - [`session`]: `grasp run` on a simulated backend: set-up, calibration, cameras and
//!   the attempt-and-retry loop, generic over [`SimulatedArm`](simulated::SimulatedArm).
//! - [`table`]: Table I through the robot path: agents times objects times trials, each
//!   trial a session, judged by the backend and aggregated as `grasp eval` does.

pub mod calibrate;

/// [`DEFAULT_POLICY`] as a literal, for `include_bytes!` (the Python module embeds it).
#[macro_export]
#[doc(hidden)]
macro_rules! default_policy {
    () => {
        "assets/policies/fig5_gru_m3_pca8"
    };
}

/// The policy `grasp run` acts with unless `--policy` names another: the shipped policy
/// with the most successes from the pre-grasp `grasp run` plans on the validation set and
/// its real slice (the rule and its measurement: docs/robot-hardware.md, "The default
/// policy"); Python's `grasp_rl.Policy.shipped()` embeds the same one. A path relative to
/// the repository, found from any working directory by [`crate::util::assets::shipped`].
pub const DEFAULT_POLICY: &str = default_policy!();

pub mod mjcf;
#[cfg(feature = "mujoco")]
pub mod mujoco_backend;
pub mod pipeline;
pub mod plan;
pub mod raw_model;
pub mod request;
pub mod session;
pub mod sim_backend;
pub mod simulated;
pub mod table;

use crate::hardware::calibration::CalibrationError;
use crate::hardware::log::LogError;
use crate::hardware::torque::TorqueError;
use crate::hardware::HwError;
use crate::perception::pointcloud::CloudError;
use std::path::PathBuf;

/// Error of a grasp attempt, a calibration or their setup. Every variant names what
/// failed (file, field or stage).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The robot (or the simulator behind the interface) reported an error.
    #[error(transparent)]
    Hw(#[from] HwError),
    /// The tactile calibration failed or its file is bad.
    #[error(transparent)]
    Calibration(#[from] CalibrationError),
    /// The tendon readings could not be mapped.
    #[error(transparent)]
    Torque(#[from] TorqueError),
    /// The point cloud is unusable.
    #[error(transparent)]
    Cloud(#[from] CloudError),
    /// The attempt log could not be written.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The simulator refused its setup.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// A grasp file is missing or malformed.
    #[error("grasp file {path}: {detail}")]
    GraspFile {
        /// The file.
        path: PathBuf,
        /// What is wrong (field, line and column where known).
        detail: String,
    },
    /// The grasp itself is unusable (degenerate directions, NaN).
    #[error("invalid grasp: {0}")]
    BadGrasp(String),
    /// UR10e inverse kinematics found no solution for a pose of the attempt.
    #[error(
        "the UR10e cannot reach the {stage} pose of the grasp at ({}, {}, {}) m: {source}",
        coord(*x),
        coord(*y),
        coord(*z)
    )]
    Ik {
        /// `approach` or `pre-grasp`.
        stage: &'static str,
        /// Grasp centre x (m, world frame).
        x: f64,
        /// Grasp centre y (m).
        y: f64,
        /// Grasp centre z (m).
        z: f64,
        /// The IK error.
        #[source]
        source: crate::robot::ur10e::IkError,
    },
    /// No grasp candidate of the cloud is usable.
    #[error("no usable grasp: {0}")]
    NoGrasp(String),
    /// The policy checkpoint cannot be used.
    #[error("policy {path}: {detail}")]
    Policy {
        /// The checkpoint folder.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// A configuration value is out of range.
    #[error("invalid {field}: {detail}")]
    Config {
        /// The field.
        field: String,
        /// What is wrong.
        detail: String,
    },
}

/// A coordinate in a message: three decimals for everyday values, as
/// [`crate::util::num::short`] writes very large or small ones (`1e300`, not 300 digits).
fn coord(v: f64) -> String {
    if v.is_finite() && v.abs() < 1e6 {
        format!("{v:.3}")
    } else {
        crate::util::num::short(v)
    }
}
