//! Where the hand starts an episode, when not at the default top-down placement.
//!
//! By default an episode places the hand top-down over the object's centre, its grasp
//! point `grasp_depth` below the object's top (see [`crate::sim::Scene::top_down`]). A
//! [`PregraspPlanner`] replaces that with a planned grasp: after the object is placed
//! (at rest, in its episode pose), the planner sees the simulator and returns a grasp
//! point and a hand yaw, as `grasp run` plans one on a robot's depth cloud. The hand is
//! then placed there, raised clear of the object where it would overlap it, exactly as
//! the default placement is. Planners live above this layer (the antipodal one in
//! `crate::run::pregrasp`, which needs the point-cloud code); the environment only calls
//! them.

use crate::sim::HandSim;

/// A planned top-down hand placement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedGrasp {
    /// Grasp point (the TH/LF fingertip midpoint) in the world (m).
    pub grasp_point: [f64; 3],
    /// Direction of the thumb-to-little-finger line about world z (rad).
    pub hand_yaw: f64,
}

impl PlannedGrasp {
    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.grasp_point.iter().all(|v| v.is_finite()) && self.hand_yaw.is_finite()
    }
}

/// Plans the hand's start for an episode from the simulator with the object placed.
pub trait PregraspPlanner: Send {
    /// The placement for the episode of `seed` (the same seed gives the same plan, so
    /// every agent starts a trial from the same pose), or `None` when the planner finds
    /// none (the episode then starts from the default placement).
    fn plan(&mut self, sim: &HandSim, seed: u64) -> Option<PlannedGrasp>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_with_nan_is_not_finite() {
        let ok = PlannedGrasp {
            grasp_point: [0.0, 0.1, 0.05],
            hand_yaw: 0.3,
        };
        assert!(ok.is_finite());
        assert!(!PlannedGrasp {
            hand_yaw: f64::NAN,
            ..ok
        }
        .is_finite());
        assert!(!PlannedGrasp {
            grasp_point: [0.0, f64::INFINITY, 0.0],
            ..ok
        }
        .is_finite());
    }
}
