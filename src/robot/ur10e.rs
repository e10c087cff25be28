//! UR10e kinematics from its DH parameters: forward kinematics of the flange (`tool0`) and
//! numerical inverse kinematics for a flange pose.
//!
//! The DH convention is the standard one: `T = prod_k Rz(q_k) Tz(d_k) Tx(a_k) Rx(alpha_k)`.
//! The base frame is the DH base (z up through the shoulder); the flange frame has z out of
//! the flange.

use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion, Vector3, Vector6};
use std::f64::consts::{FRAC_PI_2, PI};

/// Standard DH parameters of a 6-joint arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dh {
    /// Link offsets d (m).
    pub d: [f64; 6],
    /// Link lengths a (m).
    pub a: [f64; 6],
    /// Link twists alpha (rad).
    pub alpha: [f64; 6],
}

/// The UR10e's published DH parameters (ROBOT.md).
pub const UR10E: Dh = Dh {
    d: [0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655],
    a: [0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0],
    alpha: [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0],
};

/// Joint names, base to wrist.
pub const JOINT_NAMES: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

/// Position limit of every joint (+-2 pi).
pub const JOINT_LIMIT: f64 = 2.0 * PI;
/// Velocity limits (rad/s): 120 deg/s for the shoulder joints, 180 deg/s for the others.
pub const VELOCITY: [f64; 6] = [120.0 * PI / 180.0, 120.0 * PI / 180.0, PI, PI, PI, PI];
/// Effort limits (N m).
pub const EFFORT: [f64; 6] = [330.0, 330.0, 150.0, 56.0, 56.0, 56.0];

/// A comfortable "elbow up, wrist down" configuration, used as the default IK seed.
pub const HOME: [f64; 6] = [0.0, -1.2, 1.6, -1.97, -FRAC_PI_2, 0.0];

/// The transform of one DH row for joint angle `q`.
fn dh_row(dh: &Dh, k: usize, q: f64) -> Isometry3<f64> {
    let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q);
    let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), dh.alpha[k]);
    let t = rz * Vector3::new(dh.a[k], 0.0, dh.d[k]);
    Isometry3::from_parts(Translation3::from(t), rz * rx)
}

/// Poses of the DH frames 0..=6 in the base frame (frame 0 is the base, 6 the flange).
pub fn frames(dh: &Dh, q: &[f64; 6]) -> [Isometry3<f64>; 7] {
    let mut out = [Isometry3::identity(); 7];
    for (k, &qk) in q.iter().enumerate() {
        out[k + 1] = out[k] * dh_row(dh, k, qk);
    }
    out
}

/// Forward kinematics: the flange (`tool0`) pose in the base frame.
pub fn fk(q: &[f64; 6]) -> Isometry3<f64> {
    frames(&UR10E, q)[6]
}

/// Geometric Jacobian (linear velocity of the flange origin; angular velocity), base frame.
pub fn jacobian(dh: &Dh, q: &[f64; 6]) -> Matrix6<f64> {
    let f = frames(dh, q);
    let p = f[6].translation.vector;
    let mut j = Matrix6::zeros();
    for (k, fk) in f.iter().take(6).enumerate() {
        let z = fk.rotation * Vector3::z();
        let o = fk.translation.vector;
        let lin = z.cross(&(p - o));
        j.fixed_view_mut::<3, 1>(0, k).copy_from(&lin);
        j.fixed_view_mut::<3, 1>(3, k).copy_from(&z);
    }
    j
}

/// Error of inverse kinematics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    /// No solution within tolerance was found (unreachable pose or singular).
    #[error("no IK solution for the UR10e: best position error {position_error:.3e} m, orientation error {orientation_error:.3e} rad")]
    NoSolution {
        /// Best position error reached (m).
        position_error: f64,
        /// Best orientation error reached (rad).
        orientation_error: f64,
    },
    /// The target pose contains NaN or infinity.
    #[error("IK target pose is not finite")]
    NotFinite,
}

/// 6-D pose error (position; rotation vector) from `cur` to `target`, base frame.
fn pose_error(cur: &Isometry3<f64>, target: &Isometry3<f64>) -> Vector6<f64> {
    let dp = target.translation.vector - cur.translation.vector;
    let dr = (target.rotation * cur.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

fn wrap(q: f64) -> f64 {
    let mut x = (q + PI).rem_euclid(2.0 * PI) - PI;
    if x <= -PI {
        x += 2.0 * PI;
    }
    x
}

/// Damped least-squares Newton iterations from `seed`. Returns the joint angles and the
/// final (position, orientation) errors.
fn solve_from(target: &Isometry3<f64>, seed: &[f64; 6]) -> ([f64; 6], f64, f64) {
    let mut q = *seed;
    let lambda2 = 1e-6;
    for _ in 0..100 {
        let e = pose_error(&frames(&UR10E, &q)[6], target);
        if e.fixed_rows::<3>(0).norm() < 1e-12 && e.fixed_rows::<3>(3).norm() < 1e-12 {
            break;
        }
        let j = jacobian(&UR10E, &q);
        let jjt = j * j.transpose() + Matrix6::identity() * lambda2;
        let Some(y) = jjt.lu().solve(&e) else { break };
        let mut dq = j.transpose() * y;
        let n = dq.norm();
        if n > 0.5 {
            dq *= 0.5 / n;
        }
        for k in 0..6 {
            q[k] += dq[k];
        }
    }
    for v in &mut q {
        *v = wrap(*v);
    }
    let e = pose_error(&frames(&UR10E, &q)[6], target);
    (q, e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm())
}

/// Inverse kinematics for a flange pose: the solution closest to `near` (joint-space
/// distance) among the converged solutions from several seeds (`near` itself first, then
/// the eight elbow/shoulder/wrist branches around [`HOME`]). Converges to < 1e-9 m.
pub fn ik(target: &Isometry3<f64>, near: &[f64; 6]) -> Result<[f64; 6], IkError> {
    let finite = target.translation.vector.iter().all(|v| v.is_finite())
        && target.rotation.coords.iter().all(|v| v.is_finite());
    if !finite {
        return Err(IkError::NotFinite);
    }
    let mut seeds = vec![*near];
    for s0 in [0.0, PI] {
        for s1 in [1.0, -1.0] {
            for s4 in [1.0, -1.0] {
                let base = (target.translation.y).atan2(target.translation.x);
                seeds.push([
                    wrap(base + s0),
                    HOME[1] * s1,
                    HOME[2] * s1,
                    HOME[3],
                    HOME[4] * s4,
                    0.0,
                ]);
            }
        }
    }
    let mut best: Option<([f64; 6], f64)> = None;
    let mut best_err = (f64::INFINITY, f64::INFINITY);
    for seed in &seeds {
        let (q, ep, er) = solve_from(target, seed);
        if ep + er < best_err.0 + best_err.1 {
            best_err = (ep, er);
        }
        if ep < 1e-9 && er < 1e-9 {
            let dist: f64 = q.iter().zip(near).map(|(a, b)| wrap(a - b).powi(2)).sum();
            if best.is_none_or(|(_, d)| dist < d) {
                best = Some((q, dist));
            }
        }
    }
    best.map(|(q, _)| q).ok_or(IkError::NoSolution {
        position_error: best_err.0,
        orientation_error: best_err.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn zero_pose_hand_computed() {
        // All joints zero: the arm is stretched along -x. Flange at
        // x = a2 + a3 = -1.18425, y = -(d4 + d6) = -0.2907 (alpha4 = +pi/2, alpha5 = -pi/2
        // turn z4 to -y), z = d1 - d5 = 0.06085.
        let t = fk(&[0.0; 6]).translation.vector;
        assert!((t.x - (-1.18425)).abs() < 1e-12, "{t}");
        assert!((t.y - (-0.2907)).abs() < 1e-12, "{t}");
        assert!((t.z - 0.06085).abs() < 1e-12, "{t}");
    }

    #[test]
    fn fk_ik_round_trip_below_a_micrometre() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut solved = 0;
        for _ in 0..50 {
            let q: [f64; 6] = std::array::from_fn(|k| HOME[k] + rng.random_range(-0.6..0.6));
            let target = fk(&q);
            let sol = ik(&target, &HOME).expect("reachable pose");
            let back = fk(&sol);
            let ep = (back.translation.vector - target.translation.vector).norm();
            let er = back.rotation.angle_to(&target.rotation);
            assert!(ep < 1e-6, "position error {ep}");
            assert!(er < 1e-6, "orientation error {er}");
            solved += 1;
        }
        assert_eq!(solved, 50);
    }

    #[test]
    fn unreachable_pose_is_an_error() {
        let far = Isometry3::translation(3.0, 0.0, 0.5);
        assert!(matches!(ik(&far, &HOME), Err(IkError::NoSolution { .. })));
        let nan = Isometry3::translation(f64::NAN, 0.0, 0.5);
        assert_eq!(ik(&nan, &HOME), Err(IkError::NotFinite));
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let q = HOME;
        let j = jacobian(&UR10E, &q);
        let h = 1e-7;
        for k in 0..6 {
            let mut qp = q;
            qp[k] += h;
            let d = (fk(&qp).translation.vector - fk(&q).translation.vector) / h;
            for r in 0..3 {
                assert!((j[(r, k)] - d[r]).abs() < 1e-5);
            }
        }
    }
}
