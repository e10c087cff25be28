//! The layers both actor-critics are built from: what they are built for ([`NetShape`]),
//! what every network holds besides its layers ([`Core`]), the actor's heads ([`ActorHeads`]: the Gaussian's mean and log
//! standard deviation, the lift logit), two tanh layers ([`TanhMlp`]) and the MLP value
//! head ([`MlpCritic`]). Each adds its parameters under the names of the table in
//! [`super`], drawing its weights from the model's RNG in the order written here.

use super::{ActionDist, Params, PolicyConfig, GAIN_ACTOR, GAIN_CRITIC, GAIN_HIDDEN};
use crate::env::api::ActionSpec;
use candle_core::{Module, Tensor};
use candle_nn::Linear;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// What an actor-critic is built for: its config, the length of the observation it reads
/// and the shape of its actions.
#[derive(Debug, Clone, Copy)]
pub struct NetShape<'a> {
    /// The network's settings.
    pub cfg: &'a PolicyConfig,
    /// Observation length.
    pub obs_dim: usize,
    /// Action shape.
    pub spec: ActionSpec,
}

impl NetShape<'_> {
    /// The empty parameter table a network of this shape fills, and the stream seeded by
    /// `seed` that initialises its weights in the order they are added.
    pub(super) fn start(&self, seed: u64) -> (Params, ChaCha8Rng) {
        (Params::default(), ChaCha8Rng::seed_from_u64(seed))
    }
}

/// What every actor-critic holds besides its layers: its parameters by name, the length
/// of the observation it reads, how much of it the actor reads (the first values; the
/// rest only the critic), the shape of its actions and the size of its recurrent state.
#[derive(Debug)]
pub struct Core {
    params: Params,
    obs_dim: usize,
    actor_dim: usize,
    spec: ActionSpec,
    hidden: usize,
}

impl Core {
    /// The network's parameters `params` for observations of `obs_dim` values, of which
    /// the actor reads the first `actor_dim`, actions `spec` and a recurrent state of
    /// `hidden` values (0: feed-forward).
    pub(super) fn new(
        params: Params,
        obs_dim: usize,
        actor_dim: usize,
        spec: ActionSpec,
        hidden: usize,
    ) -> Self {
        Self {
            params,
            obs_dim,
            actor_dim,
            spec,
            hidden,
        }
    }

    /// The trainable parameters by name.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Length of the (stacked) observation vector.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// Observation values the actor reads (the first ones).
    pub fn actor_dim(&self) -> usize {
        self.actor_dim
    }

    /// The shape of the actions.
    pub fn action_spec(&self) -> ActionSpec {
        self.spec
    }

    /// Size of the recurrent state, 0 for a feed-forward network.
    pub fn hidden_dim(&self) -> usize {
        self.hidden
    }
}

/// Two tanh layers, `{name}.fc1` and `{name}.fc2`, `hidden` wide.
#[derive(Debug)]
pub(super) struct TanhMlp {
    fc1: Linear,
    fc2: Linear,
}

impl TanhMlp {
    /// Adds `{name}.fc1` (`inp` -> `hidden`) and `{name}.fc2` (`hidden` -> `hidden`).
    pub(super) fn new(
        p: &mut Params,
        name: &str,
        inp: usize,
        hidden: usize,
        rng: &mut ChaCha8Rng,
    ) -> candle_core::Result<Self> {
        Ok(Self {
            fc1: p.linear(&format!("{name}.fc1"), inp, hidden, GAIN_HIDDEN, rng)?,
            fc2: p.linear(&format!("{name}.fc2"), hidden, hidden, GAIN_HIDDEN, rng)?,
        })
    }

    /// `tanh(fc2(tanh(fc1(x))))`.
    pub(super) fn forward(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        self.fc2.forward(&self.fc1.forward(x)?.tanh()?)?.tanh()
    }
}

/// The actor's heads on its features: `actor.mean` (the Gaussian's mean), `actor.lift`
/// (the lift logit, when the action has a lift) and `actor.log_std` (one per continuous
/// component, independent of the state).
#[derive(Debug)]
pub(super) struct ActorHeads {
    mean: Linear,
    lift: Option<Linear>,
    log_std: Tensor,
}

impl ActorHeads {
    /// Adds the heads on `features` inputs for actions `spec`, with `cfg`'s initial lift
    /// bias and log standard deviation.
    pub(super) fn new(
        p: &mut Params,
        cfg: &PolicyConfig,
        features: usize,
        spec: ActionSpec,
        rng: &mut ChaCha8Rng,
    ) -> candle_core::Result<Self> {
        let c = spec.continuous;
        let mean = p.linear("actor.mean", features, c, GAIN_ACTOR, rng)?;
        let lift = if spec.lift {
            Some(p.linear_biased(
                "actor.lift",
                features,
                1,
                GAIN_ACTOR,
                cfg.init_lift_bias,
                rng,
            )?)
        } else {
            None
        };
        let log_std = p.add("actor.log_std", vec![cfg.init_log_std; c], &[c])?;
        Ok(Self {
            mean,
            lift,
            log_std,
        })
    }

    /// The action distribution of the actor's features `a`, shape (N, features).
    pub(super) fn dist(&self, a: &Tensor) -> candle_core::Result<ActionDist> {
        let mean = self.mean.forward(a)?;
        let lift_logit = match &self.lift {
            Some(l) => Some(l.forward(a)?.squeeze(1)?),
            None => None,
        };
        Ok(ActionDist {
            mean,
            log_std: self.log_std.clone(),
            lift_logit,
        })
    }
}

/// The MLP value head: [`TanhMlp`] `critic` (`critic.fc1`, `critic.fc2`), then the linear
/// `critic.out`.
#[derive(Debug)]
pub(super) struct MlpCritic {
    body: TanhMlp,
    out: Linear,
}

impl MlpCritic {
    /// Adds the head on `inp` inputs, `hidden` wide.
    pub(super) fn new(
        p: &mut Params,
        inp: usize,
        hidden: usize,
        rng: &mut ChaCha8Rng,
    ) -> candle_core::Result<Self> {
        Ok(Self {
            body: TanhMlp::new(p, "critic", inp, hidden, rng)?,
            out: p.linear("critic.out", hidden, 1, GAIN_CRITIC, rng)?,
        })
    }

    /// State values, shape (N), of inputs `x`, shape (N, inp).
    pub(super) fn value(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        self.out.forward(&self.body.forward(x)?)?.squeeze(1)
    }
}
