//! The interface to a real (or simulated) hand-arm system and everything that turns its
//! raw signals into the abstract observations of the agent (Sec. V of the paper).
//!
//! This module knows nothing of the physics engine: a backend implements [`HandArm`]
//! (a ROS bridge to the Shadow hand and the UR10e, or the simulator) and the rest of the
//! crate drives it through [`safety::SafeHandArm`], which clamps every command and stops
//! the robot when the data goes stale or the emergency stop is pressed.
//!
//! - [`calibration`]: tactile calibration of Sec. V-C (lower = mean of 10 still readings,
//!   upper = maximum while pressed, contact above 0.3 % of the range).
//! - [`torque`]: tendon-force drift compensation (`tau_j - tau_j0`) and torque levels.
//! - [`safety`]: joint-limit and step clamping, the sensor watchdog, the safe wrapper.
//! - [`log`]: JSON-lines attempt logs that survive a crash.
//! - `ros` (cargo feature `ros`): a rosbridge v2 client implementing [`HandArm`] for the
//!   Shadow hand's ROS 1 driver and the UR10e.

pub mod calibration;
pub mod log;
#[cfg(feature = "ros")]
pub mod ros;
pub mod safety;
pub mod torque;

// The counts of what the hand reports are the robot's: joint angles (paper order, see
// [`HAND_JOINTS`]), fingertip tactile sensors, and tendon-force channels, one per
// actuator.
use crate::robot::joints::{HAND_JOINTS, N_ACTUATORS, N_JOINTS, N_TACTILE};

/// Number of UR10e arm joints.
pub const N_ARM_JOINTS: usize = 6;

/// Error of a hardware operation. Every variant is one the caller can act on: retry,
/// stop the attempt, recalibrate or abort.
#[derive(Debug, thiserror::Error)]
pub enum HwError {
    /// No fresh data (or no acknowledgement) arrived in time.
    #[error("timeout: no fresh {what} for {waited_s:.3} s")]
    Timeout {
        /// What was waited for, e.g. `sensor data`.
        what: String,
        /// How long it was waited for (backend clock, seconds).
        waited_s: f64,
    },
    /// A measured joint angle is outside its limits.
    #[error("joint {joint} at {value:.4} rad is outside its limits [{lower:.4}, {upper:.4}]")]
    LimitViolation {
        /// Joint name (paper naming, e.g. `FFJ3`).
        joint: String,
        /// The offending value (rad).
        value: f64,
        /// Lower limit (rad).
        lower: f64,
        /// Upper limit (rad).
        upper: f64,
    },
    /// The emergency stop was requested; the robot has been stopped.
    #[error("emergency stop requested: the robot was stopped")]
    EmergencyStop,
    /// The connection to the robot was lost.
    #[error("robot disconnected: {0}")]
    Disconnected(String),
    /// A reading is unusable (NaN, infinite, wrong size).
    #[error("invalid reading in {field}: {detail}")]
    InvalidReading {
        /// The field, e.g. `joint_angles[5] (FFJ3)`.
        field: String,
        /// What is wrong.
        detail: String,
    },
    /// A command is unusable (NaN target, non-positive duration); it was not sent.
    #[error("invalid command in {field}: {detail}")]
    InvalidCommand {
        /// The field, e.g. `targets[5] (FFJ3)`.
        field: String,
        /// What is wrong.
        detail: String,
    },
    /// An I/O error of the backend.
    #[error("hardware I/O error: {0}")]
    Io(#[from] std::io::Error),
}

/// One snapshot of the raw hand signals.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RawSensors {
    /// Time of the reading on the backend clock ([`HandArm::now`]), seconds.
    pub stamp: f64,
    /// The 24 hand joint angles, paper order (rad).
    pub joint_angles: [f64; N_JOINTS],
    /// Raw fingertip sensor values, FF, MF, RF, LF, TH (sensor units).
    pub tactile_raw: [f64; N_TACTILE],
    /// Raw tendon force (or joint effort) per actuator, paper actuator order.
    pub tendon_raw: [f64; N_ACTUATORS],
}

impl RawSensors {
    /// Checks that every value is finite; the error names the first bad field.
    pub fn validate(&self) -> Result<(), HwError> {
        if !self.stamp.is_finite() {
            return Err(invalid_reading("stamp".into(), self.stamp));
        }
        if let Some(k) = self.joint_angles.iter().position(|v| !v.is_finite()) {
            return Err(invalid_reading(
                format!("joint_angles[{k}] ({})", HAND_JOINTS[k]),
                self.joint_angles[k],
            ));
        }
        if let Some(k) = self.tactile_raw.iter().position(|v| !v.is_finite()) {
            return Err(invalid_reading(
                format!("tactile_raw[{k}] ({})", crate::robot::joints::FINGERS[k]),
                self.tactile_raw[k],
            ));
        }
        if let Some(k) = self.tendon_raw.iter().position(|v| !v.is_finite()) {
            return Err(invalid_reading(
                format!("tendon_raw[{k}]"),
                self.tendon_raw[k],
            ));
        }
        Ok(())
    }
}

fn invalid_reading(field: String, v: f64) -> HwError {
    HwError::InvalidReading {
        field,
        detail: format!("value {v} is not finite"),
    }
}

/// A motion of the UR10e arm.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ArmMotion {
    /// Move to these six joint angles (rad, base to wrist 3).
    Joints([f64; N_ARM_JOINTS]),
    /// Lift the hand straight up by `height_m` metres in `duration_s` seconds.
    Lift {
        /// Lift height (m), positive and finite.
        height_m: f64,
        /// Duration (s), positive and finite.
        duration_s: f64,
    },
}

impl ArmMotion {
    /// Checks that the motion is finite and meaningful (positive lift height and
    /// duration); the error names the field.
    pub fn validate(&self) -> Result<(), HwError> {
        let bad = |field: String, detail: String| Err(HwError::InvalidCommand { field, detail });
        match *self {
            ArmMotion::Joints(q) => {
                if let Some(k) = q.iter().position(|v| !v.is_finite()) {
                    return bad(
                        format!("arm joints[{k}]"),
                        format!("{} is not finite", q[k]),
                    );
                }
            }
            ArmMotion::Lift {
                height_m,
                duration_s,
            } => {
                if !(height_m.is_finite() && height_m > 0.0) {
                    return bad(
                        "lift height_m".into(),
                        format!("{height_m} is not a positive finite height"),
                    );
                }
                if !(duration_s.is_finite() && duration_s > 0.0) {
                    return bad(
                        "lift duration_s".into(),
                        format!("{duration_s} is not a positive finite duration"),
                    );
                }
            }
        }
        Ok(())
    }
}

/// A hand-arm system: the Shadow hand on the UR10e, real or simulated.
///
/// Backends report raw values; calibration, drift compensation, clamping and the
/// watchdog live in this module, so every backend gets the same treatment. Use a backend
/// through [`safety::SafeHandArm`].
pub trait HandArm {
    /// Reads the latest hand signals.
    fn read(&mut self) -> Result<RawSensors, HwError>;
    /// Sends position targets for the 24 hand joints (paper order, rad).
    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), HwError>;
    /// Starts (and, for blocking backends, completes) an arm motion.
    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError>;
    /// Stops hand and arm where they are. Must be safe to call repeatedly.
    fn stop(&mut self) -> Result<(), HwError>;
    /// The backend clock in seconds (wall clock on the robot, simulated time in the
    /// simulator or in tests). Reading stamps use this clock.
    fn now(&self) -> f64;
    /// Lets `seconds` pass on the backend clock while the last commands act: the default
    /// sleeps the calling thread (a real robot moves on its own); the simulator steps its
    /// physics instead. Non-finite or negative durations are an
    /// [`HwError::InvalidCommand`].
    fn wait(&mut self, seconds: f64) -> Result<(), HwError> {
        check_duration(seconds)?;
        std::thread::sleep(std::time::Duration::try_from_secs_f64(seconds).unwrap_or_default());
        Ok(())
    }
    /// Whether the object was held after the last [`ArmMotion::Lift`], where the backend
    /// knows the truth (the simulator does); `None` (the default) on a real robot, where
    /// the caller judges from the sensors.
    fn lift_outcome(&self) -> Option<bool> {
        None
    }
}

/// Checks a [`HandArm::wait`] duration: finite and non-negative.
pub fn check_duration(seconds: f64) -> Result<(), HwError> {
    // A day bounds every wait (and keeps it within a `Duration`).
    if seconds.is_finite() && (0.0..=86_400.0).contains(&seconds) {
        Ok(())
    } else {
        Err(HwError::InvalidCommand {
            field: "wait seconds".into(),
            detail: format!(
                "{} is not a duration in [0, 86400] s",
                crate::util::num::short(seconds)
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok_sensors() -> RawSensors {
        RawSensors {
            stamp: 1.0,
            joint_angles: [0.0; 24],
            tactile_raw: [0.0; 5],
            tendon_raw: [0.0; 20],
        }
    }

    #[test]
    fn validate_names_the_bad_field() {
        assert!(ok_sensors().validate().is_ok());
        let mut s = ok_sensors();
        s.joint_angles[3] = f64::NAN;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("joint_angles[3] (FFJ3)"), "{e}");
        let mut s = ok_sensors();
        s.tactile_raw[4] = f64::INFINITY;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("tactile_raw[4] (TH)"), "{e}");
        let mut s = ok_sensors();
        s.tendon_raw[19] = f64::NAN;
        assert!(s
            .validate()
            .unwrap_err()
            .to_string()
            .contains("tendon_raw[19]"));
        let mut s = ok_sensors();
        s.stamp = f64::NAN;
        assert!(s.validate().unwrap_err().to_string().contains("stamp"));
    }

    #[test]
    fn arm_motion_validation() {
        assert!(ArmMotion::Joints([0.0; 6]).validate().is_ok());
        assert!(ArmMotion::Lift {
            height_m: 0.2,
            duration_s: 2.0
        }
        .validate()
        .is_ok());
        let mut q = [0.0; 6];
        q[2] = f64::NAN;
        assert!(ArmMotion::Joints(q)
            .validate()
            .unwrap_err()
            .to_string()
            .contains("arm joints[2]"));
        let e = ArmMotion::Lift {
            height_m: 0.2,
            duration_s: 0.0,
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("duration_s"), "{e}");
        let e = ArmMotion::Lift {
            height_m: -0.1,
            duration_s: 1.0,
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("height_m"), "{e}");
    }
}
