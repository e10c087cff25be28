//! Actor-critic policies on candle (CPU): a GRU policy and an MLP policy, their action
//! distribution (SPEC eq. 3) and orthogonal initialisation.
//!
//! Parameter names are stable and PyTorch-like so checkpoints can be read elsewhere:
//!
//! | policy | parameters |
//! |---|---|
//! | [`GruPolicy`] | `embed.{weight,bias}`, `gru.{weight_ih_l0,weight_hh_l0,bias_ih_l0,bias_hh_l0}`, `actor.mean.{weight,bias}`, `actor.log_std`, `actor.lift.{weight,bias}` (lift only), `critic.{weight,bias}` |
//! | [`MlpPolicy`] | `actor.fc1.*`, `actor.fc2.*`, `actor.mean.*`, `actor.log_std`, `actor.lift.*` (lift only), `critic.fc1.*`, `critic.fc2.*`, `critic.out.*` |
//!
//! Initialisation (CleanRL): orthogonal weights with gain sqrt(2) for hidden layers, 0.01
//! for the actor's mean and lift heads, 1.0 for the critic's output and the GRU, zero biases,
//! `actor.log_std` = `init_log_std`. All of it is drawn from one ChaCha8 RNG seeded by the
//! model seed, layer by layer in a fixed order.

pub mod dist;
mod gru;
pub mod init;
mod mlp;
mod parts;

pub use dist::{ActionDist, SampledActions};
pub use gru::GruPolicy;
pub use mlp::MlpPolicy;
pub use parts::{Core, NetShape};

use crate::env::api::ActionSpec;
use candle_core::{DType, Device, Tensor, Var};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// Errors while building or running a policy.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    /// A tensor operation failed.
    #[error("tensor operation failed: {0}")]
    Candle(#[from] candle_core::Error),
    /// A policy setting is out of range.
    #[error("invalid policy setting `{field}`: {message}")]
    Config {
        /// The offending field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
}

/// Which network the policy uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PolicyKind {
    /// [`GruPolicy`]: Linear embedding + tanh, one GRU layer, actor and critic heads.
    Gru,
    /// [`MlpPolicy`]: separate 2-layer tanh MLPs for the actor and the critic.
    Mlp,
}

/// Architecture settings of a policy.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PolicyConfig {
    /// The network: "gru" (default) or "mlp".
    pub kind: PolicyKind,
    /// Width of the MLP's two hidden layers (64).
    pub mlp_hidden: usize,
    /// Width of the GRU policy's embedding layer (128).
    pub embed_dim: usize,
    /// Size of the GRU's hidden state (128).
    pub gru_hidden: usize,
    /// Initial log standard deviation of the Gaussian (0.0: std 1).
    pub init_log_std: f32,
    /// Initial bias of the lift logit (0.0: p(lift) = 0.5 at every step). A negative
    /// bias makes the untrained agent lift later (-2: p = 0.12, about 8 steps), so early
    /// episodes explore the closing motion instead of lifting after one or two steps.
    pub init_lift_bias: f32,
    /// Values at the end of the observation that only the critic reads (an asymmetric
    /// critic; 0: none). Set by the training config from `[env] critic_state`. With it,
    /// the critic is a two-layer tanh MLP (`mlp_hidden` wide) over the actor's features
    /// (the GRU state, or the observation the actor reads) and these values.
    pub critic_state: usize,
}

impl Default for PolicyConfig {
    fn default() -> Self {
        Self {
            kind: PolicyKind::Gru,
            mlp_hidden: 64,
            embed_dim: 128,
            gru_hidden: 128,
            init_log_std: 0.0,
            init_lift_bias: 0.0,
            critic_state: 0,
        }
    }
}

/// The most parameters a network may have (about 400 MB of `f32` weights, 1.6 GB with
/// gradients and Adam's two moments): far above any configured network (about 0.2
/// million with the defaults), far below what aborts the process.
pub const MAX_PARAMETERS: u64 = 100_000_000;

impl PolicyConfig {
    /// The network's parameter count without its input layer (whose width is the
    /// observation's): the hidden layers of the kind's actor and critic, in `u64` so that
    /// widths near their bounds do not overflow.
    pub fn parameter_estimate(&self) -> u64 {
        let (m, e, h) = (
            self.mlp_hidden as u64,
            self.embed_dim as u64,
            self.gru_hidden as u64,
        );
        match self.kind {
            // Two hidden layers for the actor and the critic, the heads.
            PolicyKind::Mlp => 2 * m * m + 64 * m,
            // The embedding feeds the GRU (three gates over input and state), the
            // critic's MLP reads the state.
            PolicyKind::Gru => 3 * (e * h + h * h) + h * m + m * m + 64 * (e + h + m),
        }
    }

    /// Checks the settings' ranges.
    pub fn validate(&self) -> Result<(), PolicyError> {
        let positive = |field: &'static str, v: usize| {
            if v == 0 || v > 65_536 {
                Err(PolicyError::Config {
                    field,
                    message: format!("{v} must be in 1..=65536"),
                })
            } else {
                Ok(())
            }
        };
        positive("mlp_hidden", self.mlp_hidden)?;
        positive("embed_dim", self.embed_dim)?;
        positive("gru_hidden", self.gru_hidden)?;
        let params = self.parameter_estimate();
        if params > MAX_PARAMETERS {
            return Err(PolicyError::Config {
                field: "embed_dim/gru_hidden/mlp_hidden",
                message: format!(
                    "embed_dim = {}, gru_hidden = {} and mlp_hidden = {} make a network of \
                     about {} million parameters, more than the limit of {} million (its \
                     weights, gradients and optimiser state would not fit in memory); make \
                     them smaller",
                    self.embed_dim,
                    self.gru_hidden,
                    self.mlp_hidden,
                    params / 1_000_000,
                    MAX_PARAMETERS / 1_000_000
                ),
            });
        }
        if !self.init_log_std.is_finite() || self.init_log_std.abs() > 20.0 {
            return Err(PolicyError::Config {
                field: "init_log_std",
                message: format!("{} must be finite and within [-20, 20]", self.init_log_std),
            });
        }
        if !self.init_lift_bias.is_finite() || self.init_lift_bias.abs() > 20.0 {
            return Err(PolicyError::Config {
                field: "init_lift_bias",
                message: format!(
                    "{} must be finite and within [-20, 20]",
                    self.init_lift_bias
                ),
            });
        }
        Ok(())
    }
}

/// The output of a policy over a batch of N = T * B observations (time-major).
#[derive(Debug, Clone)]
pub struct PolicyOutput {
    /// The action distribution.
    pub dist: ActionDist,
    /// State values, shape (N).
    pub value: Tensor,
    /// The recurrent state after the last time step, shape (B, hidden); `None` for a
    /// feed-forward policy.
    pub hidden: Option<Tensor>,
}

/// An actor-critic network.
pub trait ActorCritic: Send + Sync {
    /// Its parameters, observation length and action shape.
    fn core(&self) -> &Core;
    /// Length of the (stacked) observation vector it reads.
    fn obs_dim(&self) -> usize {
        self.core().obs_dim()
    }
    /// The shape of the actions it outputs.
    fn action_spec(&self) -> ActionSpec {
        self.core().action_spec()
    }
    /// Size of the recurrent state, 0 for a feed-forward network.
    fn hidden_dim(&self) -> usize {
        self.core().hidden_dim()
    }
    /// The trainable parameters by name.
    fn params(&self) -> &Params {
        self.core().params()
    }
    /// Runs the network over a sequence: `obs` (T, B, obs_dim), `starts` (T, B) with 1.0
    /// where an observation is the first of an episode (the recurrent state is zeroed
    /// there, `h = h * (1 - start)`, before the step), and the initial recurrent state `h0`
    /// (B, hidden) of a recurrent network. The outputs are flattened time-major: row
    /// `t * B + b`.
    fn forward_seq(
        &self,
        obs: &Tensor,
        starts: &Tensor,
        h0: Option<&Tensor>,
    ) -> Result<PolicyOutput, PolicyError>;

    /// A zero recurrent state for `batch` sequences (`None` when feed-forward).
    fn initial_state(&self, batch: usize) -> Result<Option<Tensor>, PolicyError> {
        let h = self.hidden_dim();
        if h == 0 {
            return Ok(None);
        }
        Ok(Some(Tensor::zeros((batch, h), DType::F32, &Device::Cpu)?))
    }
}

/// Builds the policy `cfg` describes for observations of length `obs_dim` and actions
/// `spec`, initialised from `seed`.
pub fn build_policy(
    cfg: &PolicyConfig,
    obs_dim: usize,
    spec: ActionSpec,
    seed: u64,
) -> Result<Box<dyn ActorCritic>, PolicyError> {
    cfg.validate()?;
    if obs_dim == 0 {
        return Err(PolicyError::Config {
            field: "obs_dim",
            message: "the observation is empty".into(),
        });
    }
    if cfg.critic_state >= obs_dim {
        return Err(PolicyError::Config {
            field: "critic_state",
            message: format!(
                "{} critic-only values leave nothing of an observation of {obs_dim} for the actor",
                cfg.critic_state
            ),
        });
    }
    if spec.continuous == 0 {
        return Err(PolicyError::Config {
            field: "action_spec.continuous",
            message: "the action needs at least one continuous component".into(),
        });
    }
    let shape = NetShape { cfg, obs_dim, spec };
    Ok(match cfg.kind {
        PolicyKind::Gru => Box::new(GruPolicy::new(shape, seed)?),
        PolicyKind::Mlp => Box::new(MlpPolicy::new(shape, seed)?),
    })
}

/// Named trainable parameters, sorted by name (the order in which they are saved, clipped
/// and optimised).
#[derive(Debug, Default)]
pub struct Params {
    vars: BTreeMap<String, Var>,
}

impl Params {
    /// The parameters by name.
    pub fn vars(&self) -> &BTreeMap<String, Var> {
        &self.vars
    }

    /// Total number of scalar parameters.
    pub fn count(&self) -> usize {
        self.vars.values().map(|v| v.elem_count()).sum()
    }

    /// Adds a parameter and returns its tensor (which tracks gradients).
    fn add(&mut self, name: &str, data: Vec<f32>, shape: &[usize]) -> candle_core::Result<Tensor> {
        let t = Tensor::from_vec(data, shape, &Device::Cpu)?;
        let v = Var::from_tensor(&t)?;
        let out = v.as_tensor().clone();
        self.vars.insert(name.to_string(), v);
        Ok(out)
    }

    /// Adds an orthogonally initialised `out x inp` Linear layer `name.{weight,bias}`.
    fn linear(
        &mut self,
        name: &str,
        inp: usize,
        out: usize,
        gain: f64,
        rng: &mut ChaCha8Rng,
    ) -> candle_core::Result<candle_nn::Linear> {
        self.linear_biased(name, inp, out, gain, 0.0, rng)
    }

    /// Like [`Self::linear`] with every bias set to `bias`.
    fn linear_biased(
        &mut self,
        name: &str,
        inp: usize,
        out: usize,
        gain: f64,
        bias: f32,
        rng: &mut ChaCha8Rng,
    ) -> candle_core::Result<candle_nn::Linear> {
        let w = self.add(
            &format!("{name}.weight"),
            init::orthogonal(out, inp, gain, rng),
            &[out, inp],
        )?;
        let b = self.add(&format!("{name}.bias"), vec![bias; out], &[out])?;
        Ok(candle_nn::Linear::new(w, Some(b)))
    }
}

/// Gain sqrt(2) for hidden layers followed by tanh/ReLU.
pub(crate) const GAIN_HIDDEN: f64 = std::f64::consts::SQRT_2;
/// Gain for the actor's mean and lift heads.
pub(crate) const GAIN_ACTOR: f64 = 0.01;
/// Gain for the critic's output.
pub(crate) const GAIN_CRITIC: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_pytorch_like_and_init_is_seeded() {
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        let g = build_policy(&PolicyConfig::default(), 6, spec, 1).unwrap();
        let names: Vec<&str> = g.params().vars().keys().map(|s| s.as_str()).collect();
        assert_eq!(
            names,
            vec![
                "actor.lift.bias",
                "actor.lift.weight",
                "actor.log_std",
                "actor.mean.bias",
                "actor.mean.weight",
                "critic.bias",
                "critic.weight",
                "embed.bias",
                "embed.weight",
                "gru.bias_hh_l0",
                "gru.bias_ih_l0",
                "gru.weight_hh_l0",
                "gru.weight_ih_l0",
            ]
        );
        assert_eq!(
            g.params().vars()["gru.weight_ih_l0"].dims(),
            &[3 * 128, 128]
        );
        let cfg = PolicyConfig {
            kind: PolicyKind::Mlp,
            ..PolicyConfig::default()
        };
        let m = build_policy(&cfg, 6, spec, 1).unwrap();
        assert!(m.params().vars().contains_key("critic.out.weight"));
        assert!(m.params().vars().contains_key("actor.fc2.weight"));
        let m2 = build_policy(&cfg, 6, spec, 1).unwrap();
        let m3 = build_policy(&cfg, 6, spec, 2).unwrap();
        let w = |p: &dyn ActorCritic| {
            p.params().vars()["actor.fc1.weight"]
                .flatten_all()
                .unwrap()
                .to_vec1::<f32>()
                .unwrap()
        };
        assert_eq!(w(m.as_ref()), w(m2.as_ref()));
        assert_ne!(w(m.as_ref()), w(m3.as_ref()));
    }

    /// A parameter's name, shape and a weighted sum of its values.
    type Fingerprint = (&'static str, Vec<usize>, f64);
    /// A network's label, its parameters' fingerprints and its outputs.
    type Pinned = (&'static str, Vec<Fingerprint>, [Vec<f32>; 4]);

    /// Every parameter's name and shape, and a weighted sum of its initial values: a
    /// change of a name, a shape or the order in which layers draw from the RNG shows.
    fn fingerprint(p: &dyn ActorCritic) -> Vec<(String, Vec<usize>, f64)> {
        p.params()
            .vars()
            .iter()
            .map(|(name, v)| {
                let vals = v.flatten_all().unwrap().to_vec1::<f32>().unwrap();
                let sum = vals
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| (i as f64 + 1.0) * f64::from(x))
                    .sum::<f64>();
                (name.clone(), v.dims().to_vec(), (sum * 1e6).round() / 1e6)
            })
            .collect()
    }

    #[test]
    fn names_shapes_and_initial_values_are_pinned() {
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        let small = PolicyConfig {
            mlp_hidden: 4,
            embed_dim: 5,
            gru_hidden: 3,
            ..PolicyConfig::default()
        };
        let gru = build_policy(&small, 6, spec, 7).unwrap();
        let asym = PolicyConfig {
            critic_state: 2,
            ..small.clone()
        };
        let gru_asym = build_policy(&asym, 6, spec, 7).unwrap();
        let mlp_cfg = PolicyConfig {
            kind: PolicyKind::Mlp,
            ..asym.clone()
        };
        let mlp = build_policy(&mlp_cfg, 6, spec, 7).unwrap();
        // As built on 2026-12-07, before the shared heads were factored out: every
        // parameter's fingerprint, then the value, mean, lift logit and log std of two
        // steps of one sequence.
        let expected: [Pinned; 3] = [
            (
                "gru",
                vec![
                    ("actor.lift.bias", vec![1], 0.0),
                    ("actor.lift.weight", vec![1, 3], -0.00814),
                    ("actor.log_std", vec![2], 0.0),
                    ("actor.mean.bias", vec![2], 0.0),
                    ("actor.mean.weight", vec![2, 3], -0.035705),
                    ("critic.bias", vec![1], 0.0),
                    ("critic.weight", vec![1, 3], -3.265579),
                    ("embed.bias", vec![5], 0.0),
                    ("embed.weight", vec![5, 6], -69.196265),
                    ("gru.bias_hh_l0", vec![9], 0.0),
                    ("gru.bias_ih_l0", vec![9], 0.0),
                    ("gru.weight_hh_l0", vec![9, 3], 59.133893),
                    ("gru.weight_ih_l0", vec![9, 5], -16.031253),
                ],
                [
                    vec![-0.17405862, -0.31241134],
                    vec![0.0005502603, -0.005244564, -0.00018074279, -0.0005290385],
                    vec![9.471923e-5, 0.0011741678],
                    vec![0.0, 0.0],
                ],
            ),
            (
                "gru_asym",
                vec![
                    ("actor.lift.bias", vec![1], 0.0),
                    ("actor.lift.weight", vec![1, 3], 0.037291),
                    ("actor.log_std", vec![2], 0.0),
                    ("actor.mean.bias", vec![2], 0.0),
                    ("actor.mean.weight", vec![2, 3], -0.021283),
                    ("critic.fc1.bias", vec![4], 0.0),
                    ("critic.fc1.weight", vec![4, 5], 34.845084),
                    ("critic.fc2.bias", vec![4], 0.0),
                    ("critic.fc2.weight", vec![4, 4], -2.569649),
                    ("critic.out.bias", vec![1], 0.0),
                    ("critic.out.weight", vec![1, 4], 3.309478),
                    ("embed.bias", vec![5], 0.0),
                    ("embed.weight", vec![5, 4], -48.637947),
                    ("gru.bias_hh_l0", vec![9], 0.0),
                    ("gru.bias_ih_l0", vec![9], 0.0),
                    ("gru.weight_hh_l0", vec![9, 3], 31.560289),
                    ("gru.weight_ih_l0", vec![9, 5], 36.823641),
                ],
                [
                    vec![0.40855882, -0.56749964],
                    vec![0.003205336, 0.001268339, -0.0007511589, -0.0021009208],
                    vec![0.0018625228, 0.00062666694],
                    vec![0.0, 0.0],
                ],
            ),
            (
                "mlp",
                vec![
                    ("actor.fc1.bias", vec![4], 0.0),
                    ("actor.fc1.weight", vec![4, 4], -38.477521),
                    ("actor.fc2.bias", vec![4], 0.0),
                    ("actor.fc2.weight", vec![4, 4], -26.49605),
                    ("actor.lift.bias", vec![1], 0.0),
                    ("actor.lift.weight", vec![1, 4], 0.042785),
                    ("actor.log_std", vec![2], 0.0),
                    ("actor.mean.bias", vec![2], 0.0),
                    ("actor.mean.weight", vec![2, 4], -0.108429),
                    ("critic.fc1.bias", vec![4], 0.0),
                    ("critic.fc1.weight", vec![4, 6], -15.844281),
                    ("critic.fc2.bias", vec![4], 0.0),
                    ("critic.fc2.weight", vec![4, 4], 14.327609),
                    ("critic.out.bias", vec![1], 0.0),
                    ("critic.out.weight", vec![1, 4], 0.988961),
                ],
                [
                    vec![-0.71734565, -0.055018336],
                    vec![-0.007408689, -0.0060944017, -0.0002728867, -0.009519849],
                    vec![0.007073329, 0.0016121143],
                    vec![0.0, 0.0],
                ],
            ),
        ];
        for (p, (label, params, outputs)) in [gru, gru_asym, mlp].iter().zip(expected) {
            let got = fingerprint(p.as_ref());
            let want: Vec<(String, Vec<usize>, f64)> = params
                .into_iter()
                .map(|(n, s, v)| (n.to_string(), s, v))
                .collect();
            assert_eq!(got, want, "{label}");
            let obs: Vec<f32> = (0..12).map(|i| (i as f32 * 0.37).sin()).collect();
            let obs = Tensor::from_vec(obs, (2, 1, 6), &Device::Cpu).unwrap();
            let starts = Tensor::new(&[[1f32], [0.0]], &Device::Cpu).unwrap();
            let out = p.forward_seq(&obs, &starts, None).unwrap();
            let v = |t: &Tensor| t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            let lift = v(out.dist.lift_logit.as_ref().unwrap());
            let got = [v(&out.value), v(&out.dist.mean), lift, v(&out.dist.log_std)];
            assert_eq!(got, outputs, "{label}");
        }
    }

    #[test]
    fn lift_bias_sets_the_initial_lift_probability() {
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        for kind in [PolicyKind::Gru, PolicyKind::Mlp] {
            let cfg = PolicyConfig {
                kind,
                init_lift_bias: -2.0,
                ..PolicyConfig::default()
            };
            let p = build_policy(&cfg, 6, spec, 3).unwrap();
            let b = p.params().vars()["actor.lift.bias"]
                .to_vec1::<f32>()
                .unwrap();
            assert_eq!(b, vec![-2.0]);
            // The lift weights have gain 0.01, so p(lift) = sigmoid(-2 + small) ~ 0.119.
            let obs = Tensor::ones((1, 1, 6), DType::F32, &Device::Cpu).unwrap();
            let starts = Tensor::ones((1, 1), DType::F32, &Device::Cpu).unwrap();
            let h = p.initial_state(1).unwrap();
            let out = p.forward_seq(&obs, &starts, h.as_ref()).unwrap();
            let logit = out.dist.lift_logit.unwrap().to_vec1::<f32>().unwrap()[0];
            let prob = 1.0 / (1.0 + (-logit).exp());
            assert!((prob - 0.1192).abs() < 0.01, "{kind:?}: p(lift) = {prob}");
        }
        let bad = PolicyConfig {
            init_lift_bias: f32::NAN,
            ..PolicyConfig::default()
        };
        let e = build_policy(&bad, 6, spec, 0).err().unwrap();
        assert!(e.to_string().contains("init_lift_bias"), "{e}");
    }

    #[test]
    fn bad_settings_are_errors() {
        let cfg = PolicyConfig {
            gru_hidden: 0,
            ..PolicyConfig::default()
        };
        let spec = ActionSpec {
            continuous: 1,
            lift: false,
        };
        let e = build_policy(&cfg, 3, spec, 0).err().unwrap();
        assert!(e.to_string().contains("gru_hidden"), "{e}");
        let e = build_policy(&PolicyConfig::default(), 0, spec, 0)
            .err()
            .unwrap();
        assert!(e.to_string().contains("obs_dim"), "{e}");
    }
}
