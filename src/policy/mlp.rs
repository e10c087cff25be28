//! The feed-forward actor-critic: separate two-layer tanh MLPs for the actor and the critic
//! (CleanRL's `ppo_continuous_action` agent).

use super::parts::{ActorHeads, Core, MlpCritic, NetShape, TanhMlp};
use super::{ActorCritic, PolicyError, PolicyOutput};
use candle_core::Tensor;

/// A feed-forward actor-critic with two tanh hidden layers in each of the actor and the
/// critic. It ignores episode starts and has no recurrent state.
#[derive(Debug)]
pub struct MlpPolicy {
    core: Core,
    actor: TanhMlp,
    heads: ActorHeads,
    critic: MlpCritic,
}

impl MlpPolicy {
    /// Builds the network of `shape`, initialised from `seed`.
    pub fn new(shape: NetShape<'_>, seed: u64) -> Result<Self, PolicyError> {
        let NetShape { cfg, obs_dim, spec } = shape;
        let (mut p, mut rng) = shape.start(seed);
        let h = cfg.mlp_hidden;
        // With an asymmetric critic the actor reads the observation without its last
        // `critic_state` values; the critic reads all of it.
        let actor_dim = obs_dim - cfg.critic_state;
        let actor = TanhMlp::new(&mut p, "actor", actor_dim, h, &mut rng)?;
        let heads = ActorHeads::new(&mut p, cfg, h, spec, &mut rng)?;
        let critic = MlpCritic::new(&mut p, obs_dim, h, &mut rng)?;
        Ok(Self {
            core: Core::new(p, obs_dim, actor_dim, spec, 0),
            actor,
            heads,
            critic,
        })
    }
}

impl ActorCritic for MlpPolicy {
    fn core(&self) -> &Core {
        &self.core
    }

    fn forward_seq(
        &self,
        obs: &Tensor,
        _starts: &Tensor,
        _h0: Option<&Tensor>,
    ) -> Result<PolicyOutput, PolicyError> {
        let (t, b, d) = obs.dims3()?;
        let x = obs.reshape((t * b, d))?;
        let a = self
            .actor
            .forward(&x.narrow(1, 0, self.core.actor_dim())?)?;
        Ok(PolicyOutput {
            dist: self.heads.dist(&a)?,
            value: self.critic.value(&x)?,
            hidden: None,
        })
    }
}
