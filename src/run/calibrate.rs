//! The tactile calibration of Sec. V-C on any [`HandArm`]: the lower range is the mean of
//! still readings, the upper range the maximum reading while each fingertip is pressed
//! (how it is pressed is the caller's: an operator on the robot, a known force in the
//! simulator, see [`SimHandArm::read_pressed`](super::sim_backend::SimHandArm::read_pressed)).

use super::simulated::SimulatedArm;
use super::RunError;
use crate::hardware::calibration::{TactileCalibration, TactileCalibrator};
use crate::hardware::{HandArm, RawSensors};
use crate::robot::joints::N_TACTILE;
use serde::Serialize;

/// What the calibration saw, for the report and for checks: per fingertip the mean and
/// the largest still reading and the largest pressed reading, and the resulting
/// calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationReport {
    /// The calibration (lower, upper, threshold fraction).
    pub calibration: TactileCalibration,
    /// The contact threshold per fingertip (raw units).
    pub thresholds: [f64; N_TACTILE],
    /// The largest still reading per fingertip.
    pub still_max: [f64; N_TACTILE],
    /// The largest pressed reading per fingertip.
    pub pressed_max: [f64; N_TACTILE],
    /// Still readings used.
    pub still_readings: usize,
}

/// Runs the procedure: `still_readings` readings (at least 10) `period_s` apart with the
/// hand still, then for each fingertip `k` the readings `press(arm, k)` returns while it
/// is pressed. `fraction` is the contact threshold (0.003 in the paper).
pub fn calibrate_tactile<A: HandArm>(
    arm: &mut A,
    still_readings: usize,
    period_s: f64,
    fraction: f64,
    mut press: impl FnMut(&mut A, usize) -> Result<Vec<RawSensors>, RunError>,
) -> Result<CalibrationReport, RunError> {
    let mut cal = TactileCalibrator::new();
    let mut still_max = [f64::NEG_INFINITY; N_TACTILE];
    for k in 0..still_readings {
        if k > 0 {
            arm.wait(period_s)?;
        }
        let r = arm.read()?;
        cal.add_still(&r.tactile_raw)?;
        for (m, v) in still_max.iter_mut().zip(r.tactile_raw) {
            *m = m.max(v);
        }
    }
    let mut pressed_max = [f64::NEG_INFINITY; N_TACTILE];
    for (finger, max) in pressed_max.iter_mut().enumerate() {
        for r in press(arm, finger)? {
            cal.add_press(finger, &r.tactile_raw)?;
            *max = max.max(r.tactile_raw[finger]);
        }
    }
    let calibration = cal.finish(fraction)?;
    Ok(CalibrationReport {
        thresholds: std::array::from_fn(|k| calibration.threshold(k)),
        calibration,
        still_max,
        pressed_max,
        still_readings,
    })
}

/// The simulated fingertips' calibration, as `grasp run` and `grasp calibrate` make it on
/// any [`SimulatedArm`]: `still` readings 20 ms apart, then each fingertip pressed with a
/// known force (`press_n` newtons, `presses` readings each); `fraction` is the contact
/// threshold.
pub fn calibrate_simulated<A: SimulatedArm>(
    arm: &mut A,
    still: usize,
    fraction: f64,
    press_n: f64,
    presses: usize,
) -> Result<CalibrationReport, RunError> {
    calibrate_tactile(arm, still, 0.02, fraction, |a, finger| {
        (0..presses)
            .map(|_| a.read_pressed(finger, press_n).map_err(Into::into))
            .collect()
    })
}
