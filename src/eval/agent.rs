//! The agents an evaluation runs: [`AgentSpec`] names one (a scripted baseline or a
//! checkpoint), [`PolicyAgent`] acts with a learned policy, one [`policy_step`] at a time.

use crate::env::api::Action;
use crate::env::grasp::Agent;
use crate::ppo::LoadedPolicy;
use candle_core::{Device, Tensor};
use rand::SeedableRng;
use std::path::Path;
use std::sync::Arc;

/// A learned policy acting in the grasping MDP: observations are normalised as in
/// training, the GRU state is carried across steps and reset at episode starts. Actions
/// are the distribution's mode (deterministic) unless `stochastic`, then sampled from a
/// seeded RNG.
pub struct PolicyAgent {
    policy: Arc<LoadedPolicy>,
    hidden: Option<Tensor>,
    first: bool,
    stochastic: bool,
    rng: rand_chacha::ChaCha8Rng,
}

impl PolicyAgent {
    /// Wraps a loaded checkpoint's network ([`crate::checkpoint::TrainedAgent::network`]).
    pub fn new(policy: Arc<LoadedPolicy>, stochastic: bool, seed: u64) -> Self {
        PolicyAgent {
            policy,
            hidden: None,
            first: true,
            stochastic,
            rng: rand_chacha::ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// The policy's obs_dim and number of continuous action components.
    pub fn dims(&self) -> (usize, usize) {
        let p = &self.policy.policy;
        (p.obs_dim(), p.action_spec().continuous)
    }

    /// The action for `obs`, or the network's error ([`Agent::act`] lifts instead).
    pub fn try_act(&mut self, obs: &[f32]) -> candle_core::Result<Action> {
        let out = policy_step(&self.policy, obs, self.first, self.hidden.as_ref())?;
        self.hidden = out.hidden;
        self.first = false;
        let a = if self.stochastic {
            out.dist.sample(&mut self.rng)?
        } else {
            out.dist.mode()?
        };
        Ok(Action {
            cont: a.cont,
            lift: a.rho.first().is_some_and(|&r| r > 0.5),
        })
    }
}

/// One step of `policy` on the raw observation `obs`: normalised as in training, with the
/// recurrent state `hidden` (zero when `None`), reset first where `start` (an episode's
/// first observation).
pub fn policy_step(
    policy: &LoadedPolicy,
    obs: &[f32],
    start: bool,
    hidden: Option<&Tensor>,
) -> candle_core::Result<crate::policy::PolicyOutput> {
    let err = |e: crate::policy::PolicyError| candle_core::Error::Msg(e.to_string());
    let x = policy.normalize(obs);
    let d = x.len();
    let t = Tensor::from_vec(x, (1, 1, d), &Device::Cpu)?;
    let s = Tensor::from_vec(vec![if start { 1.0f32 } else { 0.0 }], (1, 1), &Device::Cpu)?;
    let zero = match hidden {
        Some(_) => None,
        None => policy.policy.initial_state(1).map_err(err)?,
    };
    policy
        .policy
        .forward_seq(&t, &s, hidden.or(zero.as_ref()))
        .map_err(err)
}

impl Agent for PolicyAgent {
    fn reset(&mut self) {
        self.hidden = None;
        self.first = true;
    }

    fn act(&mut self, obs: &[f32]) -> Action {
        self.try_act(obs).unwrap_or_else(|e| {
            tracing::error!("policy failed ({e}); lifting to end the episode");
            Action {
                cont: vec![0.0; self.policy.policy.action_spec().continuous],
                lift: true,
            }
        })
    }
}

/// An agent as an evaluation runs it: which one ([`AgentSpec`]) and, for a checkpoint,
/// its loaded network ([`TrainedAgent::network`](crate::checkpoint::TrainedAgent::network)),
/// which every worker of the evaluation shares.
#[derive(Clone, Copy)]
pub struct EvalAgent<'a> {
    /// Which agent.
    pub spec: &'a AgentSpec,
    /// A checkpoint's network (`None` for the baselines).
    pub network: Option<&'a Arc<LoadedPolicy>>,
}

/// Which agent an evaluation runs.
#[derive(Debug, Clone, PartialEq)]
pub enum AgentSpec {
    /// Scripted baseline 1 (close all fingers).
    Baseline1,
    /// Scripted baseline 2 (FF, MF, RF stop at contact).
    Baseline2,
    /// A checkpoint folder of a trained policy, acting with its distribution's mode.
    Checkpoint(std::path::PathBuf),
    /// A checkpoint folder of a trained policy, acting with actions sampled from its
    /// distribution as in training (seeded per object, so runs are reproducible).
    Sampled(std::path::PathBuf),
}

impl AgentSpec {
    /// Display name for tables.
    pub fn label(&self) -> String {
        match self {
            AgentSpec::Baseline1 => "Baseline 1".into(),
            AgentSpec::Baseline2 => "Baseline 2".into(),
            AgentSpec::Checkpoint(p) => p.display().to_string(),
            AgentSpec::Sampled(p) => format!("{} (sampled)", p.display()),
        }
    }

    /// A checkpoint's agent: [`AgentSpec::Sampled`] when `stochastic`, else
    /// [`AgentSpec::Checkpoint`].
    pub fn learned(dir: std::path::PathBuf, stochastic: bool) -> AgentSpec {
        if stochastic {
            AgentSpec::Sampled(dir)
        } else {
            AgentSpec::Checkpoint(dir)
        }
    }

    /// The checkpoint folder of a learned agent.
    pub fn checkpoint(&self) -> Option<&Path> {
        match self {
            AgentSpec::Checkpoint(p) | AgentSpec::Sampled(p) => Some(p),
            AgentSpec::Baseline1 | AgentSpec::Baseline2 => None,
        }
    }
}
