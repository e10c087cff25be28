//! Where the hand starts: the paper's grasp mapping (Sec. V-B) for a top-down grasp.
//!
//! The palm normal (palm -y) points to world -z, the direction from the thumb tip to the
//! little-finger tip (in the start posture, its component in the palm plane) is horizontal
//! at a given yaw, and the grasp point, the midpoint between the TH and LF fingertips, sits
//! at a given world point.

use crate::robot::Robot;
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Error of an impossible placement.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlacementError {
    /// A number is NaN or infinite.
    #[error("placement: {what} is not finite")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The thumb-to-little-finger direction is (nearly) along the palm normal.
    #[error("placement: the thumb and little-finger tips are aligned with the palm normal")]
    Degenerate,
}

/// The hand frames a placement is computed from (all in the robot's root frame).
#[derive(Debug, Clone, PartialEq)]
pub struct GraspFrame {
    /// Midpoint between the TH and LF fingertips.
    pub grasp_point: Point3<f64>,
    /// Unit palm normal (palm -y).
    pub palm_normal: Vector3<f64>,
    /// Unit direction from the TH tip to the LF tip, projected on the palm plane.
    pub across: Vector3<f64>,
}

/// The grasp frame of `robot` in posture `q` (24 hand angles, paper order), in the robot's
/// root (forearm) frame.
pub fn grasp_frame(robot: &Robot, q: &[f64; 24]) -> Result<GraspFrame, PlacementError> {
    if q.iter().any(|v| !v.is_finite()) {
        return Err(PlacementError::NotFinite {
            what: "start posture",
        });
    }
    let mut full = robot.zero_q();
    robot.set_hand_q(&mut full, q);
    let poses = robot.fk(&full);
    let tip = |f: usize| Point3::from(poses[robot.hand.tips[f]].translation.vector);
    let (th, lf) = (tip(4), tip(3));
    let n = poses[robot.hand.palm].rotation * Vector3::new(0.0, -1.0, 0.0);
    let d = lf - th;
    let d_perp = d - n * d.dot(&n);
    if d_perp.norm() < 1e-6 {
        return Err(PlacementError::Degenerate);
    }
    Ok(GraspFrame {
        grasp_point: Point3::from((th.coords + lf.coords) / 2.0),
        palm_normal: n,
        across: d_perp.normalize(),
    })
}

/// Pose of the robot's root (forearm) link in the world for a top-down grasp: palm normal
/// to world -z, thumb-to-little-finger direction to `(cos yaw, sin yaw, 0)`, grasp point
/// (TH/LF tip midpoint) at `grasp_point`.
pub fn hand_root_pose(
    robot: &Robot,
    grasp_point: &Point3<f64>,
    yaw: f64,
    start: &[f64; 24],
) -> Result<Isometry3<f64>, PlacementError> {
    if !grasp_point.coords.iter().all(|v| v.is_finite()) {
        return Err(PlacementError::NotFinite {
            what: "grasp point",
        });
    }
    if !yaw.is_finite() {
        return Err(PlacementError::NotFinite { what: "yaw" });
    }
    let f = grasp_frame(robot, start)?;
    let frame = |a: Vector3<f64>, b: Vector3<f64>| Matrix3::from_columns(&[a, b, a.cross(&b)]);
    let m_root = frame(f.palm_normal, f.across);
    let m_world = frame(
        Vector3::new(0.0, 0.0, -1.0),
        Vector3::new(yaw.cos(), yaw.sin(), 0.0),
    );
    let rot = Rotation3::from_matrix_unchecked(m_world * m_root.transpose());
    let rot = UnitQuaternion::from_rotation_matrix(&rot);
    let p = grasp_point.coords - rot * f.grasp_point.coords;
    Ok(Isometry3::from_parts(Translation3::from(p), rot))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Posture, Side};

    #[test]
    fn placement_puts_the_grasp_point_and_axes_where_asked() {
        let r = Robot::builtin(Side::Left);
        for (posture, yaw) in [
            (Posture::Open, 0.0),
            (Posture::CShape, 0.7),
            (Posture::Open, -2.0),
        ] {
            let q = posture.angles();
            let g = Point3::new(0.3, -0.1, 0.05);
            let pose = hand_root_pose(&r, &g, yaw, &q).unwrap();
            let f = grasp_frame(&r, &q).unwrap();
            // Grasp point lands on g.
            assert!((pose * f.grasp_point - g).norm() < 1e-9);
            // Palm normal points down.
            assert!((pose.rotation * f.palm_normal - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-9);
            // Across direction horizontal at yaw.
            let a = pose.rotation * f.across;
            assert!(
                (a - Vector3::new(yaw.cos(), yaw.sin(), 0.0)).norm() < 1e-9,
                "{a}"
            );
            // The world tips agree: LF - TH has a positive component along the yaw direction.
            let mut full = r.zero_q();
            r.set_hand_q(&mut full, &q);
            let poses = r.fk(&full);
            let th = pose * Point3::from(poses[r.hand.tips[4]].translation.vector);
            let lf = pose * Point3::from(poses[r.hand.tips[3]].translation.vector);
            assert!(((th.coords + lf.coords) / 2.0 - g.coords).norm() < 1e-9);
            assert!((lf - th).dot(&Vector3::new(yaw.cos(), yaw.sin(), 0.0)) > 0.01);
        }
    }

    #[test]
    fn nan_inputs_are_errors() {
        let r = Robot::builtin(Side::Left);
        let q = Posture::Open.angles();
        let g = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(hand_root_pose(&r, &g, 0.0, &q).is_err());
        assert!(hand_root_pose(&r, &Point3::origin(), f64::INFINITY, &q).is_err());
    }
}
