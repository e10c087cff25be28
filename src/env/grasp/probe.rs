//! A look at a placement before choosing it: the first observation of an episode that
//! would start there (beyond the paper; `grasp eval --rank-top`).
//!
//! A ranker of pre-grasps (the critic of a trained policy) scores each of the planner's
//! top placements by what the policy would observe after stage 1 there: the joint angles
//! the closing stopped at, the fingertips touching and the torque levels. The object lies
//! exactly where the trial's scene put it (or where an earlier attempt left it), the hand
//! is placed as any episode's placement is (raised clear of the object where it would
//! overlap it), and stage 1 runs as in [`Env::reset`]. Nothing of the episode in progress
//! changes but the simulator's world, which the episode's own reset rebuilds.

use super::GraspEnv;
use crate::env::api::Env;
use crate::perception::pregrasp::PlannedGrasp;
use crate::sim::{HandSim, Scene, SimError};
use nalgebra::Isometry3;

impl GraspEnv {
    /// The observation after stage 1 of an episode whose object lies at `pose` (at rest,
    /// as the simulator that planned `placement` holds it) and whose hand starts at
    /// `placement`; the object is this environment's first one. Errors when the simulator
    /// refuses the scene; a physics failure in stage 1 gives the observation where it
    /// stopped.
    pub fn first_observation_at(
        &mut self,
        pose: &Isometry3<f64>,
        placement: &PlannedGrasp,
    ) -> Result<Vec<f32>, SimError> {
        if self.current_object != Some(0) {
            self.sim.set_object(self.objects[0].1.clone())?;
            self.current_object = Some(0);
        }
        self.episode_object = 0;
        let mut scene = Scene {
            start: self.path.start(),
            object_xy: [pose.translation.x, pose.translation.y],
            object_yaw: 0.0,
            grasp_point: placement.grasp_point,
            hand_yaw: placement.hand_yaw,
        };
        let reset = |sim: &mut HandSim, scene: &Scene| sim.reset_with_object_pose(scene, pose);
        reset(&mut self.sim, &scene)?;
        super::clear_hand(&mut self.sim, &mut scene, reset)?;
        self.stack.clear();
        self.steps = 0;
        self.episode_return = 0.0;
        self.lift_record = None;
        self.done = false;
        self.touched_in_stage1 = self.stage1();
        let zero = vec![0.0; self.action_spec().continuous];
        self.push_frame(&zero);
        Ok(self.observation())
    }
}

#[cfg(test)]
mod tests {
    use crate::env::api::Env;
    use crate::env::grasp::tests::env_on;
    use crate::perception::pregrasp::{PlannedGrasp, PregraspPlanner};
    use crate::sim::{HandSim, ObjectSpec};

    /// Plans 5 cm above the table over the object's centre, at yaw 0.3.
    struct OverObject;

    fn over(sim: &HandSim) -> PlannedGrasp {
        let c = sim.object_position();
        PlannedGrasp {
            grasp_point: [c.x, c.y, 0.05],
            hand_yaw: 0.3,
        }
    }

    impl PregraspPlanner for OverObject {
        fn plan(&mut self, sim: &HandSim, _: u64, _: &[PlannedGrasp]) -> Option<PlannedGrasp> {
            Some(over(sim))
        }
    }

    #[test]
    fn the_probe_sees_what_the_episode_would() {
        // The default box's episode of seed 3, planned over its centre. Probing that very
        // placement on the object's pose gives the episode's own first observation (the
        // same world, the same stage 1); a placement 3 cm off the box's axis stops stage 1
        // elsewhere, and the probe leaves no trace in the next episode.
        let mut e = env_on(ObjectSpec::default_box()).with_pregrasp(Box::new(OverObject));
        e.reset_scene(3).expect("scene");
        let pose = e.sim.object_pose().expect("pose");
        let here = over(&e.sim);
        let first = e.reset(3);
        let probed = e.first_observation_at(&pose, &here).expect("probe");
        assert_eq!(probed, first);
        let off = PlannedGrasp {
            grasp_point: [here.grasp_point[0] + 0.03, here.grasp_point[1], 0.05],
            ..here
        };
        assert_ne!(e.first_observation_at(&pose, &off).expect("probe"), first);
        assert_eq!(e.reset(3), first);
    }
}
