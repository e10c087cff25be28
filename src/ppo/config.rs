//! PPO hyperparameters, with CleanRL's defaults.

use super::PpoError;
use crate::policy::PolicyConfig;
use crate::util::num::short;
use std::path::Path;

/// Every hyperparameter of the learner. Deserialised from TOML with unknown keys rejected;
/// missing keys take the defaults below (CleanRL's `ppo_continuous_action` /
/// `ppo_atari_lstm`, and the paper's 20 environments).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {
    /// Master seed: network initialisation, action sampling, minibatch order and the
    /// environments' episode seeds all derive from it (1).
    pub seed: u64,
    /// Number of environments stepped in parallel (20, as in the paper).
    pub num_envs: usize,
    /// Threads of the environments' own pool (2). Does not change results.
    pub env_threads: usize,
    /// Total environment transitions the run is planned for; sets the learning-rate
    /// schedule (2_000_000, the paper's budget).
    pub total_timesteps: u64,
    /// Adam learning rate (3e-4).
    pub learning_rate: f64,
    /// Anneal the learning rate linearly to 0 over `total_timesteps` (true).
    pub anneal_lr: bool,
    /// Discount factor (0.99).
    pub gamma: f64,
    /// GAE lambda (0.95).
    pub gae_lambda: f64,
    /// Steps per environment per rollout (128).
    pub num_steps: usize,
    /// Minibatches per epoch (4). For a recurrent policy the environments are split into
    /// this many groups, so it must divide `num_envs`.
    pub num_minibatches: usize,
    /// Optimisation epochs per rollout (4).
    pub update_epochs: usize,
    /// Normalise advantages per minibatch (true).
    pub norm_adv: bool,
    /// Surrogate clipping coefficient (0.2).
    pub clip_coef: f64,
    /// Clip the value loss around the rollout's values (true).
    pub clip_vloss: bool,
    /// Entropy bonus coefficient (0.0).
    pub ent_coef: f64,
    /// Value loss coefficient (0.5).
    pub vf_coef: f64,
    /// Global gradient-norm clipping threshold (0.5).
    pub max_grad_norm: f64,
    /// Stop the epochs of an update early once the approximate KL exceeds this (none).
    pub target_kl: Option<f64>,
    /// Adam epsilon (1e-5). Adam has no weight decay here.
    pub adam_eps: f64,
    /// Normalise observations with running statistics (true).
    pub norm_obs: bool,
    /// Clip normalised observations to +-this (10).
    pub obs_clip: f64,
    /// Scale rewards by the running standard deviation of the discounted return, like
    /// gymnasium's `NormalizeReward` that CleanRL uses (true).
    pub norm_reward: bool,
    /// Clip scaled rewards to +-this (10).
    pub reward_clip: f64,
    /// The network.
    pub policy: PolicyConfig,
}

impl Default for PpoConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            num_envs: 20,
            env_threads: 2,
            total_timesteps: 2_000_000,
            learning_rate: 3e-4,
            anneal_lr: true,
            gamma: 0.99,
            gae_lambda: 0.95,
            num_steps: 128,
            num_minibatches: 4,
            update_epochs: 4,
            norm_adv: true,
            clip_coef: 0.2,
            clip_vloss: true,
            ent_coef: 0.0,
            vf_coef: 0.5,
            max_grad_norm: 0.5,
            target_kl: None,
            adam_eps: 1e-5,
            norm_obs: true,
            obs_clip: 10.0,
            norm_reward: true,
            reward_clip: 10.0,
            policy: PolicyConfig::default(),
        }
    }
}

/// The most bytes a rollout's buffers may take: 8 GiB.
pub const MAX_ROLLOUT_BYTES: u64 = 8 << 30;

/// The observation width assumed when bounding the rollout buffers without the
/// environment (the grasping observations are a few hundred values).
const ROLLOUT_OBS_ESTIMATE: u64 = 512;

impl PpoConfig {
    /// Loads a TOML config file (unknown keys are errors naming line and column).
    pub fn load(path: &Path) -> Result<Self, PpoError> {
        let cfg: Self = crate::util::config::load_toml(path)?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Transitions per rollout: `num_envs * num_steps`.
    pub fn batch_size(&self) -> usize {
        self.num_envs * self.num_steps
    }

    /// Number of updates in the planned run: `total_timesteps / batch_size` (at least 1).
    pub fn num_updates(&self) -> u64 {
        (self.total_timesteps / self.batch_size().max(1) as u64).max(1)
    }

    /// Refuses rollout buffers over [`MAX_ROLLOUT_BYTES`] for observations of `obs_len`
    /// values: each transition holds its observation, the recurrent state and a few
    /// scalars. `Err` says the sizes and the limit.
    pub fn check_rollout_bytes(&self, obs_len: u64) -> Result<(), String> {
        let per_transition = 4 * (obs_len + 2 * self.policy.gru_hidden as u64 + 16);
        let transitions = self.num_envs as u64 * self.num_steps as u64;
        let bytes = transitions.saturating_mul(per_transition);
        if bytes <= MAX_ROLLOUT_BYTES {
            return Ok(());
        }
        Err(format!(
            "num_envs = {} x num_steps = {} is {transitions} transitions per rollout of \
             {obs_len}-value observations, about {} GB of buffers (more than the limit of {} \
             GB); lower num_envs or num_steps",
            self.num_envs,
            self.num_steps,
            bytes >> 30,
            MAX_ROLLOUT_BYTES >> 30
        ))
    }

    /// Checks every field's range; the error names the field.
    pub fn validate(&self) -> Result<(), PpoError> {
        fn bad(field: &'static str, message: String) -> PpoError {
            PpoError::Config { field, message }
        }
        let count = |field: &'static str, v: usize, max: usize| {
            if v == 0 || v > max {
                Err(bad(field, format!("{v} must be in 1..={max}")))
            } else {
                Ok(())
            }
        };
        count("num_envs", self.num_envs, 4096)?;
        crate::util::threads::check(self.env_threads).map_err(|m| bad("env_threads", m))?;
        count("num_steps", self.num_steps, 1 << 20)?;
        count("num_minibatches", self.num_minibatches, 1 << 20)?;
        count("update_epochs", self.update_epochs, 1000)?;
        if self.total_timesteps == 0 {
            return Err(bad("total_timesteps", "must be positive".into()));
        }
        let real = |field: &'static str, v: f64, lo: f64, hi: f64, lo_open: bool| {
            let ok = v.is_finite() && v <= hi && if lo_open { v > lo } else { v >= lo };
            if ok {
                Ok(())
            } else {
                let open = if lo_open { "(" } else { "[" };
                let (v, lo, hi) = (short(v), short(lo), short(hi));
                Err(bad(field, format!("{v} must be in {open}{lo}, {hi}]")))
            }
        };
        real("learning_rate", self.learning_rate, 0.0, 1.0, true)?;
        real("gamma", self.gamma, 0.0, 1.0, false)?;
        real("gae_lambda", self.gae_lambda, 0.0, 1.0, false)?;
        real("clip_coef", self.clip_coef, 0.0, 10.0, true)?;
        real("ent_coef", self.ent_coef, 0.0, 100.0, false)?;
        real("vf_coef", self.vf_coef, 0.0, 100.0, false)?;
        real("max_grad_norm", self.max_grad_norm, 0.0, 1e6, true)?;
        real("adam_eps", self.adam_eps, 0.0, 1.0, true)?;
        real("obs_clip", self.obs_clip, 0.0, 1e6, true)?;
        real("reward_clip", self.reward_clip, 0.0, 1e6, true)?;
        if let Some(kl) = self.target_kl {
            real("target_kl", kl, 0.0, 1e6, true)?;
        }
        // Bounded before anything is allocated (the environment's observation width is
        // checked by the training config, which knows it).
        self.check_rollout_bytes(ROLLOUT_OBS_ESTIMATE)
            .map_err(|m| bad("num_steps", m))?;
        let mb = self.num_minibatches;
        if mb > self.batch_size() {
            return Err(bad(
                "num_minibatches",
                format!(
                    "{mb} exceeds the batch of {} transitions",
                    self.batch_size()
                ),
            ));
        }
        if self.policy.kind == crate::policy::PolicyKind::Gru && !self.num_envs.is_multiple_of(mb) {
            return Err(bad(
                "num_minibatches",
                format!(
                    "{mb} must divide num_envs = {} for the recurrent policy (minibatches \
                     are whole environment sequences)",
                    self.num_envs
                ),
            ));
        }
        self.policy.validate()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::config::parse_toml;

    #[test]
    fn defaults_are_cleanrl() {
        let c = PpoConfig::default();
        assert_eq!(c.learning_rate, 3e-4);
        assert_eq!((c.gamma, c.gae_lambda, c.clip_coef), (0.99, 0.95, 0.2));
        assert_eq!(
            (c.num_steps, c.num_minibatches, c.update_epochs),
            (128, 4, 4)
        );
        assert_eq!((c.vf_coef, c.ent_coef, c.max_grad_norm), (0.5, 0.0, 0.5));
        assert!(c.clip_vloss && c.norm_adv && c.anneal_lr && c.target_kl.is_none());
        assert_eq!(c.adam_eps, 1e-5);
        c.validate().unwrap();
    }

    #[test]
    fn toml_partial_unknown_and_out_of_range() {
        let p = Path::new("ppo.toml");
        let c: PpoConfig = parse_toml(
            p,
            "num_envs = 8\ntarget_kl = 0.02\n[policy]\nkind = \"mlp\"\n",
        )
        .unwrap();
        assert_eq!(c.num_envs, 8);
        assert_eq!(c.target_kl, Some(0.02));
        assert_eq!(c.policy.kind, crate::policy::PolicyKind::Mlp);
        assert_eq!(c.gamma, 0.99);
        let e = parse_toml::<PpoConfig>(p, "gama = 0.9\n").unwrap_err();
        assert!(e.to_string().contains("gama"), "{e}");
        let c: PpoConfig = parse_toml(p, "gamma = 1.5\n").unwrap();
        let e = c.validate().unwrap_err();
        assert!(e.to_string().contains("gamma"), "{e}");
        let c: PpoConfig = parse_toml(p, "num_envs = 6\nnum_minibatches = 4\n").unwrap();
        assert!(c.validate().unwrap_err().to_string().contains("divide"));
        let c: PpoConfig = parse_toml(p, "learning_rate = nan\n").unwrap();
        assert!(c.validate().is_err());
    }

    #[test]
    fn round_trips_through_json() {
        let c = PpoConfig {
            target_kl: Some(0.01),
            ..PpoConfig::default()
        };
        let s = serde_json::to_string(&c).unwrap();
        let d: PpoConfig = serde_json::from_str(&s).unwrap();
        assert_eq!(c, d);
    }
}
