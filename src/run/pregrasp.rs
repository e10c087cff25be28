//! The pre-grasp of `grasp run` as an episode start (`grasp eval --pregrasp antipodal`):
//! the simulated depth cameras see the object where it rests ([`camera_cloud`]), the
//! antipodal sampler scores two-finger grasps on the cloud, and the best candidate within
//! `max_tilt_rad` of straight down, made exactly top-down, places the hand: its centre is
//! the grasp point (the TH/LF fingertip midpoint) and its closing direction the hand's
//! thumb-to-little-finger line. This is the choice `grasp run --backend sim` makes for a
//! cloud, less the UR10e's reachability check (every evaluation object lies within the
//! arm's reach).

use super::pipeline::snap_top_down;
use super::sim_backend::{camera_cloud, CameraConfig};
use crate::env::pregrasp::{PlannedGrasp, PregraspPlanner};
use crate::hardware::pointcloud::{grasp_candidates, AntipodalConfig};
use crate::sim::HandSim;

/// Antipodal pre-grasps on the simulated depth cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct AntipodalPregrasp {
    /// The depth cameras.
    pub cameras: CameraConfig,
    /// The sampler (its seed is replaced by the episode's).
    pub antipodal: AntipodalConfig,
    /// Largest tilt of a candidate's approach from straight down (rad).
    pub max_tilt_rad: f64,
    /// Most candidates tried, best score first.
    pub max_candidates: usize,
}

impl Default for AntipodalPregrasp {
    /// `grasp run --backend sim`'s settings: two cameras, the default sampler, top-down
    /// within 0.35 rad, the best 30 candidates.
    fn default() -> Self {
        let run = super::pipeline::PipelineConfig::default();
        AntipodalPregrasp {
            cameras: CameraConfig::default(),
            antipodal: run.antipodal,
            max_tilt_rad: run.max_tilt_rad,
            max_candidates: run.max_candidates,
        }
    }
}

impl PregraspPlanner for AntipodalPregrasp {
    fn plan(&mut self, sim: &HandSim, seed: u64) -> Option<PlannedGrasp> {
        let cloud = camera_cloud(sim, &self.cameras, seed).ok()?;
        let cfg = AntipodalConfig {
            seed,
            ..self.antipodal
        };
        let candidates = grasp_candidates(&cloud, &cfg).ok()?;
        candidates
            .iter()
            .take(self.max_candidates)
            .find_map(|c| snap_top_down(&c.grasp, self.max_tilt_rad))
            .map(|g| PlannedGrasp {
                grasp_point: g.center.into(),
                hand_yaw: g.closing.y.atan2(g.closing.x),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Posture, Robot, Side};
    use crate::sim::{ObjectSpec, Scene, SimConfig};

    #[test]
    fn a_long_box_is_grasped_across_its_narrow_width_near_its_centre() {
        // A 16 x 5 x 6 cm box (long along x) at rest at the origin, yawed by 0.4 rad: the
        // only antipodal pairs within the 11 cm opening are across its 5 cm width, so the
        // planned closing line lies within the friction cone (mu 0.5: 26.6 degrees) of the
        // box's y axis, (-sin 0.4, cos 0.4), up to sign, and the grasp point lies on the
        // box's footprint, below its 6 cm top.
        let robot = Robot::builtin(Side::Left);
        let obj = ObjectSpec::cuboid([0.08, 0.025, 0.03], 0.3, 0.8);
        let mut sim = HandSim::new(&robot, obj.clone(), SimConfig::default()).unwrap();
        let mut scene = Scene::above(&obj, Posture::Open.angles(), 0.2, 0.0);
        scene.object_yaw = 0.4;
        sim.reset(&scene).unwrap();
        let mut planner = AntipodalPregrasp::default();
        let a = planner.plan(&sim, 7).expect("a plan on a box");
        let b = planner.plan(&sim, 7).expect("a plan on a box");
        assert_eq!(a, b, "the same seed gives the same plan");
        let (s, c) = (0.4f64.sin(), 0.4f64.cos());
        let across = (a.hand_yaw.cos() * -s + a.hand_yaw.sin() * c).abs();
        assert!(
            across > (0.5f64).atan().cos(),
            "yaw {} against the box's y axis",
            a.hand_yaw
        );
        let [x, y, z] = a.grasp_point;
        // In the box's frame: |x'| within its half length, |y'| near the middle.
        let (xb, yb) = (c * x + s * y, -s * x + c * y);
        assert!(xb.abs() < 0.08 && yb.abs() < 0.015, "({xb}, {yb})");
        assert!(z > 0.0 && z < 0.06, "{z}");
    }
}
