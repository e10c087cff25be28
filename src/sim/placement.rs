//! Where the hand starts: the paper's grasp mapping (Sec. V-B) for a top-down grasp, as
//! implemented by [`crate::robot::grasp_map`].
//!
//! The palm faces world -z, the direction from the thumb tip to the little-finger tip (in
//! the start posture, without its part along the palm normal) is horizontal at a given
//! yaw, and the grasp point, the midpoint between the TH and LF fingertips, sits at a given
//! world point. This module only turns the simulator's scene numbers into a
//! [`TwoFingerGrasp::top_down`] and the palm pose into the pose of the simulated root link.

use crate::robot::grasp_map::{palm_pose_for, GraspMapError, TwoFingerGrasp};
use crate::robot::Robot;
use nalgebra::{Isometry3, Point3};

/// Error of an impossible placement.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlacementError {
    /// A number is NaN or infinite.
    #[error("placement: {what} is not finite")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The grasp mapping failed (e.g. the thumb and little-finger tips are aligned with
    /// the palm normal in the start posture).
    #[error("placement: {0}")]
    Mapping(#[from] GraspMapError),
}

/// Pose in the world of the robot's root link (the link the simulator attaches to its
/// lift) for a top-down grasp: palm facing world -z, thumb-to-little-finger direction
/// along `(cos yaw, sin yaw, 0)`, TH/LF tip midpoint at `grasp_point`, hand in posture
/// `start` (24 angles, paper order).
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
    if start.iter().any(|v| !v.is_finite()) {
        return Err(PlacementError::NotFinite {
            what: "start posture",
        });
    }
    let grasp = TwoFingerGrasp::top_down(*grasp_point, yaw);
    let palm = palm_pose_for(robot, start, &grasp)?;
    // The root link's pose in the palm frame (the forearm for the built-in hands).
    Ok(palm * robot.hand_fk_palm(start)[robot.root])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Posture, Side};
    use nalgebra::Vector3;

    #[test]
    fn placement_puts_the_grasp_point_and_axes_where_asked() {
        for side in [Side::Left, Side::Right] {
            let r = Robot::builtin(side);
            for (posture, yaw) in [
                (Posture::Open, 0.0),
                (Posture::CShape, 0.7),
                (Posture::Open, -2.0),
            ] {
                let q = posture.angles();
                let g = Point3::new(0.3, -0.1, 0.05);
                let pose = hand_root_pose(&r, &g, yaw, &q).unwrap();
                // Forward kinematics from the root, independent of the grasp mapping.
                let mut full = r.zero_q();
                r.set_hand_q(&mut full, &q);
                let poses = r.fk(&full);
                let root_inv = poses[r.root].inverse();
                let world = |link: usize| pose * root_inv * poses[link];
                let tip = |f: usize| Point3::from(world(r.hand.tips[f]).translation.vector);
                let (th, lf) = (tip(4), tip(3));
                // Grasp point lands on g.
                assert!(((th.coords + lf.coords) / 2.0 - g.coords).norm() < 1e-9);
                // Palm normal (palm -y) points down.
                let n = world(r.hand.palm).rotation * -Vector3::y();
                assert!((n - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-9, "{n}");
                // TH -> LF, without its vertical part, runs along the yaw.
                let mut d = lf - th;
                d.z = 0.0;
                let d = d.normalize();
                assert!(
                    (d - Vector3::new(yaw.cos(), yaw.sin(), 0.0)).norm() < 1e-9,
                    "{d}"
                );
            }
        }
    }

    #[test]
    fn nan_inputs_are_errors() {
        let r = Robot::builtin(Side::Left);
        let q = Posture::Open.angles();
        let g = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(hand_root_pose(&r, &g, 0.0, &q).is_err());
        assert!(hand_root_pose(&r, &Point3::origin(), f64::INFINITY, &q).is_err());
        let mut bad = q;
        bad[3] = f64::NAN;
        assert_eq!(
            hand_root_pose(&r, &Point3::origin(), 0.0, &bad),
            Err(PlacementError::NotFinite {
                what: "start posture"
            })
        );
    }
}
