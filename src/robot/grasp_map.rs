//! The two-finger-to-hand grasp mapping of the paper (Sec. V-B).
//!
//! A two-finger grasp is a grasp point, an approach direction and a closing direction.
//! It is mapped to the Shadow hand as follows:
//! 1. the fingers take a preshape (the "C" shape, [`super::Posture::CShape`]);
//! 2. the grasp point is the midpoint between the thumb and little-finger tips;
//! 3. the approach direction (grasp x axis) is the inverse of the palm normal, i.e. the
//!    direction the palm faces (palm frame -y; the palm normal points out of the back of
//!    the hand);
//! 4. the grasp y axis joins the thumb tip to the little-finger tip;
//! 5. z = x cross y.
//!
//! The result is the pose of the palm (and of the hand's forearm root) in the world.

use super::model::Robot;
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A two-finger grasp in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoFingerGrasp {
    /// The point between the two fingers (m).
    pub center: Point3<f64>,
    /// Direction in which the gripper approaches the object (unit).
    pub approach: Vector3<f64>,
    /// Direction joining the two fingers (unit, orthogonal to `approach`).
    pub closing: Vector3<f64>,
}

/// Error of the grasp mapping.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GraspMapError {
    /// A vector is zero, not finite, or the two directions are parallel.
    #[error("degenerate grasp: {0}")]
    Degenerate(&'static str),
}

impl TwoFingerGrasp {
    /// A top-down grasp: approach straight down (-z), fingers joined along the
    /// horizontal direction at angle `yaw` from the world x axis.
    pub fn top_down(center: Point3<f64>, yaw: f64) -> Self {
        TwoFingerGrasp {
            center,
            approach: -Vector3::z(),
            closing: Vector3::new(yaw.cos(), yaw.sin(), 0.0),
        }
    }

    /// The grasp frame: x = approach, y = closing (orthogonalised), z = x cross y.
    pub fn frame(&self) -> Result<Isometry3<f64>, GraspMapError> {
        let rot = frame_from(self.approach, self.closing)?;
        if !self.center.coords.iter().all(|v| v.is_finite()) {
            return Err(GraspMapError::Degenerate("grasp centre is not finite"));
        }
        Ok(Isometry3::from_parts(
            Translation3::from(self.center.coords),
            rot,
        ))
    }
}

/// Rotation with x along `x` and y along the part of `y` orthogonal to x.
fn frame_from(x: Vector3<f64>, y: Vector3<f64>) -> Result<UnitQuaternion<f64>, GraspMapError> {
    if !(x.iter().chain(y.iter()).all(|v| v.is_finite())) {
        return Err(GraspMapError::Degenerate("direction is not finite"));
    }
    let xn = x
        .try_normalize(1e-9)
        .ok_or(GraspMapError::Degenerate("approach direction is zero"))?;
    if y.norm() < 1e-9 {
        return Err(GraspMapError::Degenerate(
            "closing direction is zero: give the direction the fingers close along",
        ));
    }
    let yo = y - xn * xn.dot(&y);
    let yn = yo.try_normalize(1e-6).ok_or(GraspMapError::Degenerate(
        "closing direction is parallel to the approach",
    ))?;
    let zn = xn.cross(&yn);
    let m = Matrix3::from_columns(&[xn, yn, zn]);
    Ok(UnitQuaternion::from_rotation_matrix(
        &Rotation3::from_matrix_unchecked(m),
    ))
}

/// The hand's grasp frame in the palm frame at hand posture `q` (24 joints, paper order):
/// origin at the TH-LF fingertip midpoint, x = the direction the palm faces (-y of the
/// palm), y from the thumb tip toward the little-finger tip.
pub fn hand_grasp_frame(robot: &Robot, q: &[f64; 24]) -> Result<Isometry3<f64>, GraspMapError> {
    let tips = robot.fingertips_palm(q);
    let (lf, th) = (tips[3], tips[4]);
    let mid = Point3::from((lf.coords + th.coords) / 2.0);
    let rot = frame_from(-Vector3::y(), lf - th)?;
    Ok(Isometry3::from_parts(Translation3::from(mid.coords), rot))
}

/// Palm pose in the world that realises `grasp` with the hand at posture `q`.
pub fn palm_pose_for(
    robot: &Robot,
    q: &[f64; 24],
    grasp: &TwoFingerGrasp,
) -> Result<Isometry3<f64>, GraspMapError> {
    Ok(grasp.frame()? * hand_grasp_frame(robot, q)?.inverse())
}

/// Pose of the hand's root link (the forearm) in the world that realises `grasp` with the
/// hand at posture `q` (the wrist angles in `q` are taken into account).
pub fn root_pose_for(
    robot: &Robot,
    q: &[f64; 24],
    grasp: &TwoFingerGrasp,
) -> Result<Isometry3<f64>, GraspMapError> {
    let palm_world = palm_pose_for(robot, q, grasp)?;
    let poses = robot.hand_fk_palm(q);
    // poses are in the palm frame; the root's pose in the palm frame is poses[root].
    Ok(palm_world * poses[robot.hand.forearm])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Posture, Side};

    #[test]
    fn top_down_grasp_puts_the_tip_midpoint_on_the_point_and_the_palm_down() {
        for side in [Side::Left, Side::Right] {
            let robot = Robot::builtin(side);
            let q = Posture::CShape.angles();
            let p = Point3::new(0.5, -0.2, 0.08);
            let g = TwoFingerGrasp::top_down(p, 0.3);
            let palm = palm_pose_for(&robot, &q, &g).unwrap();
            let tips = robot.fingertips_palm(&q);
            let lf = palm * tips[3];
            let th = palm * tips[4];
            let mid = Point3::from((lf.coords + th.coords) / 2.0);
            assert!((mid - p).norm() < 1e-12, "{side:?}: {mid}");
            // The palm faces down: palm -y maps to world -z.
            let facing = palm.rotation * -Vector3::y();
            assert!((facing - -Vector3::z()).norm() < 1e-12, "{facing}");
            // Thumb -> little finger, without its part along the approach (z), runs along
            // yaw 0.3.
            let mut d = lf - th;
            d.z = 0.0;
            let d = d.normalize();
            assert!((d.y.atan2(d.x) - 0.3).abs() < 1e-12);
            // The root pose is consistent with the palm pose through FK.
            let root = root_pose_for(&robot, &q, &g).unwrap();
            let palm_again = root * robot.hand_fk_palm(&q)[robot.hand.forearm].inverse();
            assert!((palm_again.translation.vector - palm.translation.vector).norm() < 1e-12);
        }
    }

    #[test]
    fn degenerate_grasps_are_errors() {
        let g = TwoFingerGrasp {
            center: Point3::origin(),
            approach: Vector3::z(),
            closing: Vector3::z() * 2.0,
        };
        assert!(g.frame().is_err());
        let g = TwoFingerGrasp {
            center: Point3::new(f64::NAN, 0.0, 0.0),
            approach: Vector3::z(),
            closing: Vector3::x(),
        };
        assert!(g.frame().is_err());
    }
}
