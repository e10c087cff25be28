//! The PPO training loop (Schulman et al. 2017), following CleanRL's `ppo_continuous_action`
//! for feed-forward policies and `ppo_atari_lstm` for recurrent ones.
//!
//! One [`Trainer::train_update`] collects `num_steps` steps from each of the `num_envs`
//! environments, computes GAE advantages ([`super::gae`]), and runs `update_epochs` epochs
//! of minibatch updates with the clipped surrogate objective, the (clipped) value loss and
//! the entropy bonus, global gradient-norm clipping and Adam.
//!
//! Recurrent details: the recurrent state is zeroed where an observation starts an episode
//! (`h = h * (1 - start)`), both while acting and while training; the state at the start of
//! the rollout is kept, and minibatches are whole environment sequences (the environments
//! are shuffled and split into `num_minibatches` groups, time kept in order), replayed from
//! that state. Feed-forward minibatches are shuffled transitions.
//!
//! Reproducibility: every random choice (initialisation, action noise, minibatch order,
//! episode seeds) comes from ChaCha8 generators derived from `PpoConfig::seed`, so the same
//! seed gives bitwise the same metrics on the same machine and thread count.

use super::buffer::RolloutBuffer;
use super::checkpoint::{self, RngState, TrainerState, CHECKPOINT_FILE};
use super::config::PpoConfig;
use super::gae::{compute_gae, GaeInput};
use super::normalize::{RewardScaler, RunningMeanStd};
use super::optim::{clip_factor, global_grad_norm, Adam};
use super::PpoError;
use crate::env::api::{Action, ActionSpec, Env, EpisodeRecord, VecEnv};
use crate::policy::{build_policy, ActorCritic, PolicyConfig};
use candle_core::{Device, Tensor};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What one update measured of its episodes and of its optimisation: the part of
/// [`UpdateMetrics`] that a run's `metrics.csv` records in its columns `success_rate` to
/// `explained_variance` (`crate::train::MetricsRow`). The default: no episode, all losses 0.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct UpdateStats {
    /// Fraction of the episodes that finished during the rollout reporting success
    /// (`None` when none reported).
    pub success_rate: Option<f64>,
    /// Mean raw return of those episodes (`None` when none finished).
    pub episode_return: Option<f64>,
    /// Mean length of those episodes.
    pub episode_length: Option<f64>,
    /// Clipped surrogate loss, mean over minibatches.
    pub policy_loss: f64,
    /// Value loss (with the 0.5 factor), mean over minibatches.
    pub value_loss: f64,
    /// Policy entropy, mean over minibatches.
    pub entropy: f64,
    /// Approximate KL `mean((ratio - 1) - log ratio)`, mean over minibatches.
    pub approx_kl: f64,
    /// Fraction of samples whose ratio left `[1 - clip, 1 + clip]`.
    pub clip_fraction: f64,
    /// `1 - Var(returns - values) / Var(returns)` over the rollout (`None` if Var = 0).
    pub explained_variance: Option<f64>,
}

/// What one update measured.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UpdateMetrics {
    /// Index of the update, from 1.
    pub update: u64,
    /// Environment transitions collected so far.
    pub global_step: u64,
    /// Learning rate used.
    pub learning_rate: f64,
    /// Episodes that finished during the rollout.
    pub episodes: usize,
    /// Episodes that ended in a physics failure.
    pub physics_failures: usize,
    /// The episodes' success, return and length, and the optimisation's losses.
    #[serde(flatten)]
    pub stats: UpdateStats,
    /// Gradient norm before clipping, mean over minibatches.
    pub grad_norm: f64,
    /// Epochs run (fewer than `update_epochs` when `target_kl` stopped them).
    pub epochs: usize,
    /// Seconds spent collecting the rollout.
    pub rollout_secs: f64,
    /// Seconds spent optimising.
    pub optimize_secs: f64,
    /// Transitions per second over the whole update.
    pub transitions_per_sec: f64,
}

/// A PPO learner bound to a vector of environments.
pub struct Trainer {
    cfg: PpoConfig,
    envs: VecEnv,
    policy: Box<dyn ActorCritic>,
    opt: Adam,
    obs_rms: RunningMeanStd,
    rew_scaler: RewardScaler,
    rng_act: ChaCha8Rng,
    rng_mb: ChaCha8Rng,
    next_obs: Vec<f32>,
    next_start: Vec<f32>,
    hidden: Option<Tensor>,
    update: u64,
    global_step: u64,
}

/// Derived seeds: one stream per purpose.
fn derive_seed(seed: u64, purpose: u64) -> u64 {
    crate::env::api::episode_seed(seed, usize::MAX - 7, purpose)
}
const SEED_INIT: u64 = 1;
const SEED_ACT: u64 = 2;
const SEED_MB: u64 = 3;
const SEED_ENV: u64 = 4;

impl Trainer {
    /// Validates `cfg`, wraps `envs` (exactly `cfg.num_envs` of them) and builds the policy.
    pub fn new(cfg: PpoConfig, envs: Vec<Box<dyn Env>>) -> Result<Self, PpoError> {
        cfg.validate()?;
        if envs.len() != cfg.num_envs {
            return Err(PpoError::Config {
                field: "num_envs",
                message: format!(
                    "{} configured but {} environments given",
                    cfg.num_envs,
                    envs.len()
                ),
            });
        }
        let envs = VecEnv::new(envs, cfg.env_threads, 0)?;
        let policy = build_policy(
            &cfg.policy,
            envs.obs_dim(),
            envs.action_spec(),
            derive_seed(cfg.seed, SEED_INIT),
        )?;
        let opt = Adam::new(policy.params(), cfg.learning_rate, cfg.adam_eps)?;
        let mut t = Self {
            obs_rms: RunningMeanStd::new(envs.obs_dim()),
            rew_scaler: RewardScaler::new(cfg.num_envs, cfg.gamma),
            rng_act: ChaCha8Rng::seed_from_u64(derive_seed(cfg.seed, SEED_ACT)),
            rng_mb: ChaCha8Rng::seed_from_u64(derive_seed(cfg.seed, SEED_MB)),
            next_obs: Vec::new(),
            next_start: Vec::new(),
            hidden: None,
            update: 0,
            global_step: 0,
            cfg,
            envs,
            policy,
            opt,
        };
        t.restart_envs(true)?;
        Ok(t)
    }

    /// Reads the config stored in the checkpoint in `dir`, builds a trainer with it around
    /// `envs` and restores the checkpoint.
    pub fn resume(dir: &Path, envs: Vec<Box<dyn Env>>) -> Result<Self, PpoError> {
        let cfg = checkpoint::read_checkpoint_config(dir)?;
        let mut t = Self::new(cfg, envs)?;
        t.load_checkpoint(dir)?;
        Ok(t)
    }

    /// Resets every environment with episode seeds derived from the seed and the current
    /// update index, clears the recurrent state and the reward accumulators. The first
    /// observations enter the normaliser's statistics when `update_stats`.
    fn restart_envs(&mut self, update_stats: bool) -> Result<(), PpoError> {
        let base =
            crate::env::api::episode_seed(derive_seed(self.cfg.seed, SEED_ENV), 0, self.update);
        let raw = self.envs.reset(base)?;
        self.envs.drain_finished();
        self.next_obs = self.observe(&raw, update_stats);
        self.next_start = vec![1.0; self.cfg.num_envs];
        self.hidden = self.policy.initial_state(self.cfg.num_envs)?;
        self.rew_scaler.acc.iter_mut().for_each(|a| *a = 0.0);
        Ok(())
    }

    /// Normalises raw observations (updating the statistics when `update_stats`).
    fn observe(&mut self, raw: &[f32], update_stats: bool) -> Vec<f32> {
        if !self.cfg.norm_obs {
            return raw.to_vec();
        }
        if update_stats {
            self.obs_rms.update(raw);
        }
        self.obs_rms.normalize(raw, self.cfg.obs_clip)
    }

    /// The configuration.
    pub fn config(&self) -> &PpoConfig {
        &self.cfg
    }

    /// The policy being trained.
    pub fn policy(&self) -> &dyn ActorCritic {
        self.policy.as_ref()
    }

    /// The running observation statistics (used only when `norm_obs`).
    pub fn obs_normalizer(&self) -> &RunningMeanStd {
        &self.obs_rms
    }

    /// Updates done so far.
    pub fn update_index(&self) -> u64 {
        self.update
    }

    /// Environment transitions collected so far.
    pub fn global_step(&self) -> u64 {
        self.global_step
    }

    /// The planned number of updates (`total_timesteps / batch_size`).
    pub fn num_updates(&self) -> u64 {
        self.cfg.num_updates()
    }

    /// The learning rate of update `update` (from 1): linearly annealed from
    /// `learning_rate` at update 1 towards 0 after `num_updates`, never negative.
    pub fn learning_rate_at(&self, update: u64) -> f64 {
        self.annealed((update.saturating_sub(1)) as f64)
    }

    /// The learning rate after `done` updates of the current batch size (fractional when
    /// earlier updates had another batch size), annealed as [`Trainer::learning_rate_at`].
    fn annealed(&self, done: f64) -> f64 {
        if !self.cfg.anneal_lr {
            return self.cfg.learning_rate;
        }
        let frac = 1.0 - done / self.cfg.num_updates() as f64;
        self.cfg.learning_rate * frac.max(0.0)
    }

    /// Whether another update is planned: the run's length is counted in transitions,
    /// so a run resumed with another `num_envs` or `num_steps` still stops at
    /// `total_timesteps` (the last whole update that does not pass it; a new run makes
    /// at least one update).
    pub fn wants_update(&self) -> bool {
        let batch = self.cfg.batch_size() as u64;
        self.update == 0 || self.global_step.saturating_add(batch) <= self.cfg.total_timesteps
    }

    /// The updates and transitions the run will have made when [`Trainer::wants_update`]
    /// turns false, counted from now.
    pub fn planned(&self) -> (u64, u64) {
        let batch = (self.cfg.batch_size() as u64).max(1);
        let mut more = self.cfg.total_timesteps.saturating_sub(self.global_step) / batch;
        if self.update == 0 {
            more = more.max(1);
        }
        (
            self.update + more,
            self.global_step.saturating_add(more.saturating_mul(batch)),
        )
    }

    /// Collects one rollout, then optimises the policy on it.
    pub fn train_update(&mut self) -> Result<UpdateMetrics, PpoError> {
        let t0 = Instant::now();
        self.update += 1;
        // Annealed by the transitions done, in updates of the current batch size: the
        // update index itself for a run that kept its batch size, and the right point of
        // the schedule for one resumed with another.
        let batch = self.cfg.batch_size().max(1) as f64;
        let lr = self.annealed(self.global_step as f64 / batch);
        self.opt.lr = lr;
        let buf = self.rollout()?;
        let episodes = self.envs.drain_finished();
        let rollout_secs = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let (adv, ret) = compute_gae(&GaeInput {
            num_envs: buf.num_envs,
            rewards: &buf.rewards,
            values: &buf.values,
            terminated: &buf.terminated,
            truncated: &buf.truncated,
            final_values: &buf.final_values,
            next_values: &buf.next_values,
            gamma: self.cfg.gamma,
            lambda: self.cfg.gae_lambda,
        });
        let stats = self.optimize(&buf, &adv, &ret)?;
        let optimize_secs = t1.elapsed().as_secs_f64();
        let total = t0.elapsed().as_secs_f64();
        Ok(self.metrics(
            lr,
            &buf,
            &ret,
            &episodes,
            stats,
            rollout_secs,
            optimize_secs,
            total,
        ))
    }

    #[allow(clippy::too_many_arguments)]
    fn metrics(
        &self,
        lr: f64,
        buf: &RolloutBuffer,
        ret: &[f32],
        episodes: &[EpisodeRecord],
        s: OptStats,
        rollout_secs: f64,
        optimize_secs: f64,
        total: f64,
    ) -> UpdateMetrics {
        let n_ep = episodes.len();
        let mean = |f: &dyn Fn(&EpisodeRecord) -> f64| {
            (n_ep > 0).then(|| episodes.iter().map(f).sum::<f64>() / n_ep as f64)
        };
        let with_success: Vec<bool> = episodes.iter().filter_map(|e| e.success).collect();
        let success_rate = (!with_success.is_empty()).then(|| {
            with_success.iter().filter(|&&s| s).count() as f64 / with_success.len() as f64
        });
        let k = s.minibatches.max(1) as f64;
        UpdateMetrics {
            update: self.update,
            global_step: self.global_step,
            learning_rate: lr,
            episodes: n_ep,
            physics_failures: episodes.iter().filter(|e| e.physics_failure).count(),
            stats: UpdateStats {
                success_rate,
                episode_return: mean(&|e| e.ret),
                episode_length: mean(&|e| e.length as f64),
                policy_loss: s.policy_loss / k,
                value_loss: s.value_loss / k,
                entropy: s.entropy / k,
                approx_kl: s.approx_kl / k,
                clip_fraction: s.clipped as f64 / s.samples.max(1) as f64,
                explained_variance: explained_variance(&buf.values, ret),
            },
            grad_norm: s.grad_norm / k,
            epochs: s.epochs,
            rollout_secs,
            optimize_secs,
            transitions_per_sec: buf.len() as f64 / total.max(1e-12),
        }
    }

    /// Collects `num_steps` steps from every environment.
    fn rollout(&mut self) -> Result<RolloutBuffer, PpoError> {
        let cpu = Device::Cpu;
        let (t_len, b) = (self.cfg.num_steps, self.cfg.num_envs);
        let d = self.envs.obs_dim();
        let spec: ActionSpec = self.envs.action_spec();
        let c = spec.continuous;
        let mut buf = RolloutBuffer::new(t_len, b, d, c);
        buf.initial_hidden = self.hidden.clone();
        for _ in 0..t_len {
            let obs_t = Tensor::from_slice(&self.next_obs, (1, b, d), &cpu)?;
            let st = Tensor::from_slice(&self.next_start, (1, b), &cpu)?;
            let out = self.policy.forward_seq(&obs_t, &st, self.hidden.as_ref())?;
            let s = out.dist.sample(&mut self.rng_act)?;
            let cont_t = Tensor::from_slice(&s.cont, (b, c), &cpu)?;
            let rho_t = if spec.lift {
                Some(Tensor::from_slice(&s.rho, b, &cpu)?)
            } else {
                None
            };
            let logp = out
                .dist
                .log_prob(&cont_t, rho_t.as_ref())?
                .to_vec1::<f32>()?;
            let values = out.value.to_vec1::<f32>()?;
            let h_new = out.hidden.map(|h| h.detach());
            buf.obs.extend_from_slice(&self.next_obs);
            buf.starts.extend_from_slice(&self.next_start);
            buf.cont.extend_from_slice(&s.cont);
            buf.rho.extend_from_slice(&s.rho);
            buf.log_probs.extend_from_slice(&logp);
            buf.values.extend_from_slice(&values);

            let actions: Vec<Action> = (0..b)
                .map(|i| Action {
                    cont: s.cont[i * c..(i + 1) * c].to_vec(),
                    lift: s.rho[i] > 0.5,
                })
                .collect();
            let vs = self.envs.step(&actions)?;
            self.global_step += b as u64;
            let ended: Vec<bool> = (0..b)
                .map(|i| vs.terminated[i] || vs.truncated[i])
                .collect();
            let mut rewards = vs.rewards.clone();
            if self.cfg.norm_reward {
                self.rew_scaler
                    .scale(&mut rewards, &ended, self.cfg.reward_clip);
            }
            let next_obs = self.observe(&vs.obs, true);

            // Bootstrap values of truncated episodes from their final observation, with the
            // recurrent state that observation would have been seen with. Physics failures
            // are not bootstrapped (their final value stays 0).
            let mut final_values = vec![0f32; b];
            let mut idx = Vec::new();
            let mut raw = Vec::new();
            for i in 0..b {
                if vs.truncated[i] && !vs.terminated[i] && !vs.infos[i].physics_failure {
                    if let Some(fo) = &vs.final_obs[i] {
                        idx.push(i as u32);
                        raw.extend_from_slice(fo);
                    }
                }
            }
            if !idx.is_empty() {
                let k = idx.len();
                let fo = self.observe(&raw, false);
                let fo_t = Tensor::from_vec(fo, (1, k, d), &cpu)?;
                let zs = Tensor::zeros((1, k), candle_core::DType::F32, &cpu)?;
                let h_sel = match &h_new {
                    Some(h) => Some(h.index_select(&Tensor::new(idx.as_slice(), &cpu)?, 0)?),
                    None => None,
                };
                let v = self
                    .policy
                    .forward_seq(&fo_t, &zs, h_sel.as_ref())?
                    .value
                    .to_vec1::<f32>()?;
                for (j, &i) in idx.iter().enumerate() {
                    final_values[i as usize] = v[j];
                }
            }
            buf.rewards.extend_from_slice(&rewards);
            buf.terminated.extend_from_slice(&vs.terminated);
            buf.truncated.extend_from_slice(&vs.truncated);
            buf.final_values.extend_from_slice(&final_values);
            self.next_obs = next_obs;
            self.next_start = ended.iter().map(|&e| if e { 1.0 } else { 0.0 }).collect();
            self.hidden = h_new;
        }
        let obs_t = Tensor::from_slice(&self.next_obs, (1, b, d), &cpu)?;
        let st = Tensor::from_slice(&self.next_start, (1, b), &cpu)?;
        buf.next_values = self
            .policy
            .forward_seq(&obs_t, &st, self.hidden.as_ref())?
            .value
            .to_vec1::<f32>()?;
        Ok(buf)
    }

    /// Runs the epochs of minibatch updates.
    fn optimize(
        &mut self,
        buf: &RolloutBuffer,
        adv: &[f32],
        ret: &[f32],
    ) -> Result<OptStats, PpoError> {
        let recurrent = self.policy.hidden_dim() > 0;
        let nmb = self.cfg.num_minibatches;
        let mut total = OptStats::default();
        for _ in 0..self.cfg.update_epochs {
            let mut epoch = OptStats::default();
            if recurrent {
                let mut envs: Vec<usize> = (0..buf.num_envs).collect();
                envs.shuffle(&mut self.rng_mb);
                for group in envs.chunks(buf.num_envs / nmb) {
                    let idx = buf.sequence_indices(group);
                    self.minibatch(buf, adv, ret, &idx, Some(group), &mut epoch)?;
                }
            } else {
                let mut all: Vec<usize> = (0..buf.len()).collect();
                all.shuffle(&mut self.rng_mb);
                for idx in all.chunks(buf.len().div_ceil(nmb)) {
                    self.minibatch(buf, adv, ret, idx, None, &mut epoch)?;
                }
            }
            let epoch_kl = epoch.approx_kl / epoch.minibatches.max(1) as f64;
            total.add(&epoch);
            total.epochs += 1;
            if let Some(target) = self.cfg.target_kl {
                if epoch_kl > target {
                    break;
                }
            }
        }
        Ok(total)
    }

    /// One gradient step on the transitions `idx` (time-major whole sequences of the
    /// environments `seq_envs` for a recurrent policy).
    fn minibatch(
        &mut self,
        buf: &RolloutBuffer,
        adv: &[f32],
        ret: &[f32],
        idx: &[usize],
        seq_envs: Option<&[usize]>,
        stats: &mut OptStats,
    ) -> Result<(), PpoError> {
        let cpu = Device::Cpu;
        let n = idx.len();
        let (d, c) = (buf.obs_dim, buf.act_dim);
        let obs = RolloutBuffer::gather(&buf.obs, d, idx);
        let out = match seq_envs {
            Some(envs) => {
                let tb = envs.len();
                let obs_t = Tensor::from_vec(obs, (buf.num_steps, tb, d), &cpu)?;
                let starts = Tensor::from_vec(
                    RolloutBuffer::gather(&buf.starts, 1, idx),
                    (buf.num_steps, tb),
                    &cpu,
                )?;
                let h0 = match &buf.initial_hidden {
                    Some(h) => {
                        let sel: Vec<u32> = envs.iter().map(|&e| e as u32).collect();
                        Some(h.index_select(&Tensor::new(sel.as_slice(), &cpu)?, 0)?)
                    }
                    None => None,
                };
                self.policy.forward_seq(&obs_t, &starts, h0.as_ref())?
            }
            None => {
                let obs_t = Tensor::from_vec(obs, (1, n, d), &cpu)?;
                let starts = Tensor::zeros((1, n), candle_core::DType::F32, &cpu)?;
                self.policy.forward_seq(&obs_t, &starts, None)?
            }
        };
        let cont = Tensor::from_vec(RolloutBuffer::gather(&buf.cont, c, idx), (n, c), &cpu)?;
        let rho = if self.policy.action_spec().lift {
            Some(Tensor::from_vec(
                RolloutBuffer::gather(&buf.rho, 1, idx),
                n,
                &cpu,
            )?)
        } else {
            None
        };
        let old_logp = Tensor::from_vec(RolloutBuffer::gather(&buf.log_probs, 1, idx), n, &cpu)?;
        let old_v = Tensor::from_vec(RolloutBuffer::gather(&buf.values, 1, idx), n, &cpu)?;
        let ret_t = Tensor::from_vec(RolloutBuffer::gather(ret, 1, idx), n, &cpu)?;
        let mut mb_adv = RolloutBuffer::gather(adv, 1, idx);
        if self.cfg.norm_adv && n > 1 {
            normalize_advantages(&mut mb_adv);
        }
        let adv_t = Tensor::from_vec(mb_adv, n, &cpu)?;

        let clip = self.cfg.clip_coef;
        let new_logp = out.dist.log_prob(&cont, rho.as_ref())?;
        let entropy = out.dist.entropy()?.mean_all()?;
        let logratio = (&new_logp - &old_logp)?;
        let ratio = logratio.exp()?;
        {
            let lr = logratio.to_vec1::<f32>()?;
            let r = ratio.to_vec1::<f32>()?;
            let kl: f64 = lr
                .iter()
                .zip(&r)
                .map(|(&l, &r)| f64::from(r - 1.0) - f64::from(l))
                .sum::<f64>()
                / n as f64;
            stats.approx_kl += kl;
            stats.clipped += r
                .iter()
                .filter(|&&r| (f64::from(r) - 1.0).abs() > clip)
                .count();
            stats.samples += n;
        }
        let neg_adv = adv_t.neg()?;
        let pg1 = (&neg_adv * &ratio)?;
        let pg2 = (&neg_adv * ratio.clamp(1.0 - clip, 1.0 + clip)?)?;
        let pg_loss = pg1.maximum(&pg2)?.mean_all()?;
        let new_v = &out.value;
        let v_unclipped = (new_v - &ret_t)?.sqr()?;
        let v_loss = if self.cfg.clip_vloss {
            let v_clipped = (&old_v + (new_v - &old_v)?.clamp(-clip, clip)?)?;
            let v_c = (v_clipped - &ret_t)?.sqr()?;
            (v_unclipped.maximum(&v_c)?.mean_all()? * 0.5)?
        } else {
            (v_unclipped.mean_all()? * 0.5)?
        };
        let loss = ((&pg_loss - (&entropy * self.cfg.ent_coef)?)? + (&v_loss * self.cfg.vf_coef)?)?;
        let grads = loss.backward()?;
        let norm = global_grad_norm(self.policy.params(), &grads)?;
        if !norm.is_finite() {
            return Err(PpoError::NonFinite {
                what: format!("gradient norm at update {}", self.update),
            });
        }
        self.opt
            .step(&grads, clip_factor(norm, self.cfg.max_grad_norm))?;
        stats.policy_loss += f64::from(pg_loss.to_scalar::<f32>()?);
        stats.value_loss += f64::from(v_loss.to_scalar::<f32>()?);
        stats.entropy += f64::from(entropy.to_scalar::<f32>()?);
        stats.grad_norm += norm;
        stats.minibatches += 1;
        Ok(())
    }

    /// Writes the checkpoint (weights, Adam moments and step, normaliser statistics, RNG
    /// states, counters and the config) atomically to `dir/checkpoint.safetensors` and
    /// returns that path.
    pub fn save_checkpoint(&self, dir: &Path) -> Result<PathBuf, PpoError> {
        let path = dir.join(CHECKPOINT_FILE);
        let state = TrainerState {
            format: checkpoint::FORMAT.to_string(),
            version: checkpoint::VERSION,
            config: self.cfg.clone(),
            obs_dim: self.envs.obs_dim(),
            action_spec: self.envs.action_spec(),
            update: self.update,
            global_step: self.global_step,
            adam_step: self.opt.step_count(),
            rng_act: RngState::capture(&self.rng_act),
            rng_mb: RngState::capture(&self.rng_mb),
        };
        let mut tensors = Vec::new();
        for (name, v) in self.policy.params().vars() {
            tensors.push(checkpoint::RawTensor::from_f32(name, v.as_tensor())?);
        }
        for (name, m, v) in self.opt.moments() {
            tensors.push(checkpoint::RawTensor::from_f32(
                &format!("{}{name}", checkpoint::EXP_AVG),
                m,
            )?);
            tensors.push(checkpoint::RawTensor::from_f32(
                &format!("{}{name}", checkpoint::EXP_AVG_SQ),
                v,
            )?);
        }
        tensors.extend(checkpoint::rms_tensors("obs_rms", &self.obs_rms));
        tensors.extend(checkpoint::rms_tensors("ret_rms", &self.rew_scaler.rms));
        checkpoint::write_checkpoint(&path, &state, &tensors)?;
        Ok(path)
    }

    /// Restores the checkpoint in `dir`: weights, Adam state, normalisers, RNG states and
    /// counters. The stored network and environment shapes must match this trainer's; the
    /// other hyperparameters of this trainer's config are kept. Everything is checked
    /// before anything is changed. The environments then restart with fresh episodes
    /// seeded from (seed, update index), so a resumed run is reproducible, though not
    /// bitwise identical to an uninterrupted one.
    pub fn load_checkpoint(&mut self, dir: &Path) -> Result<(), PpoError> {
        let path = dir.join(CHECKPOINT_FILE);
        let ck = checkpoint::read_checkpoint(&path)?;
        let st = &ck.state;
        let mismatch = |message: String| PpoError::CheckpointMismatch {
            path: path.clone(),
            message,
        };
        if st.config.policy != self.cfg.policy {
            return Err(mismatch(format!(
                "its network differs from this run's [policy]: {}",
                policy_differences(&st.config.policy, &self.cfg.policy)
            )));
        }
        if st.obs_dim != self.envs.obs_dim() || st.action_spec != self.envs.action_spec() {
            return Err(mismatch(format!(
                "it was trained with observations of length {} and {}, the environments \
                 have observations of length {} and {} (another modality, history or \
                 number of synergy components)",
                st.obs_dim,
                st.action_spec,
                self.envs.obs_dim(),
                self.envs.action_spec()
            )));
        }
        let weights = ck.policy_tensors(self.policy.params())?;
        let mut moments = Vec::new();
        for (name, v) in self.policy.params().vars() {
            let m = ck.f32_tensor(&format!("{}{name}", checkpoint::EXP_AVG), v.dims())?;
            let s = ck.f32_tensor(&format!("{}{name}", checkpoint::EXP_AVG_SQ), v.dims())?;
            moments.push((name.clone(), m, s));
        }
        let obs_rms = ck.rms("obs_rms", self.envs.obs_dim())?;
        let ret_rms = ck.rms("ret_rms", 1)?;
        let rng_act = st.rng_act.restore(&path)?;
        let rng_mb = st.rng_mb.restore(&path)?;
        // All checked: apply.
        for (name, v) in self.policy.params().vars() {
            if let Some(t) = weights.get(name) {
                v.set(t)?;
            }
        }
        for (name, m, s) in moments {
            self.opt.set_moments(&name, m, s);
        }
        self.opt.set_step_count(st.adam_step);
        self.obs_rms = obs_rms;
        self.rew_scaler.rms = ret_rms;
        self.rng_act = rng_act;
        self.rng_mb = rng_mb;
        self.update = st.update;
        self.global_step = st.global_step;
        self.restart_envs(false)
    }
}

/// Per-update accumulators.
#[derive(Debug, Default, Clone)]
struct OptStats {
    policy_loss: f64,
    value_loss: f64,
    entropy: f64,
    approx_kl: f64,
    grad_norm: f64,
    clipped: usize,
    samples: usize,
    minibatches: usize,
    epochs: usize,
}

impl OptStats {
    fn add(&mut self, o: &OptStats) {
        self.policy_loss += o.policy_loss;
        self.value_loss += o.value_loss;
        self.entropy += o.entropy;
        self.approx_kl += o.approx_kl;
        self.grad_norm += o.grad_norm;
        self.clipped += o.clipped;
        self.samples += o.samples;
        self.minibatches += o.minibatches;
    }
}

/// `(a - mean) / (std + 1e-8)` with the unbiased standard deviation (as PyTorch's `std`).
pub fn normalize_advantages(a: &mut [f32]) {
    let n = a.len();
    if n < 2 {
        return;
    }
    let mean = a.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
    let var = a
        .iter()
        .map(|&x| (f64::from(x) - mean).powi(2))
        .sum::<f64>()
        / (n - 1) as f64;
    let std = var.sqrt();
    for x in a.iter_mut() {
        *x = ((f64::from(*x) - mean) / (std + 1e-8)) as f32;
    }
}

/// `1 - Var(y - y_pred) / Var(y)`, `None` when Var(y) = 0.
pub fn explained_variance(y_pred: &[f32], y: &[f32]) -> Option<f64> {
    let n = y.len();
    if n == 0 || y_pred.len() != n {
        return None;
    }
    let var = |it: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = it.collect();
        let m = v.iter().sum::<f64>() / n as f64;
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64
    };
    let vy = var(&mut y.iter().map(|&x| f64::from(x)));
    if vy == 0.0 {
        return None;
    }
    let vr = var(&mut y
        .iter()
        .zip(y_pred)
        .map(|(&a, &b)| f64::from(a) - f64::from(b)));
    Some(1.0 - vr / vy)
}

/// The `[policy]` settings in which `checkpoint` and `run` differ, as
/// "kind: gru in the checkpoint, mlp here; mlp_hidden: 64 in the checkpoint, 16 here".
fn policy_differences(checkpoint: &PolicyConfig, run: &PolicyConfig) -> String {
    let table = |p: &PolicyConfig| match toml::Table::try_from(p) {
        Ok(t) => t,
        Err(_) => toml::Table::new(),
    };
    let (a, b) = (table(checkpoint), table(run));
    let diffs: Vec<String> = a
        .iter()
        .filter(|(k, v)| b.get(*k) != Some(v))
        .map(|(k, v)| {
            let here = b
                .get(k)
                .map_or_else(|| "unset".to_string(), |x| x.to_string());
            format!("{k}: {v} in the checkpoint, {here} here")
        })
        .collect();
    if diffs.is_empty() {
        "the settings differ beyond their printed precision".into()
    } else {
        diffs.join("; ")
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn policy_differences_name_the_fields() {
        let gru = super::PolicyConfig::default();
        let mlp = super::PolicyConfig {
            kind: crate::policy::PolicyKind::Mlp,
            mlp_hidden: 16,
            ..gru.clone()
        };
        let d = super::policy_differences(&gru, &mlp);
        assert_eq!(
            d,
            "kind: \"gru\" in the checkpoint, \"mlp\" here; mlp_hidden: 64 in the \
             checkpoint, 16 here"
        );
        assert!(!d.contains("PolicyConfig"));
    }

    use super::*;
    use crate::env::cartpole::CartPole;
    use crate::policy::{PolicyConfig, PolicyKind};

    /// Replaying a rollout as whole sequences from the kept initial state, with the
    /// recorded episode starts, reproduces the log-probabilities and values computed while
    /// acting (so the first PPO ratio is 1), across episode boundaries inside the rollout.
    #[test]
    fn recurrent_replay_matches_the_rollout() {
        let cfg = PpoConfig {
            num_envs: 3,
            num_steps: 40,
            num_minibatches: 3,
            total_timesteps: 1000,
            policy: PolicyConfig {
                kind: PolicyKind::Gru,
                embed_dim: 8,
                gru_hidden: 8,
                ..PolicyConfig::default()
            },
            ..PpoConfig::default()
        };
        let envs: Vec<Box<dyn Env>> = (0..3)
            .map(|_| Box::new(CartPole::new(15)) as Box<dyn Env>)
            .collect();
        let mut t = Trainer::new(cfg, envs).unwrap();
        // A first rollout so the second starts from a non-zero recurrent state.
        t.rollout().unwrap();
        let buf = t.rollout().unwrap();
        assert!(
            buf.truncated.iter().any(|&x| x),
            "episodes should end inside the rollout"
        );
        let h0 = buf.initial_hidden.clone().unwrap();
        assert!(
            h0.abs()
                .unwrap()
                .sum_all()
                .unwrap()
                .to_scalar::<f32>()
                .unwrap()
                > 0.0
        );
        let cpu = Device::Cpu;
        let obs = Tensor::from_slice(&buf.obs, (40, 3, 4), &cpu).unwrap();
        let starts = Tensor::from_slice(&buf.starts, (40, 3), &cpu).unwrap();
        let out = t.policy.forward_seq(&obs, &starts, Some(&h0)).unwrap();
        let cont = Tensor::from_slice(&buf.cont, (120, 1), &cpu).unwrap();
        let lp = out
            .dist
            .log_prob(&cont, None)
            .unwrap()
            .to_vec1::<f32>()
            .unwrap();
        let v = out.value.to_vec1::<f32>().unwrap();
        for i in 0..120 {
            assert!(
                (lp[i] - buf.log_probs[i]).abs() < 1e-4,
                "{i}: {} {}",
                lp[i],
                buf.log_probs[i]
            );
            assert!((v[i] - buf.values[i]).abs() < 1e-4, "{i}");
        }
        // Without the kept initial state the replay would differ.
        let out0 = t.policy.forward_seq(&obs, &starts, None).unwrap();
        let v0 = out0.value.to_vec1::<f32>().unwrap();
        assert!((0..120).any(|i| (v0[i] - buf.values[i]).abs() > 1e-4));
    }

    #[test]
    fn advantage_normalisation_by_hand() {
        let mut a = [1.0f32, 2.0, 3.0];
        normalize_advantages(&mut a);
        // mean 2, unbiased std 1
        assert!((a[0] + 1.0).abs() < 1e-6 && a[1].abs() < 1e-6 && (a[2] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn explained_variance_by_hand() {
        assert_eq!(
            explained_variance(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]),
            Some(1.0)
        );
        // residual (1, -1, ...) : var(y) = 2/3 for (0,1,2)? y = (0, 1, 2), pred = (1, 1, 1)
        // residual (-1, 0, 1): var 2/3 -> ev = 0
        let ev = explained_variance(&[1.0, 1.0, 1.0], &[0.0, 1.0, 2.0]).unwrap();
        assert!(ev.abs() < 1e-12);
        assert_eq!(explained_variance(&[0.0, 1.0], &[1.0, 1.0]), None);
    }
}
