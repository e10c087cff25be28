//! Safety layer between the policy and the robot.
//!
//! - [`SafetyLimiter`] clamps every hand target to the joint limits and to a maximum
//!   change per command relative to the last measured angles, and reports each clamp as a
//!   [`ClampEvent`] for the log. NaN targets are rejected and never sent.
//! - [`Watchdog`] trips when the newest sensor stamp is older than its timeout.
//! - [`SafeHandArm`] wraps any [`HandArm`] backend: it runs the watchdog on every read and
//!   command, applies the limiter to every hand command, and calls
//!   [`HandArm::stop`] when the watchdog trips, a reading is invalid or out of limits,
//!   or the emergency-stop flag is set.

use super::{ArmMotion, HandArm, HwError, RawSensors};
use crate::robot::joints::HAND_JOINTS;
use crate::robot::joints::N_JOINTS;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Default maximum change of a hand target per command (rad).
pub const DEFAULT_MAX_STEP_RAD: f64 = 0.3;
/// Default watchdog timeout (s).
pub const DEFAULT_WATCHDOG_TIMEOUT_S: f64 = 0.1;
/// Default tolerance on measured angles beyond the joint limits before a reading is a
/// [`HwError::LimitViolation`] (rad).
pub const DEFAULT_LIMIT_TOLERANCE_RAD: f64 = 0.05;

/// Why a target was changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClampReason {
    /// The target was outside the joint limits.
    JointLimit,
    /// The target was further than the maximum step from the measured angle.
    MaxStep,
}

/// One clamped target, for the attempt log.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClampEvent {
    /// Joint name (paper naming, e.g. `FFJ3`).
    pub joint: String,
    /// The requested target (rad).
    pub requested: f64,
    /// The target actually sent (rad).
    pub applied: f64,
    /// The last constraint that changed the target.
    pub reason: ClampReason,
}

/// Clamps hand targets to joint limits and to a maximum step per command.
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyLimiter {
    limits: [(f64, f64); N_JOINTS],
    max_step: f64,
}

impl SafetyLimiter {
    /// A limiter with per-joint `(lower, upper)` limits (paper order, e.g.
    /// [`Robot::hand_limits`](crate::robot::Robot::hand_limits)) and a maximum change
    /// `max_step_rad` per command. Errors on non-finite or inverted limits or a
    /// non-positive step.
    pub fn new(limits: [(f64, f64); N_JOINTS], max_step_rad: f64) -> Result<Self, HwError> {
        for (k, &(lo, hi)) in limits.iter().enumerate() {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(HwError::InvalidCommand {
                    field: format!("limits[{k}] ({})", HAND_JOINTS[k]),
                    detail: format!("[{lo}, {hi}] is not a finite interval"),
                });
            }
        }
        if !(max_step_rad.is_finite() && max_step_rad > 0.0) {
            return Err(HwError::InvalidCommand {
                field: "max_step_rad".into(),
                detail: format!("{max_step_rad} must be positive and finite"),
            });
        }
        Ok(SafetyLimiter {
            limits,
            max_step: max_step_rad,
        })
    }

    /// The joint limits in use.
    pub fn limits(&self) -> &[(f64, f64); N_JOINTS] {
        &self.limits
    }

    /// The maximum step per command (rad).
    pub fn max_step(&self) -> f64 {
        self.max_step
    }

    /// Clamps `targets` given the last `measured` angles. Each target is first clamped to
    /// `[measured - max_step, measured + max_step]` and then to the joint limits (the
    /// limits always win, even if the measured angle is outside them). Returns the
    /// applied targets and one event per changed joint. NaN or infinite targets or
    /// measurements are an error: nothing may be sent.
    pub fn clamp(
        &self,
        targets: &[f64; N_JOINTS],
        measured: &[f64; N_JOINTS],
    ) -> Result<([f64; N_JOINTS], Vec<ClampEvent>), HwError> {
        if let Some(k) = targets.iter().position(|v| !v.is_finite()) {
            return Err(HwError::InvalidCommand {
                field: format!("targets[{k}] ({})", HAND_JOINTS[k]),
                detail: format!("target {} is not finite; nothing was sent", targets[k]),
            });
        }
        if let Some(k) = measured.iter().position(|v| !v.is_finite()) {
            return Err(HwError::InvalidReading {
                field: format!("joint_angles[{k}] ({})", HAND_JOINTS[k]),
                detail: format!("measured angle {} is not finite", measured[k]),
            });
        }
        let mut out = *targets;
        let mut events = Vec::new();
        for k in 0..N_JOINTS {
            let (lo, hi) = self.limits[k];
            let req = targets[k];
            let stepped = req.clamp(measured[k] - self.max_step, measured[k] + self.max_step);
            let applied = stepped.clamp(lo, hi);
            if applied != req {
                let reason = if applied != stepped {
                    ClampReason::JointLimit
                } else {
                    ClampReason::MaxStep
                };
                events.push(ClampEvent {
                    joint: HAND_JOINTS[k].to_string(),
                    requested: req,
                    applied,
                    reason,
                });
            }
            out[k] = applied;
        }
        Ok((out, events))
    }
}

/// Trips when sensor data is stale: the newest stamp is more than `timeout_s` old.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Watchdog {
    timeout_s: f64,
    last: f64,
}

impl Watchdog {
    /// A watchdog with `timeout_s`, armed at time `now` (as if data had arrived then).
    pub fn new(timeout_s: f64, now: f64) -> Result<Self, HwError> {
        if !(timeout_s.is_finite() && timeout_s > 0.0) {
            return Err(HwError::InvalidCommand {
                field: "watchdog timeout_s".into(),
                detail: format!("{timeout_s} must be positive and finite"),
            });
        }
        Ok(Watchdog {
            timeout_s,
            last: now,
        })
    }

    /// The timeout (s).
    pub fn timeout_s(&self) -> f64 {
        self.timeout_s
    }

    /// The newest stamp seen.
    pub fn last_stamp(&self) -> f64 {
        self.last
    }

    /// Records a reading's stamp; older stamps than the newest seen are ignored.
    pub fn feed(&mut self, stamp: f64) {
        if stamp.is_finite() && stamp > self.last {
            self.last = stamp;
        }
    }

    /// `Err(HwError::Timeout)` when `now - last_stamp > timeout_s`.
    pub fn check(&self, now: f64) -> Result<(), HwError> {
        let age = now - self.last;
        if age > self.timeout_s || !age.is_finite() {
            return Err(HwError::Timeout {
                what: "sensor data".into(),
                waited_s: age,
            });
        }
        Ok(())
    }
}

/// Configuration of [`SafeHandArm`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyConfig {
    /// Maximum change of a hand target per command (rad).
    pub max_step_rad: f64,
    /// Watchdog timeout on the sensor stamps (s).
    pub watchdog_timeout_s: f64,
    /// Tolerance on measured angles beyond the joint limits (rad).
    pub limit_tolerance_rad: f64,
}

impl Default for SafetyConfig {
    fn default() -> Self {
        SafetyConfig {
            max_step_rad: DEFAULT_MAX_STEP_RAD,
            watchdog_timeout_s: DEFAULT_WATCHDOG_TIMEOUT_S,
            limit_tolerance_rad: DEFAULT_LIMIT_TOLERANCE_RAD,
        }
    }
}

/// A [`HandArm`] backend behind the safety layer.
///
/// - [`read`](HandArm::read) validates the reading (finite values, angles within the
///   limits plus a tolerance), feeds and checks the watchdog against the backend clock;
/// - [`command_hand`](HandArm::command_hand) checks the e-stop and the watchdog, clamps
///   the targets with the [`SafetyLimiter`] relative to the last measured angles (a read
///   must come first) and sends the clamped targets; the clamp events of the last command
///   are available from [`last_clamp_events`](Self::last_clamp_events);
/// - on any watchdog trip, invalid reading, limit violation, backend timeout or
///   disconnection, or a set e-stop flag, the backend's [`stop`](HandArm::stop) is called
///   before the error is returned.
pub struct SafeHandArm<B: HandArm> {
    backend: B,
    limiter: SafetyLimiter,
    watchdog: Watchdog,
    tolerance: f64,
    estop: Arc<AtomicBool>,
    last_measured: Option<[f64; N_JOINTS]>,
    last_events: Vec<ClampEvent>,
    stops: usize,
}

impl<B: HandArm> SafeHandArm<B> {
    /// Wraps `backend` with joint `limits` (paper order) and `config`; the watchdog is
    /// armed at the backend's current time. `estop` is shared with whoever may request
    /// an emergency stop (a signal handler, a UI thread).
    pub fn new(
        backend: B,
        limits: [(f64, f64); N_JOINTS],
        config: SafetyConfig,
        estop: Arc<AtomicBool>,
    ) -> Result<Self, HwError> {
        let limiter = SafetyLimiter::new(limits, config.max_step_rad)?;
        let watchdog = Watchdog::new(config.watchdog_timeout_s, backend.now())?;
        if !(config.limit_tolerance_rad.is_finite() && config.limit_tolerance_rad >= 0.0) {
            return Err(HwError::InvalidCommand {
                field: "limit_tolerance_rad".into(),
                detail: format!("{} must be non-negative", config.limit_tolerance_rad),
            });
        }
        Ok(SafeHandArm {
            backend,
            limiter,
            watchdog,
            tolerance: config.limit_tolerance_rad,
            estop,
            last_measured: None,
            last_events: Vec::new(),
            stops: 0,
        })
    }

    /// The shared emergency-stop flag: store `true` to stop the robot at the next call.
    pub fn estop_handle(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.estop)
    }

    /// The clamp events of the last hand command (empty if nothing was clamped).
    pub fn last_clamp_events(&self) -> &[ClampEvent] {
        &self.last_events
    }

    /// How many times this wrapper has called the backend's `stop`.
    pub fn stop_count(&self) -> usize {
        self.stops
    }

    /// The wrapped backend.
    pub fn backend(&self) -> &B {
        &self.backend
    }

    /// The wrapped backend, mutably (bypasses the safety layer: tests and setup only).
    pub fn backend_mut(&mut self) -> &mut B {
        &mut self.backend
    }

    /// Unwraps the backend.
    pub fn into_inner(self) -> B {
        self.backend
    }

    /// Stops the backend and returns `err`. A failing stop is reported instead, since
    /// it is the more urgent problem.
    fn fail<T>(&mut self, err: HwError) -> Result<T, HwError> {
        self.stops += 1;
        self.backend.stop()?;
        Err(err)
    }

    fn check_estop(&mut self) -> Result<(), HwError> {
        if self.estop.load(Ordering::SeqCst) {
            return self.fail(HwError::EmergencyStop);
        }
        Ok(())
    }

    fn check_limits(&self, r: &RawSensors) -> Result<(), HwError> {
        for (k, &v) in r.joint_angles.iter().enumerate() {
            let (lo, hi) = self.limiter.limits()[k];
            if v < lo - self.tolerance || v > hi + self.tolerance {
                return Err(HwError::LimitViolation {
                    joint: HAND_JOINTS[k].to_string(),
                    value: v,
                    lower: lo,
                    upper: hi,
                });
            }
        }
        Ok(())
    }
}

impl<B: HandArm> HandArm for SafeHandArm<B> {
    fn read(&mut self) -> Result<RawSensors, HwError> {
        self.check_estop()?;
        let r = match self.backend.read() {
            Ok(r) => r,
            Err(e) => return self.fail(e),
        };
        if let Err(e) = r.validate() {
            return self.fail(e);
        }
        self.watchdog.feed(r.stamp);
        if let Err(e) = self.watchdog.check(self.backend.now()) {
            return self.fail(e);
        }
        if let Err(e) = self.check_limits(&r) {
            return self.fail(e);
        }
        self.last_measured = Some(r.joint_angles);
        Ok(r)
    }

    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), HwError> {
        self.last_events.clear();
        self.check_estop()?;
        if let Err(e) = self.watchdog.check(self.backend.now()) {
            return self.fail(e);
        }
        let Some(measured) = self.last_measured else {
            return Err(HwError::InvalidCommand {
                field: "targets".into(),
                detail: "no measured joint angles yet: read() before command_hand()".into(),
            });
        };
        let (applied, events) = self.limiter.clamp(targets, &measured)?;
        self.last_events = events;
        match self.backend.command_hand(&applied) {
            Ok(()) => Ok(()),
            Err(e) => self.fail(e),
        }
    }

    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError> {
        self.check_estop()?;
        motion.validate()?;
        if let Err(e) = self.watchdog.check(self.backend.now()) {
            return self.fail(e);
        }
        match self.backend.move_arm(motion) {
            Ok(()) => Ok(()),
            Err(e) => self.fail(e),
        }
    }

    fn stop(&mut self) -> Result<(), HwError> {
        self.stops += 1;
        self.backend.stop()
    }

    fn now(&self) -> f64 {
        self.backend.now()
    }

    /// Waits in slices of at most half the watchdog timeout and reads after each slice,
    /// so that stale sensor data stops the robot within the timeout even during a long
    /// wait.
    fn wait(&mut self, seconds: f64) -> Result<(), HwError> {
        self.check_estop()?;
        super::check_duration(seconds)?;
        let slice = self.watchdog.timeout_s() / 2.0;
        let mut left = seconds;
        while left > 0.0 {
            let s = left.min(slice);
            if let Err(e) = self.backend.wait(s) {
                return self.fail(e);
            }
            left -= s;
            self.read()?;
        }
        Ok(())
    }

    fn lift_outcome(&self) -> Option<bool> {
        self.backend.lift_outcome()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> [(f64, f64); 24] {
        [(-1.0, 1.0); 24]
    }

    #[test]
    fn clamp_hand_computed() {
        let l = SafetyLimiter::new(limits(), 0.3).unwrap();
        let measured = {
            let mut m = [0.0; 24];
            m[1] = 0.9;
            m
        };
        let mut t = [0.0; 24];
        t[0] = 0.5; // step: 0.5 -> 0.3
        t[1] = 1.5; // step window [0.6, 1.2] -> 1.2, limit -> 1.0
        t[2] = -0.2; // unchanged
        t[3] = -0.31; // step -> -0.3
        let (out, ev) = l.clamp(&t, &measured).unwrap();
        assert!((out[0] - 0.3).abs() < 1e-12);
        assert_eq!(out[1], 1.0);
        assert_eq!(out[2], -0.2);
        assert!((out[3] + 0.3).abs() < 1e-12);
        assert_eq!(ev.len(), 3);
        assert_eq!(ev[0].joint, "WRJ2");
        assert_eq!(ev[0].reason, ClampReason::MaxStep);
        assert_eq!(ev[1].joint, "WRJ1");
        assert_eq!(ev[1].reason, ClampReason::JointLimit);
        assert_eq!((ev[1].requested, ev[1].applied), (1.5, 1.0));
        assert_eq!(ev[2].joint, "FFJ3");
    }

    #[test]
    fn limits_win_when_measured_is_outside() {
        let l = SafetyLimiter::new(limits(), 0.3).unwrap();
        let mut m = [0.0; 24];
        m[5] = 1.4; // measured beyond the upper limit
        let mut t = [0.0; 24];
        t[5] = 1.4;
        let (out, ev) = l.clamp(&t, &m).unwrap();
        assert_eq!(out[5], 1.0);
        assert_eq!(ev[0].reason, ClampReason::JointLimit);
    }

    #[test]
    fn nan_target_is_rejected() {
        let l = SafetyLimiter::new(limits(), 0.3).unwrap();
        let mut t = [0.0; 24];
        t[23] = f64::NAN;
        let e = l.clamp(&t, &[0.0; 24]).unwrap_err().to_string();
        assert!(e.contains("targets[23] (THJ1)"), "{e}");
        assert!(SafetyLimiter::new(limits(), 0.0).is_err());
        let mut bad = limits();
        bad[4] = (1.0, -1.0);
        assert!(SafetyLimiter::new(bad, 0.3).is_err());
    }

    #[test]
    fn watchdog_with_fake_clock() {
        let mut w = Watchdog::new(0.1, 10.0).unwrap();
        assert!(w.check(10.1).is_ok());
        match w.check(10.15) {
            Err(HwError::Timeout { waited_s, .. }) => assert!((waited_s - 0.15).abs() < 1e-9),
            other => panic!("expected timeout, got {other:?}"),
        }
        w.feed(10.12);
        assert!(w.check(10.15).is_ok());
        w.feed(9.0); // older stamps are ignored
        assert_eq!(w.last_stamp(), 10.12);
        assert!(w.check(10.25).is_err());
        assert!(Watchdog::new(-1.0, 0.0).is_err());
    }
}
