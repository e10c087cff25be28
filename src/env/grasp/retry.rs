//! A second attempt after a failed lift (beyond the paper; `grasp eval --attempts`).
//!
//! On the robot a failed grasp is not the end of the object: the hand opens, the object
//! settles wherever the attempt left it, the camera sees it there and the planner chooses
//! a grasp again. [`GraspEnv::prepare_retry`] does the same in the simulator, with no
//! teleporting: the open hand stays where the lift left it while the physics runs until
//! the object lies still on the table, clear of the hand; the next reset then rebuilds the
//! world with the object exactly at that pose, still, and places the hand as any episode's
//! placement does (the planner on the new depth cloud, skipping the grasps this trial has
//! already tried, or top-down over the object's centre as it now lies).

use super::GraspEnv;
use crate::sim::settle::Unsettled;
use crate::sim::Scene;
use nalgebra::{Isometry3, Point3};
use std::time::Instant;

/// Why a trial gets no further attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, thiserror::Error)]
pub enum NoRetry {
    /// No attempt has ended yet.
    #[error("no attempt to retry")]
    NoAttempt,
    /// The attempt succeeded.
    #[error("the attempt succeeded")]
    Succeeded,
    /// The attempt, or the wait after it, ended in a physics failure.
    #[error("a physics failure")]
    PhysicsFailure,
    /// The object still moved, or still touched the hand, after
    /// [`crate::sim::settle::SETTLE_MAX_S`].
    #[error("the object did not come to rest clear of the hand")]
    NotAtRest,
    /// The object came to rest off the table top.
    #[error("the object left the table")]
    OffTable,
}

impl NoRetry {
    /// The reason's name in reports (snake case).
    pub fn name(self) -> &'static str {
        match self {
            NoRetry::NoAttempt => "no_attempt",
            NoRetry::Succeeded => "succeeded",
            NoRetry::PhysicsFailure => "physics_failure",
            NoRetry::NotAtRest => "not_at_rest",
            NoRetry::OffTable => "off_table",
        }
    }
}

/// Where the object lay when the trial was retried.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RetryStart {
    /// The object's pose at rest.
    pub pose: Isometry3<f64>,
    /// Its world bounding box then: lowest and highest corners.
    pub aabb: (Point3<f64>, Point3<f64>),
}

impl GraspEnv {
    /// Prepares the trial's next attempt after a failed one: opens the hand to the start
    /// posture where the attempt left it and lets the object settle on the table
    /// ([`crate::sim::HandSim::settle_object`]). The
    /// next reset (any seed) then keeps this object at that pose, plans the hand's
    /// placement on it again and avoids the grasps the trial already tried. An error says
    /// why there is no next attempt (the environment is then left as it was after the
    /// wait; the next reset starts a fresh scene).
    pub fn prepare_retry(&mut self) -> Result<(), NoRetry> {
        self.retry = None;
        let last = self.last.as_ref().ok_or(NoRetry::NoAttempt)?;
        if last.success {
            return Err(NoRetry::Succeeded);
        }
        if last.physics_failure || self.sim.failure().is_some() {
            return Err(NoRetry::PhysicsFailure);
        }
        let (t, before) = (Instant::now(), self.sim.physics_steps());
        let settled = self.sim.settle_object(&self.start);
        self.phases.reset.add(self.sim.physics_steps() - before, t);
        settled.map_err(|e| match e {
            Unsettled::PhysicsFailure => NoRetry::PhysicsFailure,
            Unsettled::NotAtRest => NoRetry::NotAtRest,
            Unsettled::OffTable => NoRetry::OffTable,
        })?;
        let (pose, aabb) = self
            .sim
            .object_pose()
            .zip(self.sim.object_aabb())
            .ok_or(NoRetry::PhysicsFailure)?;
        self.retry = Some(RetryStart { pose, aabb });
        Ok(())
    }

    /// The scene of a retry: the default placement top-down over the centre of the
    /// object's bounding box as it lies, `grasp_depth` below its top but never below its
    /// centre (as [`Scene::top_down`] for an object at rest upright).
    pub(super) fn retry_scene(&self, start: [f64; 24], r: &RetryStart) -> Scene {
        let (lo, hi) = r.aabb;
        let c = nalgebra::center(&lo, &hi);
        Scene {
            start,
            object_xy: [r.pose.translation.x, r.pose.translation.y],
            object_yaw: 0.0,
            grasp_point: [c.x, c.y, (hi.z - self.cfg.grasp_depth).max(c.z)],
            hand_yaw: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::api::{Action, Env};
    use crate::env::grasp::tests::env_on;
    use crate::env::grasp::{run_episode, Agent};
    use crate::sim::settle::{REST_SPEED, REST_SPIN};
    use crate::sim::ObjectSpec;

    /// Lifts at once, fingers as stage 1 left them.
    struct LiftNow(usize);

    impl Agent for LiftNow {
        fn reset(&mut self) {}
        fn act(&mut self, _obs: &[f32]) -> Action {
            Action {
                cont: vec![0.0; self.0],
                lift: true,
            }
        }
    }

    #[test]
    fn a_failed_lift_is_retried_from_where_the_object_came_to_rest() {
        // A slippery 6 cm box (friction 0.05, 0.5 kg) slides out of a hand that lifts at
        // once: the attempt fails and the box comes to rest on the table. The retry's
        // scene holds the box at exactly that pose, still, the hand top-down over its
        // centre and clear of it.
        let mut e = env_on(ObjectSpec::cuboid([0.03, 0.03, 0.03], 0.5, 0.05));
        assert_eq!(e.prepare_retry(), Err(NoRetry::NoAttempt));
        let n = e.action_spec().continuous;
        let first = run_episode(&mut e, &mut LiftNow(n), 11);
        assert!(!first.success && !first.physics_failure, "{first:?}");
        e.prepare_retry().expect("a retry");
        let rest = e.sim.object_pose().expect("pose");
        let (v, w) = e.sim.object_speed();
        assert!(v < REST_SPEED && w < REST_SPIN, "{v} {w}");
        assert_eq!(e.sim.hand_object_force(), 0.0);
        e.reset_scene(99).expect("retry scene");
        let now = e.sim.object_pose().expect("pose");
        assert!(
            (now.translation.vector - rest.translation.vector).norm() < 1e-6,
            "{now} against {rest}"
        );
        assert!(now.rotation.angle_to(&rest.rotation) < 1e-5);
        assert_eq!(e.sim.object_speed(), (0.0, 0.0));
        assert!(!e.sim.hand_overlaps_object());
        let palm = |e: &GraspEnv| e.sim.critic_geometry().expect("geometry").palm;
        let retried = palm(&e).translation.vector.xy() - rest.translation.vector.xy();
        // The next reset without a retry is a fresh scene (the box upright where the
        // scene puts it), the palm where it is over a box's centre at the same yaw.
        e.reset_scene(99).expect("fresh scene");
        assert!(e.sim.object_tilt() < 1e-6 && e.sim.object_speed() == (0.0, 0.0));
        let fresh = palm(&e).translation.vector.xy() - e.sim.object_position().xy();
        assert!(
            (retried - fresh).norm() < 0.005,
            "palm {retried} from the resting box's centre, {fresh} over a fresh one"
        );
    }

    #[test]
    fn a_won_trial_is_not_retried() {
        // Baseline 1's power grasp holds the default box.
        let mut e = env_on(ObjectSpec::default_box());
        assert!(e.run_baseline(false, 0).expect("baseline").success);
        assert_eq!(e.prepare_retry(), Err(NoRetry::Succeeded));
    }
}
