//! Choosing among the planner's top pre-grasps by a trained critic (beyond the paper;
//! `grasp eval --pregrasp antipodal --rank-top K`).
//!
//! The antipodal planner scores two-finger grasps by geometry alone and the episode starts
//! from its best. [`RankedPregrasp`] looks at its `K` best distinct placements through a
//! policy's eyes instead: for each, the episode's stage 1 runs in a probe environment of
//! its own (the object exactly where the trial's scene put it,
//! [`GraspEnv::first_observation_at`]), and the policy's critic values the first
//! observation, the closure stage 1 reached there (joint angles, touch, torque levels).
//! The placement of the highest value starts the episode; ties keep the planner's order.
//! One ranker places every agent of an evaluation, scripted or learned, so all of them
//! still start each trial from the same pose.

use crate::env::grasp::GraspEnv;
use crate::perception::pregrasp::{AntipodalPregrasp, PlannedGrasp, PregraspPlanner};
use crate::ppo::LoadedPolicy;
use crate::sim::HandSim;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// Most placements a ranker may compare (`--rank-top`).
pub const MAX_RANK_TOP: usize = 10;

/// The critic's value of an episode's first observation: the observation normalised as
/// in training, the recurrent state zero, as at any episode's start.
pub fn first_value(critic: &LoadedPolicy, obs: &[f32]) -> candle_core::Result<f32> {
    let out = super::policy_step(critic, obs, true, None)?;
    out.value.flatten_all()?.get(0)?.to_scalar::<f32>()
}

/// The antipodal planner's `top` best placements, the critic's choice among them.
pub struct RankedPregrasp {
    base: AntipodalPregrasp,
    top: usize,
    probe: GraspEnv,
    critic: Arc<LoadedPolicy>,
    /// How often each place of the planner's order was chosen (index 0: its best), shared
    /// by one agent's workers.
    chosen: Arc<Vec<AtomicUsize>>,
}

impl RankedPregrasp {
    /// Ranks `base`'s `top` best placements (at most [`MAX_RANK_TOP`]) by `critic`'s
    /// value of the first observation in `probe`, an environment in the critic's own
    /// setup (observation layout, closing path) whose first object is the trial's.
    pub fn new(
        base: AntipodalPregrasp,
        top: usize,
        probe: GraspEnv,
        critic: Arc<LoadedPolicy>,
        chosen: Arc<Vec<AtomicUsize>>,
    ) -> RankedPregrasp {
        RankedPregrasp {
            base,
            top: top.clamp(1, MAX_RANK_TOP),
            probe,
            critic,
            chosen,
        }
    }

    /// An empty tally of the places chosen, one counter per place of `top`.
    pub fn tally(top: usize) -> Arc<Vec<AtomicUsize>> {
        Arc::new(
            (0..top.clamp(1, MAX_RANK_TOP))
                .map(|_| AtomicUsize::new(0))
                .collect(),
        )
    }

    /// The critic's value of `placement` on the object at rest in `sim`, or `None` where
    /// the probe's scene is refused, its stage 1 fails or the network does.
    fn value(&mut self, sim: &HandSim, placement: &PlannedGrasp) -> Option<f32> {
        let pose = sim.object_pose()?;
        let obs = self.probe.first_observation_at(&pose, placement).ok()?;
        if self.probe.sim().failure().is_some() {
            return None;
        }
        first_value(&self.critic, &obs)
            .ok()
            .filter(|v| v.is_finite())
    }
}

impl PregraspPlanner for RankedPregrasp {
    fn plan(&mut self, sim: &HandSim, seed: u64, avoid: &[PlannedGrasp]) -> Option<PlannedGrasp> {
        let candidates = self.base.candidates(sim, seed, avoid, self.top);
        let mut best: Option<(usize, f32)> = None;
        if candidates.len() > 1 {
            for (i, c) in candidates.iter().enumerate() {
                if let Some(v) = self.value(sim, c) {
                    if best.is_none_or(|(_, b)| v > b) {
                        best = Some((i, v));
                    }
                }
            }
        }
        let i = best.map_or(0, |b| b.0);
        let choice = candidates.get(i).copied()?;
        if let Some(n) = self.chosen.get(i) {
            n.fetch_add(1, Ordering::Relaxed);
        }
        Some(choice)
    }
}

/// The antipodal planner (or a critic's ranking of its top placements), counting the
/// episodes it placed and those it left at the default placement (shared by one agent's
/// workers).
pub struct CountedPregrasp {
    /// The planner.
    pub inner: Box<dyn PregraspPlanner>,
    /// Episodes placed by a plan, and left at the default placement (no plan).
    pub counts: Arc<[AtomicUsize; 2]>,
}

impl PregraspPlanner for CountedPregrasp {
    fn plan(&mut self, sim: &HandSim, seed: u64, avoid: &[PlannedGrasp]) -> Option<PlannedGrasp> {
        let p = self.inner.plan(sim, seed, avoid);
        self.counts[usize::from(p.is_none())].fetch_add(1, Ordering::Relaxed);
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::api::ActionSpec;
    use crate::policy::{build_policy, PolicyConfig};
    use crate::ppo::PpoConfig;
    use candle_core::{Device, Tensor};

    fn critic(zero_all_but_bias: Option<f32>) -> LoadedPolicy {
        let cfg = PolicyConfig {
            embed_dim: 8,
            gru_hidden: 6,
            ..PolicyConfig::default()
        };
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        let policy = build_policy(&cfg, 4, spec, 3).expect("policy");
        if let Some(b) = zero_all_but_bias {
            for (name, v) in policy.params().vars() {
                let fill = if name == "critic.bias" { b } else { 0.0 };
                v.set(&v.ones_like().unwrap().affine(0.0, fill as f64).unwrap())
                    .unwrap();
            }
        }
        LoadedPolicy {
            policy,
            obs_rms: None,
            config: PpoConfig::default(),
            obs_clip: 10.0,
        }
    }

    #[test]
    fn the_first_value_of_a_zero_network_is_its_critic_bias() {
        // Every weight and bias zero but the critic's bias b = 0.7: the embedding gives
        // tanh(0) = 0, the GRU's gates sigmoid(0) = 0.5 and candidate tanh(0) = 0, so
        // h = 0.5 * 0 + 0.5 * h0 = 0 from the zero start state, and V = w . h + b = 0.7
        // whatever the observation.
        let c = critic(Some(0.7));
        for obs in [[0.0f32; 4], [1.0, -2.0, 3.0, 0.5]] {
            let v = first_value(&c, &obs).expect("value");
            assert!((v - 0.7).abs() < 1e-6, "{v}");
        }
    }

    #[test]
    fn the_first_value_is_the_networks_value_at_an_episode_start() {
        // A randomly initialised network: the value of the sequence's first step, from the
        // zero state with the start flag set, as training computes it.
        let c = critic(None);
        let obs = [0.3f32, -0.1, 0.8, 0.0];
        let t = Tensor::from_vec(obs.to_vec(), (1, 1, 4), &Device::Cpu).unwrap();
        let starts = Tensor::ones((1, 1), candle_core::DType::F32, &Device::Cpu).unwrap();
        let out = c.policy.forward_seq(&t, &starts, None).unwrap();
        let want: Vec<f32> = out.value.flatten_all().unwrap().to_vec1().unwrap();
        assert_eq!(first_value(&c, &obs).unwrap(), want[0]);
        assert_eq!(MAX_RANK_TOP, 10);
        assert_eq!(RankedPregrasp::tally(3).len(), 3);
        assert_eq!(RankedPregrasp::tally(0).len(), 1);
        assert_eq!(RankedPregrasp::tally(50).len(), MAX_RANK_TOP);
    }
}
