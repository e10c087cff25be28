//! The feed-forward actor-critic: separate two-layer tanh MLPs for the actor and the critic
//! (CleanRL's `ppo_continuous_action` agent).

use super::{
    ActionDist, ActorCritic, Params, PolicyConfig, PolicyError, PolicyOutput, GAIN_ACTOR,
    GAIN_CRITIC, GAIN_HIDDEN,
};
use crate::env::api::ActionSpec;
use candle_core::{Module, Tensor};
use candle_nn::Linear;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A feed-forward actor-critic with two tanh hidden layers in each of the actor and the
/// critic. It ignores episode starts and has no recurrent state.
#[derive(Debug)]
pub struct MlpPolicy {
    params: Params,
    obs_dim: usize,
    actor_dim: usize,
    spec: ActionSpec,
    actor_fc1: Linear,
    actor_fc2: Linear,
    actor_mean: Linear,
    actor_lift: Option<Linear>,
    log_std: Tensor,
    critic_fc1: Linear,
    critic_fc2: Linear,
    critic_out: Linear,
}

impl MlpPolicy {
    /// Builds the network for `obs_dim` inputs and actions `spec`, initialised from `seed`.
    pub fn new(
        cfg: &PolicyConfig,
        obs_dim: usize,
        spec: ActionSpec,
        seed: u64,
    ) -> Result<Self, PolicyError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut p = Params::default();
        let h = cfg.mlp_hidden;
        let c = spec.continuous;
        // With an asymmetric critic the actor reads the observation without its last
        // `critic_state` values; the critic reads all of it.
        let actor_dim = obs_dim - cfg.critic_state;
        let actor_fc1 = p.linear("actor.fc1", actor_dim, h, GAIN_HIDDEN, &mut rng)?;
        let actor_fc2 = p.linear("actor.fc2", h, h, GAIN_HIDDEN, &mut rng)?;
        let actor_mean = p.linear("actor.mean", h, c, GAIN_ACTOR, &mut rng)?;
        let actor_lift = if spec.lift {
            Some(p.linear_biased("actor.lift", h, 1, GAIN_ACTOR, cfg.init_lift_bias, &mut rng)?)
        } else {
            None
        };
        let log_std = p.add("actor.log_std", vec![cfg.init_log_std; c], &[c])?;
        let critic_fc1 = p.linear("critic.fc1", obs_dim, h, GAIN_HIDDEN, &mut rng)?;
        let critic_fc2 = p.linear("critic.fc2", h, h, GAIN_HIDDEN, &mut rng)?;
        let critic_out = p.linear("critic.out", h, 1, GAIN_CRITIC, &mut rng)?;
        Ok(Self {
            params: p,
            obs_dim,
            actor_dim,
            spec,
            actor_fc1,
            actor_fc2,
            actor_mean,
            actor_lift,
            log_std,
            critic_fc1,
            critic_fc2,
            critic_out,
        })
    }
}

impl ActorCritic for MlpPolicy {
    fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    fn action_spec(&self) -> ActionSpec {
        self.spec
    }

    fn hidden_dim(&self) -> usize {
        0
    }

    fn params(&self) -> &Params {
        &self.params
    }

    fn forward_seq(
        &self,
        obs: &Tensor,
        _starts: &Tensor,
        _h0: Option<&Tensor>,
    ) -> Result<PolicyOutput, PolicyError> {
        let (t, b, d) = obs.dims3()?;
        let x = obs.reshape((t * b, d))?;
        let xa = x.narrow(1, 0, self.actor_dim)?;
        let a = self
            .actor_fc2
            .forward(&self.actor_fc1.forward(&xa)?.tanh()?)?
            .tanh()?;
        let mean = self.actor_mean.forward(&a)?;
        let lift_logit = match &self.actor_lift {
            Some(l) => Some(l.forward(&a)?.squeeze(1)?),
            None => None,
        };
        let v = self
            .critic_fc2
            .forward(&self.critic_fc1.forward(&x)?.tanh()?)?
            .tanh()?;
        let value = self.critic_out.forward(&v)?.squeeze(1)?;
        Ok(PolicyOutput {
            dist: ActionDist {
                mean,
                log_std: self.log_std.clone(),
                lift_logit,
            },
            value,
            hidden: None,
        })
    }
}
