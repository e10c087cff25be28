//! Where an episode's time goes: the physics steps and the wall time a [`super::grasp::GraspEnv`]
//! spends in each phase of its episodes (placing the scene, stage 1's closing, the policy's
//! control steps, the lift and hold), summed over its episodes.

use serde::Serialize;
use std::time::Instant;

/// Physics steps and wall seconds spent in one phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Phase {
    /// Physics steps taken.
    pub physics_steps: u64,
    /// Wall seconds spent (on the thread that stepped the environment).
    pub wall_s: f64,
}

impl Phase {
    /// Counts `steps` physics steps and the time since `since`.
    pub fn add(&mut self, steps: u64, since: Instant) {
        self.physics_steps += steps;
        self.wall_s += since.elapsed().as_secs_f64();
    }

    /// The sum of two phases' figures.
    pub fn plus(self, o: Phase) -> Phase {
        Phase {
            physics_steps: self.physics_steps + o.physics_steps,
            wall_s: self.wall_s + o.wall_s,
        }
    }

    /// This phase's figures less `o`'s (never below zero).
    pub fn minus(self, o: Phase) -> Phase {
        Phase {
            physics_steps: self.physics_steps.saturating_sub(o.physics_steps),
            wall_s: (self.wall_s - o.wall_s).max(0.0),
        }
    }
}

/// The phases of grasping episodes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PhaseTally {
    /// Placing hand and object (no physics steps: the object is placed at rest).
    pub reset: Phase,
    /// Stage 1: the closing trajectory T until a fingertip touches (the baselines' whole
    /// closing and settle).
    pub closing: Phase,
    /// The policy's control steps (0.2 s of physics each), lift steps excluded.
    pub policy: Phase,
    /// The lift and hold that judge the grasp.
    pub lift: Phase,
}

impl PhaseTally {
    /// The phases with their names, in episode order.
    pub fn phases(&self) -> [(&'static str, Phase); 4] {
        [
            ("reset", self.reset),
            ("closing", self.closing),
            ("policy", self.policy),
            ("lift", self.lift),
        ]
    }

    /// All phases together.
    pub fn total(&self) -> Phase {
        self.phases()
            .iter()
            .fold(Phase::default(), |acc, (_, p)| acc.plus(*p))
    }

    /// The sum of two tallies (e.g. of several environments).
    pub fn plus(&self, o: &PhaseTally) -> PhaseTally {
        PhaseTally {
            reset: self.reset.plus(o.reset),
            closing: self.closing.plus(o.closing),
            policy: self.policy.plus(o.policy),
            lift: self.lift.plus(o.lift),
        }
    }

    /// What was added since `earlier` (a copy of this tally taken before).
    pub fn since(&self, earlier: &PhaseTally) -> PhaseTally {
        PhaseTally {
            reset: self.reset.minus(earlier.reset),
            closing: self.closing.minus(earlier.closing),
            policy: self.policy.minus(earlier.policy),
            lift: self.lift.minus(earlier.lift),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(steps: u64, s: f64) -> Phase {
        Phase {
            physics_steps: steps,
            wall_s: s,
        }
    }

    #[test]
    fn tallies_add_subtract_and_total() {
        let a = PhaseTally {
            reset: p(0, 0.5),
            closing: p(48, 1.0),
            policy: p(288, 6.0),
            lift: p(264, 5.0),
        };
        let b = PhaseTally {
            closing: p(12, 0.25),
            lift: p(100, 2.0),
            ..Default::default()
        };
        let sum = a.plus(&b);
        assert_eq!(sum.closing, p(60, 1.25));
        assert_eq!(sum.lift, p(364, 7.0));
        assert_eq!(sum.total(), p(712, 14.75));
        assert_eq!(sum.since(&b), a);
        assert_eq!(sum.since(&a), b);
        assert_eq!(
            sum.phases().map(|(n, _)| n),
            ["reset", "closing", "policy", "lift"]
        );
    }
}
