//! The recurrent actor-critic: a Linear embedding with tanh, one GRU layer shared by the
//! actor and the critic, then the heads (the layout of CleanRL's `ppo_atari_lstm`, with a
//! GRU as in the paper).

use super::parts::{ActorHeads, Core, MlpCritic, NetShape};
use super::{ActorCritic, PolicyError, PolicyOutput, GAIN_CRITIC, GAIN_HIDDEN};
use candle_core::{DType, Device, Module, Tensor};
use candle_nn::rnn::{GRUConfig, GRUState, GRU, RNN};
use candle_nn::{Linear, VarBuilder};
use std::collections::HashMap;

/// A GRU actor-critic: `embed` (Linear + tanh) -> `gru` (one layer) -> `actor.mean`,
/// `actor.lift` and `critic`. The recurrent state is zeroed at every episode start.
#[derive(Debug)]
pub struct GruPolicy {
    core: Core,
    embed: Linear,
    gru: GRU,
    heads: ActorHeads,
    critic: Critic,
}

/// The GRU policy's value head: linear on the GRU state, or with an asymmetric critic a
/// two-layer tanh MLP on the GRU state and the critic-only observation values.
#[derive(Debug)]
enum Critic {
    Linear(Linear),
    Asymmetric(MlpCritic),
}

impl GruPolicy {
    /// Builds the network of `shape`, initialised from `seed`.
    pub fn new(shape: NetShape<'_>, seed: u64) -> Result<Self, PolicyError> {
        let NetShape { cfg, obs_dim, spec } = shape;
        let (mut p, mut rng) = shape.start(seed);
        let (e, h) = (cfg.embed_dim, cfg.gru_hidden);
        let actor_dim = obs_dim - cfg.critic_state;
        let embed = p.linear("embed", actor_dim, e, GAIN_HIDDEN, &mut rng)?;
        // The GRU's tensors, `gru.<name>` with the names candle's GRU looks up under the
        // prefix `gru`.
        let mut gru_ts = HashMap::new();
        for (name, data, shape) in [
            (
                "weight_ih_l0",
                super::init::orthogonal(3 * h, e, 1.0, &mut rng),
                [3 * h, e],
            ),
            (
                "weight_hh_l0",
                super::init::orthogonal(3 * h, h, 1.0, &mut rng),
                [3 * h, h],
            ),
        ] {
            let name = format!("gru.{name}");
            gru_ts.insert(name.clone(), p.add(&name, data, &shape)?);
        }
        for name in ["bias_ih_l0", "bias_hh_l0"] {
            let name = format!("gru.{name}");
            gru_ts.insert(name.clone(), p.add(&name, vec![0.0; 3 * h], &[3 * h])?);
        }
        let vb = VarBuilder::from_tensors(gru_ts, DType::F32, &Device::Cpu);
        let gru = candle_nn::rnn::gru(e, h, GRUConfig::default(), vb.pp("gru"))?;
        let heads = ActorHeads::new(&mut p, cfg, h, spec, &mut rng)?;
        let critic = if cfg.critic_state == 0 {
            Critic::Linear(p.linear("critic", h, 1, GAIN_CRITIC, &mut rng)?)
        } else {
            Critic::Asymmetric(MlpCritic::new(
                &mut p,
                h + cfg.critic_state,
                cfg.mlp_hidden,
                &mut rng,
            )?)
        };
        Ok(Self {
            core: Core::new(p, obs_dim, actor_dim, spec, h),
            embed,
            gru,
            heads,
            critic,
        })
    }
}

impl ActorCritic for GruPolicy {
    fn core(&self) -> &Core {
        &self.core
    }

    fn forward_seq(
        &self,
        obs: &Tensor,
        starts: &Tensor,
        h0: Option<&Tensor>,
    ) -> Result<PolicyOutput, PolicyError> {
        let (t, b, d) = obs.dims3()?;
        let (actor_dim, hidden) = (self.core.actor_dim(), self.core.hidden_dim());
        let flat = obs.reshape((t * b, d))?;
        let x = self
            .embed
            .forward(&flat.narrow(1, 0, actor_dim)?)?
            .tanh()?
            .reshape((t, b, ()))?;
        let keep = starts.affine(-1.0, 1.0)?.unsqueeze(2)?; // (T, B, 1)
        let mut h = match h0 {
            Some(h) => h.clone(),
            None => Tensor::zeros((b, hidden), DType::F32, &Device::Cpu)?,
        };
        let mut outs = Vec::with_capacity(t);
        for i in 0..t {
            let masked = h.broadcast_mul(&keep.get(i)?)?;
            h = self.gru.step(&x.get(i)?, &GRUState { h: masked })?.h;
            outs.push(h.clone());
        }
        let hs = Tensor::stack(&outs, 0)?.reshape((t * b, hidden))?;
        let dist = self.heads.dist(&hs)?;
        let value = match &self.critic {
            Critic::Linear(c) => c.forward(&hs)?.squeeze(1)?,
            Critic::Asymmetric(c) => {
                let extra = flat.narrow(1, actor_dim, d - actor_dim)?;
                c.value(&Tensor::cat(&[&hs, &extra], 1)?)?
            }
        };
        Ok(PolicyOutput {
            dist,
            value,
            hidden: Some(h),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::api::ActionSpec;
    use crate::policy::PolicyConfig;
    use rand::Rng;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn policy() -> GruPolicy {
        let cfg = PolicyConfig {
            embed_dim: 8,
            gru_hidden: 6,
            ..PolicyConfig::default()
        };
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        GruPolicy::new(
            NetShape {
                cfg: &cfg,
                obs_dim: 3,
                spec,
            },
            11,
        )
        .unwrap()
    }

    fn rand_tensor(shape: &[usize], seed: u64) -> Tensor {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n: usize = shape.iter().product();
        let v: Vec<f32> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        Tensor::from_vec(v, shape, &Device::Cpu).unwrap()
    }

    fn rows(t: &Tensor) -> Vec<f32> {
        t.flatten_all().unwrap().to_vec1::<f32>().unwrap()
    }

    #[test]
    fn hidden_state_resets_at_episode_start() {
        let p = policy();
        let (t, b) = (4, 2);
        let obs = rand_tensor(&[t, b, 3], 1);
        let h0 = rand_tensor(&[b, 6], 2);
        // Env 0 starts a new episode at t = 2, env 1 at t = 0.
        let starts = Tensor::new(
            &[[0f32, 1.0], [0.0, 0.0], [1.0, 0.0], [0.0, 0.0]],
            &Device::Cpu,
        )
        .unwrap();
        let full = p.forward_seq(&obs, &starts, Some(&h0)).unwrap();
        let v_full = rows(&full.value);

        // Env 1 from t = 0: same as starting from a zero state, whatever h0 says.
        let obs1 = obs.narrow(1, 1, 1).unwrap();
        let zero_start = Tensor::zeros((t, 1), DType::F32, &Device::Cpu).unwrap();
        let fresh = p.forward_seq(&obs1, &zero_start, None).unwrap();
        let v1 = rows(&fresh.value);
        for i in 0..t {
            assert!((v_full[i * b + 1] - v1[i]).abs() < 1e-6, "t={i}");
        }
        // Env 0 at t >= 2 equals a fresh sequence started at t = 2.
        let obs0 = obs.narrow(0, 2, 2).unwrap().narrow(1, 0, 1).unwrap();
        let zs = Tensor::zeros((2, 1), DType::F32, &Device::Cpu).unwrap();
        let fresh0 = p.forward_seq(&obs0, &zs, None).unwrap();
        let v0 = rows(&fresh0.value);
        assert!((v_full[2 * b] - v0[0]).abs() < 1e-6);
        assert!((v_full[3 * b] - v0[1]).abs() < 1e-6);
        // ... but not before the reset: at t = 0 env 0 still used h0.
        let h0_0 = h0.narrow(0, 0, 1).unwrap();
        let no_reset = p.forward_seq(&obs0, &zs, Some(&h0_0)).unwrap();
        assert!((rows(&no_reset.value)[0] - v0[0]).abs() > 1e-6);
    }

    #[test]
    fn stepwise_equals_sequence() {
        let p = policy();
        let (t, b) = (3, 2);
        let obs = rand_tensor(&[t, b, 3], 5);
        let starts = Tensor::new(&[[1f32, 1.0], [0.0, 1.0], [0.0, 0.0]], &Device::Cpu).unwrap();
        let seq = p.forward_seq(&obs, &starts, None).unwrap();
        let mut h = p.initial_state(b).unwrap();
        let mut vals = Vec::new();
        let mut means = Vec::new();
        for i in 0..t {
            let o = obs.narrow(0, i, 1).unwrap();
            let s = starts.narrow(0, i, 1).unwrap();
            let out = p.forward_seq(&o, &s, h.as_ref()).unwrap();
            vals.extend(rows(&out.value));
            means.extend(rows(&out.dist.mean));
            h = out.hidden;
        }
        let sv = rows(&seq.value);
        let sm = rows(&seq.dist.mean);
        for (a, b) in sv.iter().zip(&vals).chain(sm.iter().zip(&means)) {
            assert!((a - b).abs() < 1e-6);
        }
        assert_eq!(seq.hidden.unwrap().dims(), &[2, 6]);
    }

    #[test]
    fn the_actor_ignores_the_critic_only_values_and_the_critic_reads_them() {
        let cfg = PolicyConfig {
            embed_dim: 8,
            gru_hidden: 6,
            mlp_hidden: 5,
            critic_state: 2,
            ..PolicyConfig::default()
        };
        let spec = ActionSpec {
            continuous: 2,
            lift: true,
        };
        let p = GruPolicy::new(
            NetShape {
                cfg: &cfg,
                obs_dim: 5,
                spec,
            },
            11,
        )
        .unwrap();
        assert_eq!(p.params().vars()["embed.weight"].dims(), &[8, 3]);
        assert_eq!(p.params().vars()["critic.fc1.weight"].dims(), &[5, 6 + 2]);
        let starts = Tensor::ones((1, 1), DType::F32, &Device::Cpu).unwrap();
        let run = |o: &[f32]| {
            let obs = Tensor::from_vec(o.to_vec(), (1, 1, 5), &Device::Cpu).unwrap();
            let out = p.forward_seq(&obs, &starts, None).unwrap();
            (rows(&out.dist.mean), rows(&out.value))
        };
        let (m1, v1) = run(&[0.1, -0.2, 0.3, 0.0, 0.0]);
        let (m2, v2) = run(&[0.1, -0.2, 0.3, 5.0, -5.0]);
        assert_eq!(m1, m2);
        assert_ne!(v1, v2);
        let e = crate::policy::build_policy(&cfg, 2, spec, 0).err().unwrap();
        assert!(e.to_string().contains("critic_state"), "{e}");
    }

    #[test]
    fn gradients_reach_every_parameter() {
        let p = policy();
        let obs = rand_tensor(&[2, 2, 3], 3);
        let starts = Tensor::zeros((2, 2), DType::F32, &Device::Cpu).unwrap();
        let out = p.forward_seq(&obs, &starts, None).unwrap();
        let cont = rand_tensor(&[4, 2], 4);
        let rho = Tensor::new(&[0f32, 1.0, 0.0, 0.0], &Device::Cpu).unwrap();
        let loss = (out
            .dist
            .log_prob(&cont, Some(&rho))
            .unwrap()
            .sum_all()
            .unwrap()
            + out.value.sum_all().unwrap())
        .unwrap();
        let grads = loss.backward().unwrap();
        for (name, v) in p.params().vars() {
            assert!(grads.get(v).is_some(), "no gradient for {name}");
        }
    }
}
