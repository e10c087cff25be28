//! Sensor models: the PD motor effort a joint reports and the per-step [`Sensors`]
//! reading. Efforts are mapped to the paper's six torque levels by
//! [`crate::util::levels::torque_level`].
//!
//! Units: efforts are N m (N for the lift). A torque reading in *sim units* is
//! `effort * torque_scale` (default 100 units per N m), so the paper's simulation
//! thresholds {-20, -10, 0, 10, 20} are {-0.2, -0.1, 0, 0.1, 0.2} N m.

use serde::Serialize;

/// The effort a position motor applies and reports (rapier gives no read-back):
/// `clamp(kp * (target - q) - kd * qdot, -effort, +effort)`.
///
/// A non-finite input gives a non-finite result only through `q`/`qdot`; `effort` must be
/// non-negative.
pub fn pd_effort(kp: f64, kd: f64, target: f64, q: f64, qdot: f64, effort: f64) -> f64 {
    (kp * (target - q) - kd * qdot).clamp(-effort, effort)
}

/// The rest point of an implicit joint spring of stiffness `kp` and damping `kd` that
/// applies [`pd_effort`] at the state (`q`, `qdot`): `kp (rest - q) - kd qdot` equals the
/// clamped effort. `kp` must be positive.
pub fn spring_rest(kp: f64, kd: f64, target: f64, q: f64, qdot: f64, effort: f64) -> f64 {
    q + (pd_effort(kp, kd, target, q, qdot, effort) + kd * qdot) / kp
}

/// Whether a joint at `q` moving at `qdot` is within `margin + |qdot| dt` of a bound of
/// `[lower, upper]`: only then does its limit become a solver row (`limit_rows = "near"`).
pub fn near_limit(q: f64, qdot: f64, lower: f64, upper: f64, margin: f64, dt: f64) -> bool {
    let reach = margin + qdot.abs() * dt;
    q - lower < reach || upper - q < reach
}

/// Everything the hand senses at one instant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sensors {
    /// Binary fingertip contact with the object (FF, MF, RF, LF, TH): the distal phalanx
    /// (with its tip) pushes on the object with a normal force above the threshold.
    pub tactile: [u8; 5],
    /// Normal contact force (N) on each distal phalanx from the object.
    pub tip_force: [f64; 5],
    /// Actuator efforts (N m), the 20 actuators in the paper's order (coupled J0 = the sum
    /// of the J1 and J2 efforts).
    pub effort: [f64; 20],
    /// Torque levels of the 20 actuators.
    pub torque_level: [u8; 20],
    /// The 24 hand joint angles (rad), paper order.
    pub q: [f64; 24],
    /// The 24 hand joint velocities (rad/s), paper order.
    pub qdot: [f64; 24],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spring_rest_applies_the_clamped_effort_hand_computed() {
        // Unclamped: 2 * (0.5 - 0.2) - 0.02 * 1.0 = 0.58 -> rest = 0.2 + (0.58 + 0.02) / 2
        // = 0.5, the target itself.
        assert!((spring_rest(2.0, 0.02, 0.5, 0.2, 1.0, 2.0) - 0.5).abs() < 1e-12);
        // Clamped: 2 * 1.5 = 3 > 2 -> rest = 0 + 2 / 2 = 1.0 (kp * 1.0 = the 2 N m limit).
        assert!((spring_rest(2.0, 0.0, 1.5, 0.0, 0.0, 2.0) - 1.0).abs() < 1e-12);
        // With damping, clamped: 2 * 1.5 - 0.1 * 2 = 2.8 -> 2; rest = (2 + 0.2) / 2 = 1.1,
        // so kp (rest - q) - kd qdot = 2.2 - 0.2 = 2.
        let r = spring_rest(2.0, 0.1, 1.5, 0.0, 2.0, 2.0);
        assert!((r - 1.1).abs() < 1e-12);
        assert!((2.0 * r - 0.1 * 2.0 - 2.0).abs() < 1e-12);
    }

    #[test]
    fn near_limit_hand_computed() {
        // 0.04 from the lower bound, margin 0.05: near.
        assert!(near_limit(0.04, 0.0, 0.0, 1.5, 0.05, 0.01));
        // 0.1 away at rest: not near; moving at 6 rad/s, one 0.01 s step adds 0.06 to the
        // reach (0.05 + 0.06 = 0.11 > 0.1): near.
        assert!(!near_limit(0.1, 0.0, 0.0, 1.5, 0.05, 0.01));
        assert!(near_limit(0.1, -6.0, 0.0, 1.5, 0.05, 0.01));
        // Near the upper bound.
        assert!(near_limit(1.47, 0.0, 0.0, 1.5, 0.05, 0.01));
    }

    #[test]
    fn pd_effort_hand_computed_and_clamped() {
        // 2 * (0.5 - 0.2) - 0.02 * 1.0 = 0.58
        assert!((pd_effort(2.0, 0.02, 0.5, 0.2, 1.0, 2.0) - 0.58).abs() < 1e-12);
        // 2 * (1.5 - 0) = 3 -> clamped to 2
        assert_eq!(pd_effort(2.0, 0.0, 1.5, 0.0, 0.0, 2.0), 2.0);
        // 2 * (-1.5) = -3 -> clamped to -1
        assert_eq!(pd_effort(2.0, 0.0, -1.5, 0.0, 0.0, 1.0), -1.0);
        // damping only: -0.1 * 3 = -0.3
        assert!((pd_effort(2.0, 0.1, 0.0, 0.0, 3.0, 2.0) + 0.3).abs() < 1e-12);
    }
}
